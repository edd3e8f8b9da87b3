"""Scanner formats (LAS/LAZ, E57, PCD, PTS): files written by the formats'
own libraries (laspy, pye57) or by hand, read, written and read back."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.errors import InputError
from splatedit.io import read, write


def _terrain(n=3000, seed=1):
    """UTM-like millimetre coordinates of a rolling 100 m tile."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0, 100, size=(n, 2))
    z = 300 + 2 * np.sin(xy[:, 0] / 9) * np.cos(xy[:, 1] / 13)
    return np.column_stack([xy[:, 0] + 512_345.0, xy[:, 1] + 5_123_456.0, z])


def _laspy_file(path, *, rgb=True, n=3000):
    import laspy
    world = _terrain(n)
    header = laspy.LasHeader(point_format=3 if rgb else 1, version="1.2")
    header.scales = np.array([0.001, 0.001, 0.001])
    header.offsets = np.array([512_000.0, 5_123_000.0, 0.0])
    las = laspy.LasData(header)
    las.x, las.y, las.z = world[:, 0], world[:, 1], world[:, 2]
    rng = np.random.default_rng(2)
    las.intensity = rng.integers(0, 65535, n).astype(np.uint16)
    las.classification = rng.integers(1, 7, n).astype(np.uint8)
    if rgb:
        c = rng.integers(0, 256, size=(n, 3)).astype(np.uint16) * 257
        las.red, las.green, las.blue = c[:, 0], c[:, 1], c[:, 2]
    las.write(str(path))
    return laspy.read(str(path))


@pytest.mark.parametrize("ext", [".las", ".laz"])
def test_las_round_trip_keeps_the_integer_coordinates_and_attributes(tmp_path, ext):
    import laspy
    src = tmp_path / f"in{ext}"
    orig = _laspy_file(src)
    cloud = read(src)
    # rebased: local coordinates small enough for float32 at sub-mm steps
    assert np.abs(cloud.positions).max() < 100 and np.abs(cloud.origin).max() > 5e6
    out = tmp_path / f"out{ext}"
    write(out, cloud)
    back = laspy.read(str(out))
    for d in "XYZ":
        assert np.array_equal(np.asarray(back[d]), np.asarray(orig[d])), d
    assert np.allclose(back.header.scales, orig.header.scales)
    assert np.allclose(back.header.offsets, orig.header.offsets)
    assert np.array_equal(back.intensity, orig.intensity)
    assert np.array_equal(back.classification, orig.classification)
    assert np.array_equal(np.asarray(back.red) >> 8, np.asarray(orig.red) >> 8)


def test_las_without_rgb_gets_grey_from_intensity_and_is_written_without_rgb(tmp_path):
    import laspy
    src = tmp_path / "g.las"
    orig = _laspy_file(src, rgb=False)
    cloud = read(src)
    assert cloud.colors is not None
    assert np.array_equal(cloud.colors[:, 0], cloud.colors[:, 1])
    order = np.argsort(orig.intensity)
    assert np.all(np.diff(cloud.colors[order, 0].astype(int)) >= 0)   # monotone in intensity
    write(tmp_path / "g2.las", cloud)
    assert "red" not in set(laspy.read(str(tmp_path / "g2.las")).point_format.dimension_names)


def test_ply_cloud_to_las_and_back_is_exact_to_the_millimetre(tmp_path):
    src = tmp_path / "in.las"
    _laspy_file(src)
    c = read(src)
    write(tmp_path / "mid.ply", c)
    ply = read(tmp_path / "mid.ply")
    # the PLY stores world coordinates; reading re-derives an origin of its own
    assert np.allclose(ply.world_positions(), c.world_positions(), rtol=0, atol=1e-9)
    write(tmp_path / "out.las", ply)
    back = read(tmp_path / "out.las")
    assert np.array_equal(np.rint(back.world_positions() * 1000), np.rint(c.world_positions() * 1000))


def test_garbage_las_is_one_line_error_naming_the_file(tmp_path):
    bad = tmp_path / "bad.las"
    bad.write_bytes(b"LASF" + b"\0" * 50)
    with pytest.raises(InputError) as info:
        read(bad)
    assert str(bad) in str(info.value) and "\n" not in str(info.value)


