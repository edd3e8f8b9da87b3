"""Closed-form neighbourhood PCA and the Morton point order."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from splatedit.io import read
from splatedit.model.pca import morton_order, neighbourhood_covariances, smallest_eigenvectors


def _full(cov6):
    m = np.empty((len(cov6), 3, 3))
    for c, (i, j) in enumerate(((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))):
        m[:, i, j] = m[:, j, i] = cov6[:, c]
    return m


def _angle_to_eigh(cov6):
    w, e = np.linalg.eigh(_full(cov6))
    v = smallest_eigenvectors(cov6)
    ang = np.arccos(np.clip(np.abs(np.einsum("ij,ij->i", v, e[:, :, 0])), 0, 1))
    return ang, w


def test_closed_form_matches_eigh_on_real_scan_neighbourhoods(shared_data):
    p = read(shared_data / "kitten.xyz").positions
    _, nb = cKDTree(p).query(p, k=16)
    cov = neighbourhood_covariances(p, nb, centres=p)
    ang, _ = _angle_to_eigh(cov)
    assert ang.max() < 1e-6


def test_closed_form_is_unit_and_matches_eigh_where_the_eigenvalue_is_simple():
    rng = np.random.default_rng(5)
    q, _ = np.linalg.qr(rng.normal(size=(20000, 3, 3)))
    lam = np.sort(rng.random((20000, 3)) ** 3, axis=1)
    lam[:1000, 1] = lam[:1000, 0]                  # smallest eigenvalue double: any vector in its plane
    lam[1000:2000] = 0.5                           # isotropic
    a = np.einsum("nij,nj,nkj->nik", q, lam, q)
    cov = a[:, [0, 0, 0, 1, 1, 2], [0, 1, 2, 1, 2, 2]]
    v = smallest_eigenvectors(cov)
    assert np.allclose(np.linalg.norm(v, axis=1), 1.0)
    # every answer is an eigenvector of the smallest eigenvalue: |A v - l v| small
    res = np.linalg.norm(np.einsum("nij,nj->ni", a, v) - lam[:, :1] * v, axis=1)
    assert res.max() < 1e-7
    gap = (lam[:, 1] - lam[:, 0]) / np.maximum(lam[:, 2], 1e-300)
    ang, _ = _angle_to_eigh(cov)
    simple = gap > 1e-3
    assert ang[simple].max() < 1e-5


def test_covariance_is_translation_invariant_for_georeferenced_coordinates():
    rng = np.random.default_rng(2)
    p = rng.normal(size=(2000, 3)) * [1.0, 1.0, 0.01]
    _, nb = cKDTree(p).query(p, k=12)
    near = neighbourhood_covariances(p, nb, centres=p)
    far = neighbourhood_covariances(p + [500_000.0, 5_000_000.0, 300.0], nb,
                                    centres=p + [500_000.0, 5_000_000.0, 300.0])
    assert np.allclose(near, far, rtol=1e-6, atol=1e-9 * np.abs(near).max())


def test_morton_order_is_a_permutation_that_keeps_neighbours_close_in_memory():
    p = np.random.default_rng(1).random((50000, 3))
    o = morton_order(p)
    assert np.array_equal(np.sort(o), np.arange(len(p)))
    # consecutive points in the order are far closer than consecutive points in random order
    step_sorted = np.median(np.linalg.norm(np.diff(p[o], axis=0), axis=1))
    step_random = np.median(np.linalg.norm(np.diff(p, axis=0), axis=1))
    assert step_sorted < 0.1 * step_random
