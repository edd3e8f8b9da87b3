"""Kernel, polynomial basis and farthest-point ordering (independent oracles)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from splatedit.deform.centers import FarthestPointSampler, farthest_point_order
from splatedit.deform.kernels import (
    MONOMIALS,
    N_POLY,
    distance_matrix,
    kernel_gradient,
    kernel_matrix,
    phi,
    poly_gradient,
    poly_matrix,
    squared_distances,
)
from splatedit.errors import ParameterError


def _rng(seed=0):
    return np.random.default_rng(seed)


def test_phi_is_r_cubed():
    r = np.array([0.0, 0.5, 1.0, 2.0])
    assert np.array_equal(phi(r), r ** 3)


def test_kernel_matrix_matches_loop():
    rng = _rng()
    x, c = rng.normal(size=(7, 3)), rng.normal(size=(5, 3))
    ref = np.array([[np.linalg.norm(xi - cj) ** 3 for cj in c] for xi in x])
    np.testing.assert_allclose(kernel_matrix(x, c), ref, rtol=1e-13)
    np.testing.assert_allclose(distance_matrix(x, c) ** 3, ref, rtol=1e-13)
    assert np.all(np.diag(kernel_matrix(x, x)) == 0.0)


def test_kernel_matrix_into_strided_out():
    rng = _rng(1)
    x, c = rng.normal(size=(6, 3)), rng.normal(size=(4, 3))
    big = np.full((8, 10), np.nan, order="F")
    kernel_matrix(x, c, out=big[1:7, 3:7])
    np.testing.assert_allclose(big[1:7, 3:7], kernel_matrix(x, c))
    assert np.isnan(big[0]).all() and np.isnan(big[:, :3]).all()


def test_close_points_keep_relative_accuracy():
    # explicit differences: no |x|^2 + |c|^2 - 2x.c cancellation far from the origin
    x = np.array([[1e4, 1e4, 1e4]])
    c = x + np.array([[1e-6, 0.0, 0.0]])
    assert squared_distances(x, c)[0, 0] == pytest.approx(1e-12, rel=1e-6)


def test_kernel_gradient_central_differences():
    rng = _rng(2)
    x, c = rng.normal(size=(5, 3)), rng.normal(size=(4, 3))
    g = kernel_gradient(x, c)
    h = 1e-6
    for d in range(3):
        e = np.zeros(3)
        e[d] = h
        fd = (kernel_matrix(x + e, c) - kernel_matrix(x - e, c)) / (2 * h)
        np.testing.assert_allclose(g[:, :, d], fd, rtol=1e-7, atol=1e-9)


def test_poly_matrix_monomials():
    rng = _rng(3)
    x = rng.normal(size=(6, 3))
    p = poly_matrix(x)
    assert p.shape == (6, N_POLY) and len(MONOMIALS) == N_POLY
    for j, (ex, ey, ez) in enumerate(MONOMIALS):
        np.testing.assert_allclose(p[:, j], x[:, 0] ** ex * x[:, 1] ** ey * x[:, 2] ** ez)


def test_poly_gradient_central_differences():
    rng = _rng(4)
    x = rng.normal(size=(6, 3))
    g = poly_gradient(x)
    h = 1e-6
    for d in range(3):
        e = np.zeros(3)
        e[d] = h
        fd = (poly_matrix(x + e) - poly_matrix(x - e)) / (2 * h)
        np.testing.assert_allclose(g[:, :, d], fd, atol=1e-8)


def _brute_force_order(points):
    m = len(points)
    first = int(np.argmax(np.linalg.norm(points - points.mean(0), axis=1)))
    order = [first]
    while len(order) < m:
        d = np.min(np.linalg.norm(points[:, None] - points[order][None], axis=2), axis=1)
        d[order] = -1
        order.append(int(np.argmax(d)))
    return np.array(order)


def test_farthest_point_order_matches_brute_force():
    pts = _rng(5).uniform(size=(60, 3))
    assert np.array_equal(farthest_point_order(pts), _brute_force_order(pts))


@settings(max_examples=25, deadline=None)
@given(arrays(np.float64, st.tuples(st.integers(1, 40), st.just(3)),
              elements=st.floats(-10, 10, allow_nan=False, allow_subnormal=False)))
def test_farthest_point_order_is_a_permutation_and_greedy(pts):
    order = farthest_point_order(pts)
    assert sorted(order.tolist()) == list(range(len(pts)))
    # greedy property: each selected point is (one of) the farthest from the previous ones
    for i in range(1, len(order)):
        prev = pts[order[:i]]
        d_rest = np.min(np.linalg.norm(pts[order[i:], None] - prev[None], axis=2), axis=1)
        assert d_rest[0] >= d_rest.max() - 1e-9


def test_sampler_incremental_equals_one_shot_and_duplicates_last():
    pts = _rng(6).normal(size=(30, 3))
    pts = np.vstack([pts, pts[:3]])  # 3 exact duplicates
    full = farthest_point_order(pts)
    s = FarthestPointSampler(pts)
    parts = np.concatenate([s.take(5), s.take(11), s.take(100)])
    assert np.array_equal(parts, full)
    assert s.take(3).size == 0
    # the duplicated pairs: the second copy of each comes after all 30 distinct points
    pos = np.argsort(full)
    for i in range(3):
        assert max(pos[i], pos[30 + i]) >= 30
    assert np.array_equal(farthest_point_order(pts, 4), full[:4])


def test_sampler_rejects_bad_shapes():
    with pytest.raises(ParameterError, match="points"):
        farthest_point_order(np.zeros((4, 2)))
    with pytest.raises(ParameterError, match="points"):
        farthest_point_order(np.zeros((0, 3)))
