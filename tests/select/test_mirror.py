"""Mirror selection: the splat across the bounding box's middle plane."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from splatedit.select.graph import NeighbourGraph
from splatedit.select.mirror import mirror_indices, plane_centre, reflect


def _jittered_grid(k=60, jitter=0.25, seed=3):
    """k x k samples of the z = 0 square [0, 2] x [0, 1] (off-centre in x: the
    plane is the box's middle, not x = 0), each side sampled independently
    with ``jitter`` spacings of noise."""
    rng = np.random.default_rng(seed)
    xs, ys = np.meshgrid(np.linspace(0, 2, k), np.linspace(0, 1, k))
    p = np.c_[xs.ravel(), ys.ravel(), np.zeros(k * k)]
    step = 2.0 / (k - 1)
    p[:, :2] += rng.uniform(-jitter, jitter, (len(p), 2)) * step
    return p


def test_reflection_is_an_involution_about_the_box_middle():
    p = _jittered_grid()
    c = plane_centre(p, 0)
    assert abs(c - 0.5 * (p[:, 0].min() + p[:, 0].max())) < 1e-15
    assert np.allclose(reflect(reflect(p, 0, c), 0, c), p, rtol=0, atol=1e-15)


def test_every_sample_of_a_jittered_symmetric_grid_finds_its_mirror():
    p = _jittered_grid()
    g = NeighbourGraph.build(p)
    right = np.flatnonzero(p[:, 0] > 1.2)
    got = mirror_indices(p, right, g.tree, g.spacing, 0)
    want = np.flatnonzero(p[:, 0] < 2 * plane_centre(p, 0) - 1.2)
    # the mirrored strip: the left strip's samples (up to the jittered edge), nothing from the middle
    assert np.array_equal(got, want)
    assert p[got, 0].max() < 2 * plane_centre(p, 0) - 1.2 + 2 * g.spacing


def test_a_part_without_counterpart_has_no_mirror():
    p = np.r_[_jittered_grid(), [[5.0, 0.5, 0.0]]]     # an outlier far right widens the box
    g = NeighbourGraph.build(p)
    c = 1.0                                             # the grid's own middle, given explicitly
    assert len(mirror_indices(p, [len(p) - 1], g.tree, g.spacing, 0, c)) == 0
    # about the box middle (x = 2.5) the grid reflects off the model: only the outlier matches
    got = mirror_indices(p, np.arange(len(p) - 1), cKDTree(p), g.spacing, 0)
    assert got.tolist() == [len(p) - 1]
