"""Benchmark of the incremental QR (Sect. 5) against LAPACK references.

``bench_qr(m)`` builds the full IQR least-squares matrix (m constraint rows
plus 10 side-condition rows; 10 polynomial columns plus m kernel columns in
farthest-point order) for m points sampled on a bumpy closed surface (not a
quadric, so the polynomial is kept) and times

* ``iqr_blocked_s``   -- :func:`splatedit.deform.qr.blocked_qr` on the
  prebuilt matrix, all columns (factorisation + Q^T b + all prefix residuals),
* ``iqr_fit_s``       -- ``TriharmonicRBF.fit(method="iqr", tol=0)``, i.e. the
  same plus building the columns lazily and the triangular solve,
* ``scipy_qr_economic_s`` / ``scipy_qr_r_s`` -- ``scipy.linalg.qr`` with
  ``mode="economic"`` (forms Q, like the spec asks) and ``mode="r"`` (R only,
  the like-for-like comparison),
* ``lu_fit_s``        -- ``TriharmonicRBF.fit(method="lu")`` (build + dgetrf
  + dgecon + dgetrs + residual),
* ``naive_s``         -- an unblocked column-by-column Householder QR in
  numpy (BLAS-2), measured for m <= ``naive_max`` and otherwise extrapolated
  with the O(M^3) rule from a measurement at ``naive_max``
  (``naive_extrapolated`` says which).

Usage: ``python -m splatedit.bench.qr 1000 3000 5000`` prints one JSON line
per size.
"""

from __future__ import annotations

import json
import os
import sys
import time

import numpy as np
import scipy.linalg

from splatedit.deform.centers import farthest_point_order
from splatedit.deform.kernels import kernel_matrix, poly_matrix
from splatedit.deform.rbf import TriharmonicRBF, blocked_qr


