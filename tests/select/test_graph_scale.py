"""The tiled neighbour graph build: the same edges as one global k-d tree
query across tile boundaries, cancellable per tile, the global tree lazy."""

import functools

import numpy as np
import pytest
from scipy import sparse
from scipy.spatial import cKDTree

import splatedit.select.graph as graph_mod
from splatedit.data import default_model_path
from splatedit.io import read
from splatedit.model.tiles import tiled_knn
from splatedit.select.graph import NeighbourGraph
from splatedit.tolerances import GRAPH_EDGE_MAX_REL, GRAPH_NEIGHBOURS


def global_tree_graph(pts: np.ndarray, k: int = GRAPH_NEIGHBOURS):
    """The graph as built before the tiles: one cKDTree query over all
    splats, (n, k) float64 distances, a COO matrix plus its transpose.
    Returns (adjacency CSR, spacing)."""
    n = len(pts)
    d, j = cKDTree(pts).query(pts, k=k + 1)
    d, j = d[:, 1:], j[:, 1:]
    first = np.where(d > 0, d, np.inf).min(axis=1)
    spacing = float(np.median(first[np.isfinite(first)]))
    scale = np.median(d, axis=1)
    i = np.repeat(np.arange(n), k)
    j = j.ravel()
    keep = d.ravel() <= GRAPH_EDGE_MAX_REL * np.minimum(scale[i], scale[j])
    a = sparse.coo_matrix((np.ones(keep.sum(), np.int8), (i[keep], j[keep])), shape=(n, n)).tocsr()
    return (a + a.T).tocsr(), spacing


@pytest.fixture
def small_tiles(monkeypatch):
    """Tiles of 2,000 points (cells of 16): a 37k-point scan is cut into ~20
    tiles and many answers near cell walls go through the retry levels."""
    monkeypatch.setattr(graph_mod, "tiled_knn", functools.partial(tiled_knn, tile_points=2000, cell_points=16))


def _same_graph(pts):
    g = NeighbourGraph.build(pts)
    ref, spacing = global_tree_graph(pts)
    assert g.indices.dtype == np.int32 and g.indptr.dtype == np.int64
    assert g.spacing == spacing
    diff = g.matrix().astype(np.int32) - (ref > 0).astype(np.int32)
    assert diff.nnz == 0 or not diff.data.any(), f"{np.count_nonzero(diff.data)} edges differ"
    assert g.indptr[-1] == (ref > 0).nnz
    return g


def test_tiled_build_has_the_global_trees_edges_on_the_bunny_across_tile_boundaries(small_tiles):
    pts = read(default_model_path()).positions
    g = _same_graph(pts)
    assert g.indptr[-1] > 10 * len(pts)           # not a trivial graph: > 10 edge ends per splat


def test_tiled_build_has_the_global_trees_edges_on_the_shared_scans(small_tiles, shared_data):
    for name in ("kitten.xyz", "hippo1.ply", "poste_france.xyz", "bunny00.off"):
        _same_graph(read(shared_data / name).positions)


def test_build_stops_when_progress_raises_between_tiles(small_tiles):
    pts = read(default_model_path()).positions
    calls = []

    class Stop(Exception):
        pass

    def progress(stage, fraction):
        calls.append((stage, fraction))
        if len(calls) == 2:
            raise Stop()

    with pytest.raises(Stop):
        NeighbourGraph.build(pts, progress=progress)
    assert len(calls) == 2 and calls[0][1] < 1.0      # stopped during the tiles


def test_the_global_tree_is_built_on_first_use_and_reused():
    pts = read(default_model_path()).positions
    g = NeighbourGraph.build(pts)
    assert "tree" not in g.__dict__                 # the build itself needs no global tree
    assert g.warm().tree is g.tree and g.tree.n == len(pts)
    given = cKDTree(pts)
    assert NeighbourGraph.build(pts, tree=given).tree is given


def test_the_float64_fallback_alone_gives_the_same_edges(small_tiles, monkeypatch):
    """Every comparison sent to the float64 path (a margin of 10x): the edges
    do not depend on which comparisons float32 settles."""
    monkeypatch.setattr(graph_mod, "GRAPH_EXACT_MARGIN_REL", 10.0)
    _same_graph(read(default_model_path()).positions)
