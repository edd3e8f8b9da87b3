"""Up-axis detection for the editor's numpad views: file-format hints, the
ground signal of a scan resting on a flat side, the graphics default."""

from __future__ import annotations

import numpy as np

from splatedit.model.orientation import CYCLE, UpAxis, UpSource, detect_up_axis, next_up


def _read(path):
    from splatedit.io import read
    return read(str(path))


def test_bundled_bunny_is_y_up():
    from splatedit.data import default_model_path
    c = _read(default_model_path())
    up = detect_up_axis(c.normals, c.positions, default_model_path())
    assert (up.axis, up.sign, up.source) == (1, 1, UpSource.DEFAULT)


def test_one_sided_hippo_scan_is_not_taken_for_a_floor(shared_data):
    """hippo1 was scanned from +Z (37% of its normals face +Z) but stands
    upright along +Y (legs to -Y): the scanner side is no ground."""
    c = _read(shared_data / "hippo1.ply")
    up = detect_up_axis(c.normals, c.positions, shared_data / "hippo1.ply")
    assert (up.label, up.source) == ("+Y", UpSource.DEFAULT)


def test_an_object_standing_on_a_floor_slab_is_up_from_the_floor():
    """A sphere (normals every way) standing on a square floor patch in the
    x-y plane at its bottom: +Z, from the floor."""
    rng = np.random.default_rng(2)
    s = rng.normal(size=(1500, 3))
    s /= np.linalg.norm(s, axis=1, keepdims=True)
    floor = np.c_[rng.uniform(-3, 3, 2000), rng.uniform(-3, 3, 2000), np.full(2000, -1.0)]
    p = np.vstack([s, floor])
    n = np.vstack([s, np.tile([0.0, 0.0, 1.0], (2000, 1))])
    up = detect_up_axis(n, p)
    assert (up.label, up.source) == ("+Z", UpSource.GROUND)


def test_shared_object_scans_without_a_ground_keep_y_up(shared_data):
    for name in ("kitten.xyz", "bunny00.off"):
        c = _read(shared_data / name)
        assert detect_up_axis(c.normals, c.positions, shared_data / name).label == "+Y", name


def test_scanner_formats_are_z_up_whatever_the_points():
    from splatedit.io.formats import is_z_up     # the callers (editor, render) ask io's registry
    rng = np.random.default_rng(0)
    p = rng.normal(size=(500, 3))
    n = p / np.linalg.norm(p, axis=1, keepdims=True)
    for suffix in (".las", ".LAZ", ".e57"):
        path = f"/scans/room{suffix}"
        assert is_z_up(path), suffix
        up = detect_up_axis(n, p, path, z_up_format=is_z_up(path))
        assert (up.label, up.source) == ("+Z", UpSource.FILE_FORMAT)
    assert not is_z_up("/scans/room.ply")
    assert detect_up_axis(n, p, "/scans/room.ply", z_up_format=is_z_up("/scans/room.ply")).label == "+Y"


def test_a_floor_facing_down_the_y_axis_gives_minus_y():
    rng = np.random.default_rng(1)
    floor = np.c_[rng.uniform(-5, 5, 3000), np.zeros(3000), rng.uniform(-5, 5, 3000)]
    wall = np.c_[rng.uniform(-5, 5, 1000), rng.uniform(-3, 0, 1000), np.full(1000, 5.0)]
    p = np.vstack([floor, wall])
    n = np.vstack([np.tile([0.0, -1.0, 0.0], (3000, 1)), np.tile([0.0, 0.0, -1.0], (1000, 1))])
    up = detect_up_axis(n, p)
    assert (up.axis, up.sign, up.source) == (1, -1, UpSource.GROUND)


def test_u_cycles_through_all_six_signed_axes():
    up, seen = UpAxis(1, 1), []
    for _ in range(len(CYCLE)):
        up = next_up(up)
        seen.append(up.label)
        assert up.source is UpSource.USER and np.isclose(np.abs(up.vector).sum(), 1.0)
    assert sorted(seen) == sorted(["+X", "+Y", "+Z", "-X", "-Y", "-Z"])


def test_a_ply_header_comment_names_the_up_axis(tmp_path):
    from splatedit.data import default_model_path
    from splatedit.io import read
    from splatedit.io.ply import write_ply
    from splatedit.model.orientation import header_up_hint

    def write(path, cloud, overwrite, comment):
        with open(path, "wb") as fh:
            write_ply(fh, cloud, comment=comment)
    c = read(str(default_model_path()))
    for comment, label in (("up_axis Z", "+Z"), ("scanned Z-up, metres", "+Z"), ("up: -y", "-Y"),
                           ("upaxis=+X", "+X")):
        p = tmp_path / "m.ply"
        write(p, c, True, comment)
        up = detect_up_axis(c.normals, c.positions, p)
        assert (up.label, up.source) == (label, UpSource.FILE_HEADER), comment
    write(p, c, True, "made by splatedit; backup copy")   # "backup" is no hint
    assert header_up_hint(p) is None
    assert detect_up_axis(c.normals, c.positions, p).source is UpSource.DEFAULT


