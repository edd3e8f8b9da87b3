"""The triharmonic kernel and the quadratic polynomial space of the paper.

Botsch & Kobbelt (EG 2005), Sect. 2 and 4: a deformation component is

    f(x) = sum_j w_j phi(||c_j - x||) + p(x),   phi(r) = r^3,   p in Pi_2,

with Pi_2 spanned by the 10 trivariate quadratic monomials.  Everything here is
plain vectorised numpy on (already normalised) coordinates; callers are
responsible for chunking large evaluations (see ``splatedit.deform.rbf``).

Conventions
-----------
* ``kernel_matrix(x, c)[i, j] = phi(||x_i - c_j||)``  (shape (N, n)).
* Gradient of one basis function w.r.t. the evaluation point:
  ``d/dx phi(||x - c||) = 3 ||x - c|| (x - c)``.
* ``MONOMIALS`` order: 1, x, y, z, x^2, xy, xz, y^2, yz, z^2.
"""

from __future__ import annotations

import numpy as np

#: number of trivariate quadratic monomials
N_POLY = 10

#: exponents (ex, ey, ez) of the monomials, in the documented order
MONOMIALS = (
    (0, 0, 0),
    (1, 0, 0), (0, 1, 0), (0, 0, 1),
    (2, 0, 0), (1, 1, 0), (1, 0, 1),
    (0, 2, 0), (0, 1, 1),
    (0, 0, 2),
)


def phi(r: np.ndarray) -> np.ndarray:
    """The triharmonic radial function ``phi(r) = r**3``."""
    r = np.asarray(r, dtype=np.float64)
    return r * r * r


