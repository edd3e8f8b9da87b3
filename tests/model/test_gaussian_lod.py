"""The Gaussian level of detail's ranking (splatedit.model.gaussian_lod): the
bundled 3DGS bunny ranked by opacity x projected area, levels as prefixes,
basis rows and masks mapped to ranking positions, coverage compensation."""

import numpy as np
import pytest

from splatedit.data import gaussian_scene_path
from splatedit.errors import ParameterError
from splatedit.io import read_gaussians
from splatedit.model.gaussian_lod import build_gaussian_lod, importance, subset
from splatedit.tolerances import GS_LOD_MAX_FRACTION, GS_LOD_MIN_COUNT


@pytest.fixture(scope="module")
def scene():
    return read_gaussians(str(gaussian_scene_path()))


def test_ranking_keeps_the_most_important_in_decreasing_order(scene):
    lod = build_gaussian_lod(scene)
    n = len(scene)
    assert lod.n == n and lod.m == min(n, max(GS_LOD_MIN_COUNT, int(GS_LOD_MAX_FRACTION * n)))
    imp = importance(scene)
    kept = imp[lod.order]
    assert (np.diff(kept) <= 0).all()                                   # most important first
    assert kept[-1] >= np.delete(imp, lod.order).max()                  # nothing better left out
    assert np.array_equal(lod.rank[lod.order], np.arange(lod.m))
    assert (lod.rank >= 0).sum() == lod.m
    # the importance is opacity x the two largest standard deviations' product
    s = np.sort(scene.scales(), axis=1)
    assert np.allclose(imp, scene.opacities() * s[:, 2] * s[:, 1], rtol=1e-6)


def test_level_arrays_masks_and_basis_rows_are_the_scenes_rows(scene):
    lod = build_gaussian_lod(scene)
    lc = lod.cloud(scene)
    assert len(lc) == lod.m
    assert np.array_equal(lc.positions, scene.positions[lod.order])
    assert np.array_equal(lc.sh, scene.sh[lod.order])
    rng = np.random.default_rng(0)
    mask = rng.random(len(scene)) < 0.3
    (got, none) = lod.masks(mask, None)
    assert none is None and np.array_equal(got, mask[lod.order])
    idx = np.flatnonzero(mask)
    B = rng.normal(size=(len(idx), 4))
    r, rb = lod.rows(idx, B)
    # every row kept belongs to a level Gaussian, at its ranking position, unchanged
    assert len(r) == np.count_nonzero(lod.rank[idx] >= 0)
    assert np.array_equal(lod.order[r], idx[lod.rank[idx] >= 0])
    assert np.array_equal(rb, B[lod.rank[idx] >= 0])
    with pytest.raises(ParameterError):
        lod.cloud(subset(scene, np.arange(10)))


def test_compensation_keeps_opacity_weighted_area(scene):
    lod = build_gaussian_lod(scene)
    imp = importance(scene)
    f = [lod.compensation(c) for c in (200, 1000, lod.m)]
    assert f[0] > f[1] > f[2] > 1.0
    c = 1000
    # sigma x f on both large axes: the kept importance grows by f^2 to the total
    assert imp[lod.order[:c]].sum() * lod.compensation(c) ** 2 == pytest.approx(imp.sum(), rel=1e-9)
    whole = build_gaussian_lod(subset(scene, np.arange(GS_LOD_MIN_COUNT)))
    assert whole.m == whole.n and whole.compensation(whole.n) == 1.0


def test_compensation_is_capped_so_fewer_gaussians_stay_cheaper():
    """A Gaussian's cost grows with its screen area (factor squared): the
    compensation stops at GS_LOD_MAX_COMPENSATION (uncapped, 2,000 of a 1M
    tiled-bunny scene were drawn at sigma x22: 240 ms a frame at half
    resolution; capped at 3: 75 ms)."""
    from splatedit.bench.gaussians import bench_scene
    from splatedit.tolerances import GS_LOD_MAX_COMPENSATION
    scene = bench_scene(40_000)
    lod = build_gaussian_lod(scene)
    factors = [lod.compensation(c) for c in (lod.m, 2_000, 200, 1)]
    assert all(1.0 <= f <= GS_LOD_MAX_COMPENSATION for f in factors)
    assert factors == sorted(factors)
    assert factors[-1] == GS_LOD_MAX_COMPENSATION
