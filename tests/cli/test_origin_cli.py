"""A georeferenced scan keeps its local origin through ``deform``: camera
flags and edit scripts (local coordinates) written against the original
file line up on the deformed one."""

from __future__ import annotations

import json

import laspy
import numpy as np
import pytest
from PIL import Image

from splatedit.cli import main
from splatedit.io import read


def _terrain_las(path, offsets, n=6000):
    """A 100 m x 100 m UTM terrain tile (mm grid) written by laspy with ``offsets``."""
    rng = np.random.default_rng(5)
    xy = rng.uniform(0, 100, size=(n, 2))
    z = 300 + 2 * np.sin(xy[:, 0] / 9) * np.cos(xy[:, 1] / 13)
    header = laspy.LasHeader(point_format=1, version="1.2")
    header.scales = np.array([0.001, 0.001, 0.001])
    header.offsets = np.asarray(offsets, dtype=np.float64)
    las = laspy.LasData(header)
    las.x, las.y, las.z = xy[:, 0] + 512_345.0, xy[:, 1] + 5_123_456.0, z
    las.intensity = rng.integers(0, 65535, n).astype(np.uint16)
    las.write(str(path))
    return laspy.read(str(path))


def _lift_script(path, origin, corner=(512_355.0, 5_123_466.0)):
    """An edit lifting a hill at a corner of the tile (world x, y) by 20 m,
    written in the file's local coordinates."""
    c = (np.array([*corner, 300.0]) - origin).tolist()
    path.write_text(json.dumps({"version": 1, "edits": [{
        "support": {"sphere": {"center": c, "radius": 25.0}},
        "handle": {"sphere": {"center": c, "radius": 5.0}},
        "transform": {"translate": [0.0, 0.0, 20.0]}}]}))


# the tile's corner offset (the file carries its origin) and a far round offset
# (no origin of its own within reach: the grid origin of the extent)
@pytest.mark.parametrize("offsets", [(512_300.0, 5_123_400.0, 250.0), (500_000.0, 5_000_000.0, 0.0)])
def test_deform_keeps_the_origin_camera_flags_frame_the_same_view(tmp_path, offsets):
    src, out = tmp_path / "tile.las", tmp_path / "lifted.las"
    orig = _terrain_las(src, offsets)
    before = read(src)
    _lift_script(tmp_path / "lift.json", before.origin)
    assert main(["-q", "deform", str(src), "--edit", str(tmp_path / "lift.json"), "-o", str(out)]) == 0
    after = read(out)
    assert np.array_equal(after.origin, before.origin)
    # the edit moved the bounding box (its top rose by ~20 m) ...
    assert after.bounds()[1][2] > before.bounds()[1][2] + 15
    # ... but not the points outside its support: the same integers (scale 0.001)
    back = laspy.read(str(out))
    far = np.hypot(orig.x - 512_355.0, orig.y - 5_123_466.0) > 30.0
    assert far.sum() > 0.8 * len(far)
    for d in "XYZ":
        assert np.array_equal(np.asarray(back[d])[far], np.asarray(orig[d])[far]), d
    # the same flags (local coordinates) look at the same far corner of the tile
    target = np.array([512_425.0, 5_123_536.0, 300.0]) - before.origin
    flags = ["--size", "120x90", "--eye", ",".join(map(str, target + [0.0, -8.0, 25.0])),
             "--target", ",".join(map(str, target)), "--fov", "40"]
    for name in ("tile.las", "lifted.las"):
        assert main(["-q", "render", str(tmp_path / name), "-o", str(tmp_path / f"{name}.png"), *flags]) == 0
    a, b = (np.asarray(Image.open(tmp_path / f"{n}.png"), dtype=np.int16) for n in ("tile.las", "lifted.las"))
    covered = (np.abs(a[..., :3] - 255).max(axis=2) > 8).mean()
    assert covered > 0.5, covered           # the view shows the terrain, not the background
    assert np.abs(a - b).max() <= 1, np.abs(a - b).max()


def test_ply_written_from_a_deformed_scan_carries_its_origin(tmp_path):
    """PLY stores world coordinates plus the origin in a header comment, read back as the origin."""
    src, out = tmp_path / "tile.las", tmp_path / "lifted.ply"
    _terrain_las(src, (500_000.0, 5_000_000.0, 0.0))
    before = read(src)
    _lift_script(tmp_path / "lift.json", before.origin)
    assert main(["-q", "deform", str(src), "--edit", str(tmp_path / "lift.json"), "-o", str(out)]) == 0
    assert b"comment splatedit origin" in out.read_bytes()[:1000]
    after = read(out)
    assert np.array_equal(after.origin, before.origin)
    # a script written against the original file (another corner) does the
    # same there when replayed on the deformed one
    other = (512_435.0, 5_123_546.0)
    _lift_script(tmp_path / "other.json", before.origin, corner=other)
    results = []
    for name in ("tile.las", "lifted.ply"):
        dst = tmp_path / f"other-{name}.ply"
        assert main(["-q", "deform", str(tmp_path / name), "--edit", str(tmp_path / "other.json"),
                     "-o", str(dst)]) == 0
        results.append(read(dst).world_positions())
    region = np.hypot(*(before.world_positions()[:, :2] - other).T) < 10
    assert results[0][region, 2].mean() > before.world_positions()[region, 2].mean() + 10
    assert np.allclose(results[0][region], results[1][region], rtol=0, atol=1e-6)