def _pye57_file(path, scans):
    import pye57
    e = pye57.E57(str(path), mode="w")
    for xyz, rgb, inten, translation in scans:
        data = {"cartesianX": xyz[:, 0], "cartesianY": xyz[:, 1], "cartesianZ": xyz[:, 2],
                "colorRed": rgb[:, 0], "colorGreen": rgb[:, 1], "colorBlue": rgb[:, 2],
                "intensity": inten}
        e.write_scan_raw(data, translation=np.asarray(translation, dtype=np.float64),
                         rotation=np.array([1.0, 0, 0, 0]))
    e.close()


def test_e57_scans_merged_with_poses_or_picked_by_index(tmp_path):
    rng = np.random.default_rng(3)
    scans = []
    for k in range(2):
        xyz = rng.normal(size=(800, 3))
        xyz /= np.linalg.norm(xyz, axis=1, keepdims=True)
        rgb = np.full((800, 3), 40 + 100 * k, dtype=np.uint8)
        scans.append((xyz, rgb, rng.uniform(0, 1, 800), (10.0 * k, 0.0, 0.0)))
    path = tmp_path / "two.e57"
    _pye57_file(path, scans)
    merged = read(path)
    assert merged.n == 1600
    second = read(f"{path}#1")
    assert second.n == 800
    # the pose's translation is applied: scan 1 is centred at x = 10
    assert abs(second.world_positions()[:, 0].mean() - 10.0) < 0.2
    assert np.all(second.colors[:, 0] == 140) and second.intensity is not None
    with pytest.raises(InputError) as info:
        read(f"{path}#5")
    assert "out of range 0..1" in str(info.value)
    write(tmp_path / "out.e57", second)
    again = read(tmp_path / "out.e57")
    assert np.allclose(again.world_positions(), second.world_positions(), atol=1e-9)
    assert np.array_equal(again.colors, second.colors)
    assert np.array_equal(again.intensity, second.intensity)


def test_e57_round_trip_of_georeferenced_scan_keeps_millimetres(tmp_path):
    """pye57 writes single-precision points: the writer must store local coordinates and put the
    origin in the pose, else y ~ 5,123,000 is rounded to 0.5 m steps."""
    from splatedit.tolerances import E57_ROUND_TRIP_ATOL
    _laspy_file(tmp_path / "t.las")
    cloud = read(tmp_path / "t.las")
    write(tmp_path / "t.e57", cloud)
    again = read(tmp_path / "t.e57")
    err = np.abs(again.world_positions() - cloud.world_positions()).max()
    assert err < E57_ROUND_TRIP_ATOL, f"E57 round trip moved points by up to {err:.3g} m"


def _pcd_text(rows, binary=False, fields="x y z rgb"):
    n = len(rows)
    head = (f"# .PCD v0.7\nVERSION 0.7\nFIELDS {fields}\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\n"
            f"WIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\n")
    if binary:
        arr = np.array([tuple(r) for r in rows], dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"),
                                                       ("rgb", "<u4")])
        return (head + "DATA binary\n").encode() + arr.tobytes()
    return (head + "DATA ascii\n" + "".join(" ".join(str(v) for v in r) + "\n" for r in rows)).encode()


@pytest.mark.parametrize("binary", [False, True])
def test_pcd_as_pcl_writes_it_reads_positions_and_packed_rgb(tmp_path, binary):
    rng = np.random.default_rng(4)
    p = rng.normal(size=(500, 3)).astype(np.float32)
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    rgb = (200 << 16) | (100 << 8) | 50
    path = tmp_path / "a.pcd"
    path.write_bytes(_pcd_text([(*map(float, r), rgb) for r in p], binary=binary))
    c = read(path)
    assert np.allclose(c.positions, p.astype(np.float64), atol=1e-6)
    assert tuple(c.colors[0]) == (200, 100, 50, 255)
    write(tmp_path / "b.pcd", c)
    d = read(tmp_path / "b.pcd")
    assert np.array_equal(d.positions, c.positions) and np.array_equal(d.colors, c.colors)


def test_pcd_binary_compressed_and_truncated_are_clear_errors(tmp_path):
    path = tmp_path / "c.pcd"
    path.write_bytes(_pcd_text([(0, 0, 0, 0)] * 4).replace(b"DATA ascii", b"DATA binary_compressed"))
    with pytest.raises(InputError, match="binary_compressed"):
        read(path)
    path.write_bytes(_pcd_text([(0.0, 0.0, 0.0, 0)] * 20, binary=True)[:-30])
    with pytest.raises(InputError, match="row 18"):
        read(path)


