"""Real SH basis (3DGS convention) and its rotation: SH'(Q d) == SH(d)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from splatedit.model.spherical_harmonics import BAND_SLICES, C1, rotate_sh, sh_basis, sh_colors


def _dirs(rng, n):
    d = rng.normal(size=(n, 3))
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def test_band_1_has_the_reference_signs():
    """The reference sh_utils: -C1 y sh1 + C1 z sh2 - C1 x sh3."""
    d = np.array([[0.0, 0.6, 0.8]])
    np.testing.assert_allclose(sh_basis(d, 1)[0, 1:], [-C1 * 0.6, C1 * 0.8, -0.0])


def test_bands_are_orthonormal_on_the_sphere():
    """Monte Carlo integral of Y_i Y_j over the sphere: 4 pi mean = identity (200,000 samples)."""
    y = sh_basis(_dirs(np.random.default_rng(0), 200_000))
    gram = 4 * np.pi * (y.T @ y) / len(y)
    assert np.abs(gram - np.eye(16)).max() < 0.03


@pytest.mark.parametrize("degree", [1, 2, 3])
def test_rotated_coefficients_give_the_rotated_function(degree):
    rng = np.random.default_rng(degree)
    n = 500
    q = Rotation.random(n, random_state=degree).as_matrix()
    sh = rng.normal(size=(n, (degree + 1) ** 2, 3))
    rot = rotate_sh(sh, q)
    d = _dirs(rng, n)
    before = np.einsum("nk,nkc->nc", sh_basis(d, degree), sh)
    after = np.einsum("nk,nkc->nc", sh_basis(np.einsum("nij,nj->ni", q, d), degree), rot)
    assert np.abs(after - before).max() < 1e-12
    # each band keeps its energy; band 0 is untouched
    for band in BAND_SLICES[:degree + 1]:
        np.testing.assert_allclose((rot[:, band] ** 2).sum(1), (sh[:, band] ** 2).sum(1), rtol=1e-12)
    assert np.array_equal(rot[:, 0], sh[:, 0])


def test_reflections_and_chunks():
    """An improper orthogonal map works too, and blocks of rows agree with one block."""
    rng = np.random.default_rng(7)
    q = Rotation.random(100, random_state=3).as_matrix() @ np.diag([1.0, 1.0, -1.0])
    sh = rng.normal(size=(100, 16, 3))
    a, b = rotate_sh(sh, q), rotate_sh(sh, q, chunk=7)
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-14)
    d = _dirs(rng, 100)
    np.testing.assert_allclose(sh_colors(a, np.einsum("nij,nj->ni", q, d)), sh_colors(sh, d), atol=1e-12)
