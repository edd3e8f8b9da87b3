"""Level-of-detail clustering: budget, coverage (hole-free), basis row gathering."""

import numpy as np

from splatedit.model import SplatCloud
from splatedit.model.lod import LodPyramid, build_level, level_for_budget


def sphere_cloud(n=20000, seed=0):
    rng = np.random.default_rng(seed)
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    a = np.cross(p, [0.3, 0.5, 0.8])
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(p, a)
    r = 2.0 * np.sqrt(4 * np.pi / n)
    return SplatCloud(p, a * r, b * r)


def ellipse_norm(cloud, idx, pts):
    u, v = cloud.u[idx], cloud.v[idx]
    d = pts - cloud.positions[idx]
    g = np.stack([np.stack([(u * u).sum(1), (u * v).sum(1)], 1),
                  np.stack([(u * v).sum(1), (v * v).sum(1)], 1)], 1)
    rhs = np.stack([(d * u).sum(1), (d * v).sum(1)], 1)
    st = np.linalg.solve(g, rhs[..., None])[..., 0]
    return np.linalg.norm(st, axis=1)


def test_budget_respected_and_levels_ordered():
    c = sphere_cloud()
    for b in (5000, 1000, 300):
        lvl = level_for_budget(c, b)
        assert 0 < lvl.n <= b
        assert lvl.n > b / 8  # not absurdly coarse
    pyr = LodPyramid(c, budgets=(8000, 2000, 500))
    counts = [l.n for l in pyr.levels]
    assert counts == sorted(counts, reverse=True)
    assert pyr.level_for(10 ** 9) is None
    assert pyr.level_for(2500).n <= 2500
    assert pyr.level_for(1) is pyr.levels[-1]


def test_every_member_covered_by_its_representative():
    c = sphere_cloud()
    lvl = build_level(c, 0.1)
    assert lvl.cluster.shape == (c.n,)
    # representatives are members of their own cluster
    assert np.array_equal(lvl.cluster[lvl.rep], np.arange(lvl.n))
    e = ellipse_norm(lvl.cloud, lvl.cluster, c.positions)
    assert (e <= 1.0 + 1e-9).all()


def test_hole_free_on_dense_surface_samples():
    c = sphere_cloud(20000)
    lvl = level_for_budget(c, 800)
    q = sphere_cloud(5000, seed=7).positions
    # each surface sample lies (in projection) inside some LOD splat near it
    from scipy.spatial import cKDTree
    tree = cKDTree(lvl.cloud.positions)
    _, nb = tree.query(q, k=8)
    best = np.min(np.stack([ellipse_norm(lvl.cloud, nb[:, j], q) for j in range(8)], 1), 1)
    assert (best <= 1.0).all()


def test_rows_and_masks_follow_representatives():
    c = sphere_cloud(5000)
    lvl = build_level(c, 0.2)
    sup = c.positions[:, 2] > 0.5
    idx = np.flatnonzero(sup)
    B = np.arange(len(idx) * 4, dtype=float).reshape(-1, 4)
    li, LB = lvl.rows(idx, B)
    assert np.array_equal(lvl.rep[li], idx[np.searchsorted(idx, lvl.rep[li])])
    assert np.array_equal(LB, B[np.searchsorted(idx, lvl.rep[li])])
    (ms,) = lvl.masks(sup)
    assert np.array_equal(np.flatnonzero(ms), li)
    d = lvl.deformed(c.positions + 1, c.u, c.v)
    assert np.allclose(d.positions, lvl.cloud.positions + 1)


def test_pyramid_levels_cover_the_full_cloud():
    c = sphere_cloud(20000)
    pyr = LodPyramid(c, budgets=(6000, 1500, 400))
    for lvl in pyr.levels:
        assert lvl.cluster.shape == (c.n,) and lvl.cluster.max() == lvl.n - 1
        # the level's splats are the representatives' splats, scaled
        assert np.allclose(lvl.cloud.positions, c.positions[lvl.rep])
        assert np.allclose(lvl.cloud.u, c.u[lvl.rep] * lvl.scale[:, None])
        e = ellipse_norm(lvl.cloud, lvl.cluster, c.positions)
        assert np.percentile(e, 99) <= 1.0 and e.max() <= 1.3


def test_background_pyramid_shows_a_covering_preview_then_the_real_levels(monkeypatch):
    """background=True on a cloud above the preview sample size: the
    constructor returns at once with a preview level (within the coarsest
    budget, its splats are splats of the cloud, scaled), 99.9% of all splat
    centres lie in one of the 16 nearest preview ellipses, and after wait()
    the levels are those of a foreground build."""
    import splatedit.model.lod as lod
    from scipy.spatial import cKDTree
    monkeypatch.setattr(lod, "LOD_PREVIEW_SAMPLE_SPLATS", 6000)
    c = sphere_cloud(60000)
    budgets = (20000, 6000, 300)              # ~20 sampled members per preview cluster
    pyr = LodPyramid(c, budgets=budgets, background=True)
    pre = pyr.preview
    assert pre is not None and pre.cluster is None and 0 < pre.n <= 300
    assert np.allclose(pre.cloud.positions, c.positions[pre.rep])
    assert np.allclose(pre.cloud.u, c.u[pre.rep] * pre.scale[:, None])
    _, near = cKDTree(pre.cloud.positions).query(c.positions, k=16)
    inside = np.zeros(c.n, bool)
    for j in range(16):
        inside |= ellipse_norm(pre.cloud, near[:, j], c.positions) <= 1.0
    assert inside.mean() >= 0.999
    assert pyr.wait(60)
    ref = LodPyramid(c, budgets=budgets)
    assert [lvl.n for lvl in pyr.levels] == [lvl.n for lvl in ref.levels]