def test_pts_with_intensity_and_colour_and_bad_row(tmp_path):
    rng = np.random.default_rng(5)
    p = rng.normal(size=(400, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    lines = [f"{len(p)}"] + [f"{x:.17g} {y:.17g} {z:.17g} {-2048 + i} 10 20 30"
                             for i, (x, y, z) in enumerate(p)]
    path = tmp_path / "a.pts"
    path.write_text("\n".join(lines) + "\n")
    c = read(path)
    assert np.array_equal(c.positions, p) and c.intensity[5] == 5
    assert tuple(c.colors[0]) == (10, 20, 30, 255)
    write(tmp_path / "b.pts", c)
    d = read(tmp_path / "b.pts")
    assert np.array_equal(d.positions, c.positions) and np.array_equal(d.intensity, c.intensity)
    lines[7] = "1 2 3 4 5"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(InputError) as info:
        read(path)
    assert "line 8" in str(info.value) and "row 6" in str(info.value)


def test_pcd_invalid_nan_points_are_dropped_with_a_warning(tmp_path):
    from splatedit.errors import InputWarning
    rng = np.random.default_rng(6)
    p = rng.normal(size=(300, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    rows = [(*map(float, r), 0) for r in p] + [(float("nan"),) * 3 + (0,)] * 7
    path = tmp_path / "org.pcd"
    path.write_bytes(_pcd_text(rows, binary=True))
    with pytest.warns(InputWarning, match="7 of 307 points"):
        c = read(path)
    assert c.n == 300


def test_las14_format_and_wide_classes_are_kept(tmp_path):
    import laspy
    world = _terrain(500)
    header = laspy.LasHeader(point_format=7, version="1.4")
    header.scales = np.array([0.001, 0.001, 0.001])
    header.offsets = np.array([512_000.0, 5_123_000.0, 0.0])
    las = laspy.LasData(header)
    las.x, las.y, las.z = world[:, 0], world[:, 1], world[:, 2]
    las.classification = (np.arange(500) % 200).astype(np.uint8)   # 8-bit classes (1.4 only)
    las.red = las.green = las.blue = np.full(500, 65535, dtype=np.uint16)
    las.write(str(tmp_path / "a.las"))
    write(tmp_path / "b.las", read(tmp_path / "a.las"))
    back = laspy.read(str(tmp_path / "b.las"))
    assert back.point_format.id == 7
    assert np.array_equal(back.classification, las.classification)
    assert np.array_equal(np.asarray(back.X), np.asarray(laspy.read(str(tmp_path / "a.las")).X))


def test_las_other_dimensions_and_extra_bytes_survive_read_deform_subset_write(tmp_path):
    import laspy
    world = _terrain(800)
    header = laspy.LasHeader(point_format=1, version="1.2")
    header.add_extra_dims([laspy.ExtraBytesParams("amplitude", np.float32)])
    header.scales = np.array([0.001, 0.001, 0.001])
    header.offsets = np.array([512_000.0, 5_123_000.0, 0.0])
    las = laspy.LasData(header)
    las.x, las.y, las.z = world[:, 0], world[:, 1], world[:, 2]
    las.gps_time = np.linspace(1e5, 2e5, 800)
    las.return_number = (np.arange(800) % 3 + 1).astype(np.uint8)
    las.number_of_returns = np.full(800, 3, dtype=np.uint8)
    las.amplitude = np.linspace(0, 1, 800).astype(np.float32)
    las.write(str(tmp_path / "a.las"))
    cloud = read(tmp_path / "a.las")
    keep = np.arange(0, 800, 2)
    part = cloud.subset(keep)
    write(tmp_path / "b.las", part.replace(positions=part.positions + [0, 0, 0.5]))
    back = laspy.read(str(tmp_path / "b.las"))
    assert back.point_format.id == 1
    for nm in ("gps_time", "return_number", "number_of_returns", "amplitude"):
        assert np.array_equal(np.asarray(back[nm]), np.asarray(las[nm])[keep]), nm
    assert np.array_equal(np.asarray(back.Z), np.asarray(las.Z)[keep] + 500)


def test_all_zero_intensity_gives_the_default_material_not_black(tmp_path):
    import laspy
    world = _terrain(400)
    las = laspy.LasData(laspy.LasHeader(point_format=1, version="1.2"))
    las.header.scales = np.array([0.001, 0.001, 0.001])
    las.header.offsets = np.array([512_000.0, 5_123_000.0, 0.0])
    las.x, las.y, las.z = world[:, 0], world[:, 1], world[:, 2]
    las.write(str(tmp_path / "z.las"))
    assert read(tmp_path / "z.las").colors is None