def surface_points(m: int, seed: int = 0) -> np.ndarray:
    """m random points on a bumpy, non-quadric closed surface."""
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(m, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    theta = np.arccos(np.clip(u[:, 2], -1, 1))
    phi = np.arctan2(u[:, 1], u[:, 0])
    r = 1.0 + 0.2 * np.sin(3 * theta) * np.cos(2 * phi)
    return u * r[:, None] * np.array([2.0, 1.0, 1.5])


def iqr_matrix(points: np.ndarray):
    """The full normalised IQR matrix and its farthest-point column order."""
    lo, hi = points.min(0), points.max(0)
    pn = (points - 0.5 * (lo + hi)) / (0.5 * np.max(hi - lo))
    m = pn.shape[0]
    order = farthest_point_order(pn)
    p = poly_matrix(pn)
    a = np.zeros((m + 10, m + 10), order="F")
    a[:m, :10] = p
    kernel_matrix(pn, pn[order], out=a[:m, 10:])
    a[m:, 10:] = p[order].T
    return a


def naive_householder_qr(a: np.ndarray, b: np.ndarray):
    """Unblocked right-looking Householder QR (one column at a time, BLAS-2)."""
    a = np.array(a, dtype=np.float64, order="F")
    b = np.array(b, dtype=np.float64)
    n_rows, n_cols = a.shape
    for j in range(min(n_rows - 1, n_cols)):
        x = a[j:, j]
        alpha = -np.copysign(np.linalg.norm(x), x[0])
        v = x.copy()
        v[0] -= alpha
        vn2 = v @ v
        if vn2 == 0.0:
            continue
        beta = 2.0 / vn2
        a[j:, j + 1:] -= np.outer(beta * v, v @ a[j:, j + 1:])
        b[j:] -= np.outer(beta * v, v @ b[j:])
        a[j, j] = alpha
        a[j + 1:, j] = 0.0
    return np.triu(a), b


def _best_of(fn, repeat):
    best = np.inf
    out = None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def bench_qr(m: int, seed: int = 0, naive_max: int = 1000, repeat: int = 1) -> dict:
    """Time the blocked IQR against scipy QR, LU and a naive Householder QR.

    Returns a JSON-serialisable dict (one line per size); ``ratio_*`` fields
    are IQR time divided by the reference time.
    """
    pts = surface_points(m, seed)
    values = np.c_[np.sin(pts[:, 0]), pts[:, 1] * pts[:, 2], np.cos(2 * pts[:, 2])]
    t0 = time.perf_counter()
    a = iqr_matrix(pts)
    t_build = time.perf_counter() - t0
    b = np.zeros((a.shape[0], 3))
    b[:m] = values

    t_iqr, (qr, tails) = _best_of(lambda: blocked_qr(a, b), repeat)
    t_econ, _ = _best_of(lambda: scipy.linalg.qr(a, mode="economic", check_finite=False), repeat)
    t_r, (r_ref,) = _best_of(lambda: scipy.linalg.qr(a, mode="r", check_finite=False), repeat)
    # agreement with the reference R (up to row signs)
    r_iqr = qr.r_factor()
    r_err = float(np.max(np.abs(np.abs(np.diag(r_iqr)) - np.abs(np.diag(r_ref))))
                  / np.max(np.abs(np.diag(r_ref))))
    del qr, r_iqr, r_ref
    t_fit_iqr, f_iqr = _best_of(
        lambda: TriharmonicRBF.fit(pts, values, method="iqr", tol=0.0), repeat)
    t_fit_lu, f_lu = _best_of(lambda: TriharmonicRBF.fit(pts, values, method="lu"), repeat)
    probe = surface_points(200, seed + 1) * 0.9
    rel_diff = float(np.max(np.abs(f_iqr(probe) - f_lu(probe))) / np.max(np.abs(f_lu(probe))))
    t_iqr_tol, f_tol = _best_of(
        lambda: TriharmonicRBF.fit(pts, values, method="iqr"), repeat)  # default tol

    m_naive = min(m, naive_max)
    if m_naive == m:
        t_naive, _ = _best_of(lambda: naive_householder_qr(a, b), 1)
        extrapolated = False
    else:
        a_small = iqr_matrix(surface_points(m_naive, seed))
        t_small, _ = _best_of(lambda: naive_householder_qr(a_small, np.zeros((a_small.shape[0], 3))), 1)
        t_naive = t_small * (a.shape[0] / a_small.shape[0]) ** 3
        extrapolated = True

    return {
        "m": m,
        "matrix_rows": a.shape[0],
        "blas_threads": (os.environ.get("OPENBLAS_NUM_THREADS") or os.environ.get("OMP_NUM_THREADS")
                         or f"default ({os.cpu_count()} cpus)"),
        "build_matrix_s": round(t_build, 4),
        "iqr_blocked_s": round(t_iqr, 4),
        "iqr_fit_s": round(t_fit_iqr, 4),
        "scipy_qr_economic_s": round(t_econ, 4),
        "scipy_qr_r_s": round(t_r, 4),
        "lu_fit_s": round(t_fit_lu, 4),
        "naive_s": round(t_naive, 3),
        "naive_extrapolated": extrapolated,
        "ratio_iqr_vs_qr_economic": round(t_iqr / t_econ, 3),
        "ratio_iqr_vs_qr_r": round(t_iqr / t_r, 3),
        "r_diag_rel_err": r_err,
        "iqr_full_vs_lu_rel": rel_diff,
        "iqr_default_tol": f_tol.tol,
        "iqr_default_tol_s": round(t_iqr_tol, 4),
        "iqr_default_tol_centers": f_tol.n_centers,
        "iqr_default_tol_residual": f_tol.residual,
    }


def main(argv=None) -> int:
    sizes = [int(s) for s in (argv if argv is not None else sys.argv[1:])] or [1000, 3000, 5000]
    for m in sizes:
        print(json.dumps(bench_qr(m)), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
