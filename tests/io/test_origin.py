"""The local origin of far models (splatedit.io._build.local_origin): chosen
from a power-of-two grid of the extent or taken from the file, stable under
edits, exact, and precise enough for float32."""

from __future__ import annotations

import numpy as np

from splatedit.io import read, write
from splatedit.io._build import local_origin, origin_grid
from splatedit.model.cloud import SplatCloud
from splatedit.tolerances import REBASE_GRID_MIN, REBASE_STORED_REACH


def _tile(side=100.0, corner=(512_345.678, 5_123_456.789, 290.0), n=4000, seed=0):
    rng = np.random.default_rng(seed)
    p = rng.uniform(0, 1, size=(n, 3)) * [side, side, side / 10] + corner
    return np.round(p, 3)


def test_grid_origin_keeps_local_coordinates_within_the_extent_and_exact():
    for side in (0.3, 7.0, 100.0, 2500.0):
        p = _tile(side)
        o = local_origin(p)
        lo, hi = p.min(0), p.max(0)
        assert np.abs(p - o).max() <= max(np.max(hi - lo), REBASE_GRID_MIN), side
        assert np.array_equal((p - o) + o, p), side          # rebasing and back is exact
        step = origin_grid(lo, hi)
        assert np.array_equal(o, np.round(o / step) * step) and step >= 1.0


def test_grid_origin_is_stable_under_a_local_edit():
    p = _tile()
    o = local_origin(p)
    moved = p.copy()
    near = np.linalg.norm(p[:, :2] - p[:, :2].min(0), axis=1) < 20
    moved[near, 2] += 15.0                  # lift one corner: the box's z range grows 10x
    assert not np.allclose(moved.max(0), p.max(0))
    assert np.array_equal(local_origin(moved), o)


def test_stored_origin_wins_within_reach_else_the_grid():
    p = _tile()
    lo, hi = p.min(0), p.max(0)
    side = np.max(hi - lo)
    near = lo - 0.9 * REBASE_STORED_REACH * side / 2
    assert np.array_equal(local_origin(p, stored=near), near)
    far = lo - 1.1 * REBASE_STORED_REACH * side
    assert np.array_equal(local_origin(p, stored=far), local_origin(p))
    # a model near 0 is never rebased, whatever the file says
    assert not local_origin(p - lo, stored=near).any()


def test_ply_round_trip_keeps_an_origin_off_the_grid(tmp_path):
    """A cloud whose origin was chosen elsewhere (an editor session, another
    format) keeps it through PLY, binary and ascii."""
    world = _tile()
    origin = np.array([512_360.5, 5_123_470.25, 300.0])        # not a grid point
    assert not np.array_equal(origin, local_origin(world))
    u = np.tile([0.05, 0.0, 0.0], (len(world), 1))
    v = np.tile([0.0, 0.05, 0.0], (len(world), 1))
    cloud = SplatCloud(world - origin, u, v, origin=origin)
    for binary in (True, False):
        path = tmp_path / f"o{binary}.ply"
        write(path, cloud, binary=binary)
        back = read(path)
        assert np.array_equal(back.origin, origin), binary
        assert np.array_equal(back.world_positions(), cloud.world_positions()), binary


def test_las_laz_and_e57_carry_the_origin_of_a_cloud_not_read_from_them(tmp_path):
    """LAS/LAZ store it as the header offset, E57 as the scan's pose."""
    world = _tile()
    origin = np.array([512_360.5, 5_123_470.25, 300.0])
    u = np.tile([0.05, 0.0, 0.0], (len(world), 1))
    v = np.tile([0.0, 0.05, 0.0], (len(world), 1))
    cloud = SplatCloud(world - origin, u, v, origin=origin)
    for ext in (".las", ".laz", ".e57"):
        path = tmp_path / f"o{ext}"
        write(path, cloud)
        assert np.array_equal(read(path).origin, origin), ext
