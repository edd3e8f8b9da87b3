"""The thinned level of detail (splatedit.model.lod.thinned_level): kept
splats are splats of the cloud, enlarged so the covered area per unit of
surface stays what it was."""

from __future__ import annotations

import numpy as np

from splatedit.model.lod import thinned_level
from splatedit.model.tangents import splats_from_normals


def _plane(n=200_000, seed=0):
    rng = np.random.default_rng(seed)
    p = np.column_stack([rng.random((n, 2)), np.zeros(n)])
    return splats_from_normals(p, np.tile([0.0, 0.0, 1.0], (n, 1)), rng.uniform(0.002, 0.004, n))


def _area(c):
    return float((np.pi * np.linalg.norm(c.u, axis=1) * np.linalg.norm(c.v, axis=1)).sum())


def test_thinning_keeps_the_covered_area_and_the_splats_themselves():
    """keep 1/10: about 10 % kept (binomial: within 4 sigma), the kept splats'
    total area within 2 % of the cloud's, every kept splat the cloud's splat
    (same centre and frame) scaled by sqrt(10)."""
    c = _plane()
    lvl = thinned_level(c, np.full(c.n, 0.1))
    sigma = np.sqrt(c.n * 0.1 * 0.9)
    assert abs(lvl.n - 0.1 * c.n) < 4 * sigma
    assert abs(_area(lvl.cloud) / _area(c) - 1.0) < 0.02
    np.testing.assert_array_equal(lvl.cloud.positions, c.positions[lvl.rep])
    np.testing.assert_allclose(lvl.cloud.u, c.u[lvl.rep] * np.sqrt(10.0), rtol=1e-12)
    assert lvl.cluster is None


def test_margin_grows_only_the_thinned_splats_and_keep_one_changes_nothing():
    c = _plane(20_000)
    keep = np.where(np.arange(c.n) % 2 == 0, 1.0, 0.25)
    lvl = thinned_level(c, keep, margin=1.2)
    sure = keep[lvl.rep] == 1.0
    assert sure.sum() == c.n // 2                       # every keep-1 splat is there, unchanged
    np.testing.assert_allclose(lvl.scale[sure], 1.0)
    np.testing.assert_allclose(lvl.scale[~sure], np.sqrt((1 + 0.44 * 0.75) / 0.25))
    again = thinned_level(c, keep, margin=1.2)          # seeded: the same level
    np.testing.assert_array_equal(again.rep, lvl.rep)