def squared_distances(x: np.ndarray, c: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """``D[i, j] = ||x_i - c_j||^2`` computed from coordinate differences.

    Differences are formed explicitly (not via ``|x|^2 + |c|^2 - 2 x.c``) so
    that close pairs keep full relative accuracy; the cost is a few
    memory-bound passes over the (N, n) result.
    """
    x = np.asarray(x, dtype=np.float64)
    c = np.asarray(c, dtype=np.float64)
    n_rows, n_cols = x.shape[0], c.shape[0]
    if out is None:
        out = np.empty((n_rows, n_cols), dtype=np.float64)
    tmp = np.empty((n_rows, n_cols), dtype=np.float64)
    np.subtract.outer(x[:, 0], c[:, 0], out=out)
    np.multiply(out, out, out=out)
    for d in (1, 2):
        np.subtract.outer(x[:, d], c[:, d], out=tmp)
        np.multiply(tmp, tmp, out=tmp)
        out += tmp
    return out


def augmented_centers(c: np.ndarray) -> np.ndarray:
    """(5, n) matrix ``[-2 c^T; |c|^2; 1]`` for :func:`evaluation_squared_distances`."""
    c = np.asarray(c, dtype=np.float64)
    return np.ascontiguousarray(np.vstack([-2.0 * c.T, (c * c).sum(axis=1), np.ones(len(c))]))


def evaluation_squared_distances(x: np.ndarray, c_aug: np.ndarray) -> np.ndarray:
    """``D[i, j] = ||x_i - c_j||^2`` as ONE matrix product (BLAS-3), for evaluation.

    ``[x, 1, |x|^2] @ [-2 c^T; |c|^2; 1]`` writes the (N, n) result in a single
    pass instead of the eight passes of :func:`squared_distances`.  Close pairs
    lose relative accuracy (absolute error ~1e-15 in normalised coordinates,
    i.e. ~3e-8 in r for coincident points), which is harmless for evaluating
    ``r^3`` and ``3 r (x - c)``; the fitting matrices keep the exact form.
    Negative round-off is clamped to 0.

    Args:
        x: (N, 3) normalised query points.
        c_aug: (5, n) from :func:`augmented_centers`.
    """
    x = np.asarray(x, dtype=np.float64)
    x_aug = np.empty((x.shape[0], 5))
    x_aug[:, :3] = x
    x_aug[:, 3] = 1.0
    x_aug[:, 4] = (x * x).sum(axis=1)
    d2 = x_aug @ c_aug
    np.maximum(d2, 0.0, out=d2)
    return d2


def distance_matrix(x: np.ndarray, c: np.ndarray) -> np.ndarray:
    """``R[i, j] = ||x_i - c_j||`` (shape (N, n))."""
    d = squared_distances(x, c)
    np.sqrt(d, out=d)
    return d


def kernel_matrix(x: np.ndarray, c: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """``Phi[i, j] = ||x_i - c_j||^3`` (shape (N, n)).

    ``out`` may be a preallocated (N, n) float64 array, e.g. a column block of
    a Fortran-ordered matrix; it is filled in place and returned.
    """
    d2 = squared_distances(x, c)
    if out is None:
        out = np.empty_like(d2)
    np.sqrt(d2, out=out)
    out *= d2
    return out


def kernel_gradient(x: np.ndarray, c: np.ndarray) -> np.ndarray:
    """``G[i, j, :] = d/dx phi(||x - c_j||) at x_i = 3 r_ij (x_i - c_j)``.

    Shape (N, n, 3); meant for tests and small problems.  Large evaluations
    should use the GEMM form in :mod:`splatedit.deform.rbf`, which never
    materialises this 3-index array.
    """
    x = np.asarray(x, dtype=np.float64)
    c = np.asarray(c, dtype=np.float64)
    diff = x[:, None, :] - c[None, :, :]
    r = np.sqrt(np.einsum("ijk,ijk->ij", diff, diff))
    return 3.0 * r[:, :, None] * diff


def poly_matrix(x: np.ndarray) -> np.ndarray:
    """``P[i, j] = p_j(x_i)`` for the 10 quadratic monomials (shape (N, 10))."""
    x = np.asarray(x, dtype=np.float64)
    px, py, pz = x[:, 0], x[:, 1], x[:, 2]
    out = np.empty((x.shape[0], N_POLY), dtype=np.float64)
    out[:, 0] = 1.0
    out[:, 1] = px
    out[:, 2] = py
    out[:, 3] = pz
    out[:, 4] = px * px
    out[:, 5] = px * py
    out[:, 6] = px * pz
    out[:, 7] = py * py
    out[:, 8] = py * pz
    out[:, 9] = pz * pz
    return out


def poly_gradient_coefficients(q: np.ndarray) -> np.ndarray:
    """(3, 4, k) matrices G_d with ``grad_d p(x) = [1, x, y, z] @ G_d`` for the
    quadratic ``p = sum_j q_j p_j`` (q: (10, k), monomials in :data:`MONOMIALS` order)."""
    q = np.asarray(q, dtype=np.float64)
    return np.stack([
        np.stack([q[1], 2.0 * q[4], q[5], q[6]]),   # d/dx: x, x^2, xy, xz
        np.stack([q[2], q[5], 2.0 * q[7], q[8]]),   # d/dy: y, xy, y^2, yz
        np.stack([q[3], q[6], q[8], 2.0 * q[9]]),   # d/dz: z, xz, yz, z^2
    ])


def poly_gradient(x: np.ndarray) -> np.ndarray:
    """``G[i, j, d] = d p_j / d x_d at x_i`` (shape (N, 10, 3))."""
    x = np.asarray(x, dtype=np.float64)
    px, py, pz = x[:, 0], x[:, 1], x[:, 2]
    g = np.zeros((x.shape[0], N_POLY, 3), dtype=np.float64)
    # linear terms
    g[:, 1, 0] = 1.0
    g[:, 2, 1] = 1.0
    g[:, 3, 2] = 1.0
    # x^2
    g[:, 4, 0] = 2.0 * px
    # xy
    g[:, 5, 0] = py
    g[:, 5, 1] = px
    # xz
    g[:, 6, 0] = pz
    g[:, 6, 2] = px
    # y^2
    g[:, 7, 1] = 2.0 * py
    # yz
    g[:, 8, 1] = pz
    g[:, 8, 2] = py
    # z^2
    g[:, 9, 2] = 2.0 * pz
    return g