def test_front_direction_is_horizontal_and_faces_the_front_of_y_and_z_up_models():
    """The front view (the editor's first view, render's default): a Y-up
    model is seen from +Z, a Z-up scan from -Y (not from above); for any up
    the direction is a unit vector perpendicular to it."""
    from splatedit.model.orientation import front_direction
    assert np.allclose(front_direction([0, 1, 0]), [0, 0, 1])
    assert np.allclose(front_direction([0, 0, 1]), [0, -1, 0])
    assert np.allclose(front_direction([0, 0, -1]), [0, -1, 0])
    assert np.allclose(front_direction([1, 0, 0]), [0, 0, 1])
    for up in np.random.default_rng(4).normal(size=(50, 3)):
        d = front_direction(up)
        assert abs(np.linalg.norm(d) - 1) < 1e-12 and abs(d @ up) < 1e-12 * np.linalg.norm(up)


def test_front_direction_of_a_tiny_up_vector_is_a_unit_vector():
    from splatedit.model.orientation import front_direction
    assert np.allclose(front_direction([0, 1e-300, 0]), [0, 0, 1])
    assert np.allclose(front_direction([0, 0, 1e300]), [0, -1, 0])


def test_cloud_up_axis_on_a_sample_agrees_with_all_splats(monkeypatch):
    """A Z-up floor scan above UP_AXIS_SAMPLE splats: the floor rule on the
    stride sample gives the same axis as on every splat."""
    from splatedit.model.cloud import SplatCloud
    from splatedit.model import orientation
    rng = np.random.default_rng(7)
    n = 60_000
    floor = np.column_stack([rng.uniform(-5, 5, n), rng.uniform(-5, 5, n), np.zeros(n)])
    m = 20_000
    d = rng.normal(size=(m, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    ball = d + [0.0, 0.0, 2.0]
    pos = np.vstack([floor, ball])
    nrm = np.vstack([np.tile([0.0, 0.0, 1.0], (n, 1)), d])
    t = np.cross(nrm, [0.3, 0.5, 0.8])
    t /= np.linalg.norm(t, axis=1)[:, None]
    cloud = SplatCloud(pos, 0.05 * t, 0.05 * np.cross(nrm, t))
    whole = orientation.detect_up_axis(cloud.normals, cloud.positions)
    monkeypatch.setattr(orientation, "UP_AXIS_SAMPLE", 5_000)
    sampled = orientation.detect_cloud_up_axis(cloud)
    assert (sampled.axis, sampled.sign, sampled.source) == (whole.axis, whole.sign, whole.source)
    assert (whole.axis, whole.sign) == (2, 1)


def _figure(height_axis: int, height=1.8, width=0.5, depth=0.3, n=4000, seed=4):
    """Points on an ellipsoid `height` long along `height_axis` (a standing
    figure with the arms down, as a Z-up tool exports it when axis 2)."""
    rng = np.random.default_rng(seed)
    s = rng.normal(size=(n, 3))
    s /= np.linalg.norm(s, axis=1, keepdims=True)
    radii = np.array([width, depth, depth]) / 2
    radii[height_axis] = height / 2
    if height_axis != 0:
        radii[0] = width / 2
    p = s * radii
    nrm = s / radii
    return p, nrm / np.linalg.norm(nrm, axis=1, keepdims=True)


def test_a_figure_standing_along_z_is_z_up_from_its_shape():
    """man.off (a CGAL sample) opened lying down: a model 3x taller along Z
    than wide and deep, with no word from the file and no floor, is +Z."""
    p, n = _figure(2)
    up = detect_up_axis(n, p)
    assert (up.label, up.source) == ("+Z", UpSource.SHAPE)


def test_models_long_along_z_but_not_standing_keep_y_up():
    """A Y-up car about 2.5x as long (Z) as wide, and a figure standing
    along Y, stay +Y: only a clearly tall Z extent counts."""
    rng = np.random.default_rng(5)
    car = rng.uniform(-1, 1, size=(3000, 3)) * [0.9, 0.75, 2.25]
    nrm = rng.normal(size=(3000, 3))
    up = detect_up_axis(nrm / np.linalg.norm(nrm, axis=1, keepdims=True), car)
    assert up.label == "+Y"
    p, n = _figure(1)
    assert detect_up_axis(n, p).label == "+Y"
