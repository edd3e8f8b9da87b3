"""Tiled exact k-NN (splatedit.model.tiles) and the bounded memory of estimate_splats."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest
from scipy.spatial import cKDTree

from splatedit.model.pca import morton_codes
from splatedit.model.tiles import TiledKnnStats, tiled_knn
from splatedit.tolerances import ESTIMATE_PEAK_EXTRA_BYTES_PER_POINT
from tests.model.scan_helpers import inject_outliers


def _sorted(points):
    codes, lo, scale = morton_codes(points)
    o = np.argsort(codes, kind="stable")
    return points[o], codes[o], lo, scale


def _global(points, k):
    d, i = cKDTree(points).query(points, k=k)
    return d.astype(np.float32), i


def _check_same_as_global(sp, dist, idx, k):
    d, i = _global(sp, k)
    assert np.array_equal(dist, d)
    # neighbour sets agree wherever the k-th distance is not tied with the next
    same = (np.sort(idx, axis=1) == np.sort(i, axis=1)).all(axis=1)
    d_next, _ = cKDTree(sp).query(sp, k=k + 1)
    untied = d_next[:, k] > d_next[:, k - 1]
    assert same[untied].all(), f"{(~same[untied]).sum()} rows differ"


def test_tiled_neighbours_equal_the_global_tree_across_tile_borders_and_for_outliers():
    """A sphere (every tile border cuts the surface) with 1% uniform noise and
    far strays (whose neighbours lie outside their tile's halo: the coarser
    retry, then the tree over all points): tiled k-NN == one global
    cKDTree, distances bit for bit."""
    rng = np.random.default_rng(4)
    p = rng.normal(size=(20000, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    sp, codes, lo, scale = _sorted(inject_outliers(p, seed=1, fraction=0.01, far=5))
    stats = TiledKnnStats()
    dist, idx = tiled_knn(sp, codes, lo, scale, 16, tile_points=1000, cell_points=16, stats=stats)
    # borders, a coarser-level retry and the global tree for the strays all exercised
    assert stats.tiles >= 20 and stats.retried > stats.global_queries >= 5
    _check_same_as_global(sp, dist, idx, 16)


def test_tiled_neighbours_of_a_real_scan_equal_the_global_tree(shared_data):
    from splatedit.io import read
    sp, codes, lo, scale = _sorted(read(shared_data / "poste_france.xyz").positions)
    dist, idx = tiled_knn(sp, codes, lo, scale, 16, tile_points=500, cell_points=8)
    _check_same_as_global(sp, dist, idx, 16)


def test_tiled_knn_with_fewer_points_than_k_and_duplicates():
    sp, codes, lo, scale = _sorted(np.vstack([np.zeros((6, 3)), np.eye(3)]))
    dist, idx = tiled_knn(sp, codes, lo, scale, 16)
    assert idx.shape == (9, 9)
    _check_same_as_global(sp, dist, idx, 9)


@pytest.mark.parametrize("threads", [1, 3])
def test_tile_threads_give_the_same_table(threads):
    rng = np.random.default_rng(2)
    sp, codes, lo, scale = _sorted(rng.random((5000, 3)))
    ref = tiled_knn(sp, codes, lo, scale, 8, tile_points=300, threads=1)
    got = tiled_knn(sp, codes, lo, scale, 8, tile_points=300, threads=threads)
    assert np.array_equal(ref[0], got[0]) and np.array_equal(ref[1], got[1])


def test_estimate_splats_peak_memory_per_point_is_bounded():
    """1M raw points (no normals) sampled on the bunny: the traced peak of
    numpy memory during estimate_splats, above the input, stays below
    ESTIMATE_PEAK_EXTRA_BYTES_PER_POINT (the output's u and v are 48 of it)."""
    from splatedit.bench.estimate import bunny_points
    from splatedit.model.estimate import estimate_splats
    n = 1_000_000
    pts, face_n = bunny_points(n)
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        cloud = estimate_splats(pts)
        peak = tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()
    assert peak / n < ESTIMATE_PEAK_EXTRA_BYTES_PER_POINT, f"{peak / n:.0f} bytes per point"
    outward = np.einsum("ij,ij->i", np.cross(cloud.u, cloud.v), face_n) > 0
    assert outward.all(), f"{(~outward).sum()} normals inward"
