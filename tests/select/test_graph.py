"""The neighbour graph: rings, grow/shrink, flood fill, subgraphs, cut edges."""

import numpy as np

from splatedit.select.graph import NeighbourGraph, unique_indices


def grid(n: int = 30, h: float = 0.1) -> np.ndarray:
    x, y = np.meshgrid(np.arange(n) * h, np.arange(n) * h)
    return np.column_stack([x.ravel(), y.ravel(), np.zeros(n * n)])


def test_spacing_is_the_grid_step_and_every_edge_is_symmetric():
    g = NeighbourGraph.build(grid())
    assert abs(g.spacing - 0.1) < 1e-12
    a = g.matrix()
    assert (a != a.T).nnz == 0
    assert g.diagonal > 0


def test_grow_by_rings_reaches_the_graph_distance_and_shrink_undoes_it_inside():
    pts = grid()
    g = NeighbourGraph.build(pts)
    centre = 15 * 30 + 15
    seed = np.zeros(len(pts), bool)
    seed[centre] = True
    one = g.grow(seed, 1)
    # ten neighbours on a grid: the 8-neighbourhood plus the two nearest of the next shell
    assert 9 <= one.sum() <= 13
    five = g.grow(seed, 5)
    d = np.abs(pts[five] - pts[centre])[:, :2].max(axis=1)
    assert d.max() <= 0.5 * 2 + 1e-9 and five.sum() > one.sum()
    assert g.shrink(g.grow(five, 2), 2)[five].all()      # closing keeps the set
    assert not g.shrink(five, 1)[g.ring(g.shrink(five, 1)) ].any()


def test_connected_stays_inside_allowed_and_components_count_parts():
    pts = np.vstack([grid(10), grid(10) + [5.0, 0, 0]])     # two separate patches
    g = NeighbourGraph.build(pts)
    part = g.connected([0])
    assert part.sum() == 100 and part[:100].all()
    count, labels = g.components(np.arange(len(pts)))
    assert count == 2 and len(set(labels[:100])) == 1


def test_an_outlier_is_not_connected_to_the_surface():
    pts = np.vstack([grid(20), [[1.0, 1.0, 3.0]]])
    g = NeighbourGraph.build(pts)
    assert g.indptr[-1] - g.indptr[-2] == 0       # its long edges are cut
    assert not g.connected([0])[-1]


def test_subgraph_keeps_edges_inside_the_index_set_renumbered():
    pts = grid()
    g = NeighbourGraph.build(pts)
    idx = np.flatnonzero(pts[:, 0] < 1.0)
    sub = g.subgraph(idx)
    full = g.matrix()[idx][:, idx]
    assert sub.n == len(idx) and (sub.matrix() != full).nnz == 0


def test_unique_indices_drops_repeats():
    v = np.array([5, 3, 5, 7, 3, 3, 0])
    assert sorted(unique_indices(v, np.empty(8, np.int64))) == [0, 3, 5, 7]
