"""The framed extent (splatedit.model.extent): far outlier clumps are left
out of a default view's box, a clean model keeps its full box."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.data import default_model_path
from splatedit.io import read
from splatedit.model.extent import framing_extent
from splatedit.tolerances import FRAMING_OUTLIER_MAX_FRACTION, FRAMING_OUTLIER_RATIO


@pytest.fixture(scope="module")
def bunny():
    return read(default_model_path()).positions


def _with_clumps(points, fraction, distance, seed=3):
    """``points`` plus ``fraction`` of their count in 4 tight clumps
    ``distance`` half-diagonals from the box centre (a scan's stray returns)."""
    rng = np.random.default_rng(seed)
    lo, hi = points.min(0), points.max(0)
    c, r = (lo + hi) / 2, np.linalg.norm(hi - lo) / 2
    k = max(4, int(fraction * len(points)))
    dirs = rng.normal(size=(4, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    centres = c + distance * r * dirs
    clumps = centres[np.arange(k) % 4] + rng.normal(scale=0.02 * r, size=(k, 3))
    return np.vstack([points, clumps]), k


def test_poste_scan_frames_its_body_not_the_far_clumps(shared_data):
    """poste_france.xyz: a 262-unit box of which the scan fills ~24 units."""
    pts = read(shared_data / "poste_france.xyz").positions
    ext = framing_extent(pts)
    assert ext.robust
    # the measured 124 far points are 1.4 % of 9,031: about what outlier
    # detection finds there (32 outliers + 104 stray-cluster points)
    assert 50 <= ext.n_far <= FRAMING_OUTLIER_MAX_FRACTION * len(pts)
    assert ext.radius < 0.15 * ext.full_radius
    inside = np.all((pts >= ext.lo) & (pts <= ext.hi), axis=1)
    assert inside.sum() == len(pts) - ext.n_far       # the box is the kept points' exact box
    far = pts[~inside]
    # every point left out is far from the framed box (> 3 of its radii from its centre)
    assert np.linalg.norm(far - ext.center, axis=1).min() > 3 * ext.radius
    assert "points far outside the main body (outliers?)" in ext.note()
    assert "splatedit convert --remove-outliers" in ext.note()


@pytest.mark.parametrize("name", ["kitten.xyz", "hippo1.ply", "bunny00.off"])
def test_clean_shared_models_keep_their_full_box(shared_data, name):
    pts = read(shared_data / name).positions
    ext = framing_extent(pts)
    assert not ext.robust and ext.note() is None
    assert np.array_equal(ext.lo, pts.min(0)) and np.array_equal(ext.hi, pts.max(0))


def test_bundled_bunny_keeps_its_full_box(bunny):
    ext = framing_extent(bunny)
    assert not ext.robust and ext.n_far == 0
    assert np.array_equal(ext.lo, bunny.min(0)) and np.array_equal(ext.hi, bunny.max(0))


@pytest.mark.parametrize("sample", [5_000, 1_000_000])
def test_far_clumps_added_to_the_bunny_leave_its_box_framed(bunny, sample):
    """1 % of points in clumps 10 radii out: the framed box is the bunny's
    own box, exactly (also when the centre and shell come from a subsample),
    and the count is the clumps'."""
    pts, k = _with_clumps(bunny, 0.01, 10.0)
    ext = framing_extent(pts, sample=sample)
    assert ext.robust and ext.n_far == k
    assert np.array_equal(ext.lo, bunny.min(0)) and np.array_equal(ext.hi, bunny.max(0))
    assert np.array_equal(ext.full_lo, pts.min(0))
    assert ext.note().startswith(f"{k:,} points far outside the main body")


def test_points_close_to_the_body_are_framed_with_it(bunny):
    """Clumps just beyond the body (the full box would show it at more than
    FRAMING_OUTLIER_RATIO of the size) are part of the view."""
    pts, _ = _with_clumps(bunny, 0.01, 1.4)      # measured: 94 points outside the shell, box ratio 0.58
    ext = framing_extent(pts)
    lo, hi = pts.min(0), pts.max(0)
    assert not ext.robust and np.array_equal(ext.lo, lo) and np.array_equal(ext.hi, hi)


def test_a_sparse_part_larger_than_a_few_outliers_is_framed(bunny):
    """8 % of the points far out is a sparse part of the model, not outliers."""
    pts, k = _with_clumps(bunny, 0.08, 10.0)
    assert k > FRAMING_OUTLIER_MAX_FRACTION * len(pts)
    ext = framing_extent(pts)
    assert not ext.robust and np.array_equal(ext.lo, pts.min(0))


def test_a_single_point_and_coincident_points_keep_their_box():
    one = framing_extent(np.array([[1.0, 2.0, 3.0]]))
    assert not one.robust and one.radius == 0.0 and np.array_equal(one.center, [1, 2, 3])
    pile = np.vstack([np.zeros((95, 3)), np.eye(3) * 50, -np.eye(3)[:2] * 50])
    ext = framing_extent(pile)          # the 90th-percentile distance is 0: nothing to measure by
    assert not ext.robust and np.array_equal(ext.hi, [50, 50, 50])
