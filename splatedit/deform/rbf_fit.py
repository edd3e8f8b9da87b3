"""Fit drivers of the triharmonic RBF (Botsch & Kobbelt 2005, Sect. 4-5).

:func:`solve_constraints` validates the constraints, normalises them into
[-1, 1]^3 (bounding-box centre and half its largest extent), merges
(near-)duplicates, decides which part of the quadratic polynomial the
constraints determine numerically (:func:`polynomial_basis`, with the
coordinates' precision from :func:`coordinate_precision`) and which solver
runs, and solves for the weights either exactly (dense LU of
system (3), :func:`_fit_lu`) or by the incremental least-squares QR of
Sect. 5 (:func:`_fit_iqr`, farthest-point centres, lazily built columns in a
:class:`~splatedit.deform.qr.IncrementalQR`).  The result is the raw
:class:`FitSolution` from which :meth:`TriharmonicRBF.fit
<splatedit.deform.rbf.TriharmonicRBF.fit>` builds the evaluable function.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from typing import Optional

import numpy as np
from scipy.linalg import lapack

from splatedit.blas import single_blas_thread
from splatedit.deform.centers import FarthestPointSampler
from splatedit.deform.kernels import N_POLY, kernel_matrix, poly_matrix
from splatedit.deform.qr import IncrementalQR
from splatedit.errors import ParameterError, SolverError
from splatedit.progress import ProgressFn, report
from splatedit.tolerances import (
    AUTO_EXACT_MAX_CONSTRAINTS,
    DUPLICATE_POINT_REL,
    DUPLICATE_VALUE_RTOL,
    IQR_DEFAULT_TOL,
    IQR_PANEL_COLUMNS,
    IQR_R_DIAG_RTOL,
    LU_MAX_CONSTRAINTS,
    LU_MIN_RCOND,
    POLY_NOISE_FACTOR,
    POLY_RANK_RTOL,
    COORD_FLOAT32_REL_PRECISION,
    COORD_GRID_MAX_DECIMALS,
)

METHODS = ("auto", "iqr", "lu")
PROGRESS_STAGE = "fitting deformation"

# ---------------------------------------------------------------------------
# input validation and preprocessing
# ---------------------------------------------------------------------------

def as_float_array(name: str, value) -> np.ndarray:
    """``value`` as a float64 array; not numeric: a
    :class:`~splatedit.errors.ParameterError` naming the parameter ``name``."""
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ParameterError(name, f"not a numeric array ({exc})") from None
    return arr


def _validate(points, values, method, tol, max_centers, progress):
    pts = as_float_array("points", points)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ParameterError("points", f"expected shape (m, 3), got {pts.shape}")
    m = pts.shape[0]
    if m < 1:
        raise ParameterError("points", "need at least one constraint point")
    if not np.all(np.isfinite(pts)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(pts), axis=1))[0])
        raise ParameterError("points", f"row {bad} is not finite")
    vals = as_float_array("values", values)
    if vals.ndim != 2:
        raise ParameterError(
            "values", f"expected shape (m, k), got {vals.shape} (use values[:, None] for one column)")
    if vals.shape[0] != m:
        raise ParameterError("values", f"has {vals.shape[0]} rows but points has {m}")
    if vals.shape[1] < 1:
        raise ParameterError("values", "needs at least one column")
    if not np.all(np.isfinite(vals)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(vals), axis=1))[0])
        raise ParameterError("values", f"row {bad} is not finite")
    if not isinstance(method, str) or method not in METHODS:
        raise ParameterError("method", f"must be one of {METHODS}, got {method!r}")
    if isinstance(tol, bool) or not isinstance(tol, numbers.Real) or not math.isfinite(tol) or tol < 0:
        raise ParameterError("tol", f"must be a finite number >= 0, got {tol!r}")
    if max_centers is not None:
        if isinstance(max_centers, bool) or not isinstance(max_centers, numbers.Integral) \
                or max_centers < 1:
            raise ParameterError("max_centers", f"must be None or an integer >= 1, got {max_centers!r}")
        max_centers = int(max_centers)
    if progress is not None and not callable(progress):
        raise ParameterError("progress", "must be callable or None")
    return pts, vals, float(tol), max_centers


def _merge_duplicates(pts_n: np.ndarray, vals: np.ndarray, radius: float):
    """Indices of the constraints to keep after merging (near-)duplicates.

    Points closer than ``radius`` (normalised units) form a group; a group
    whose values agree (DUPLICATE_VALUE_RTOL) is replaced by its first member,
    a group with conflicting values raises SolverError.
    """
    m = pts_n.shape[0]
    if m < 2:
        return np.arange(m), 0
    from scipy.spatial import cKDTree  # local: only needed here

    pairs = cKDTree(pts_n).query_pairs(radius, output_type="ndarray")
    if len(pairs) == 0:
        return np.arange(m), 0
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(m, m))
    _, labels = connected_components(graph, directed=False)
    # first member of every group, in input order
    _, first = np.unique(labels, return_index=True)
    first.sort()
    rep_of_label = np.empty(labels.max() + 1, dtype=np.intp)
    rep_of_label[labels[first]] = first
    rep_of_point = rep_of_label[labels]
    vmax = float(np.max(np.abs(vals))) if vals.size else 0.0
    diff = np.max(np.abs(vals - vals[rep_of_point]), axis=1)
    bad = np.flatnonzero(diff > DUPLICATE_VALUE_RTOL * vmax)
    if bad.size:
        i = int(bad[0])
        j = int(rep_of_point[i])
        raise SolverError(
            f"constraint points {j} and {i} coincide but have different values "
            f"(max difference {diff[i]:.3g}); a function cannot interpolate both "
            f"({bad.size} such conflicting point(s))")
    return first, m - first.size


@dataclass
class FitInfo:
    """How an RBF fit went: the solver ``method``, whether a ``polynomial``
    part was fitted, the relative ``residuals`` per column, the iterative
    solver's ``residual_history`` (None for direct solves) and ``notes``."""
    method: str
    polynomial: bool
    residuals: np.ndarray
    residual_history: Optional[np.ndarray]
    notes: list = field(default_factory=list)
    n_constraints: int = 0
    n_input_constraints: int = 0
    tol: float = IQR_DEFAULT_TOL
    rcond: Optional[float] = None
    seconds: float = 0.0
    poly_rank: int = 0
    poly_singular: Optional[np.ndarray] = None
    poly_weakest: float = 1.0
    precision: float = 0.0


@dataclass
class FitSolution:
    """What :func:`solve_constraints` found (normalised coordinates
    ``xn = (x - shift) / scale``).

    Attributes:
        points: (m_in, 3) float64 the validated input constraint points.
        values: (m_in, k) float64 their validated values.
        centers_n: (n, 3) float64 normalised RBF centres.
        weights: (n, k) float64 RBF weights.
        poly_coeffs: (10, k) float64 monomial coefficients, or None (dropped).
        shift: (3,) float64, scale: float (model units) the normalisation.
        center_indices: (n,) indices of the centres into ``points``.
        info: the solver's :class:`FitInfo`.
    """

    points: np.ndarray
    values: np.ndarray
    centers_n: np.ndarray
    weights: np.ndarray
    poly_coeffs: Optional[np.ndarray]
    shift: np.ndarray
    scale: float
    center_indices: np.ndarray
    info: FitInfo


def coordinate_precision(pts: np.ndarray) -> float:
    """The precision (model units) to which the coordinates ``pts`` (m, 3) are
    known.  Coordinates that all lie on a decimal grid of 10^-d (d <=
    COORD_GRID_MAX_DECIMALS: text files written with d decimals, LAS-style
    scaled integers) are known to half its step, at least to their storage's
    own rounding (float32 when every value is a float32).  Otherwise they are
    assumed to come from float32 storage (every 3DGS file and most scans,
    possibly moved since): COORD_FLOAT32_REL_PRECISION of their largest
    magnitude.
    """
    mag = float(np.max(np.abs(pts))) if pts.size else 0.0
    if mag == 0.0:
        return 0.0
    eps32 = COORD_FLOAT32_REL_PRECISION * mag
    eps64 = float(np.finfo(np.float64).eps) * mag
    is32 = bool(np.array_equal(pts.astype(np.float32).astype(np.float64), pts))
    own = eps32 if is32 else eps64
    # a value of the grid, stored, is off it by its storage's rounding (plus
    # the rounding of pts / step); grids not coarser than that are not seen
    allowed = 2.0 * own + 8.0 * eps64
    for d in range(COORD_GRID_MAX_DECIMALS + 1):
        step = 10.0 ** -d
        if step <= 4.0 * allowed:
            break
        k = pts / step
        if float(np.max(np.abs(k - np.rint(k)))) * step <= allowed:
            return max(0.5 * step, own)
    return eps32


@dataclass
class PolyBasis:
    """The part of the quadratic polynomial space Pi_2 that the constraint
    points determine numerically (see :func:`polynomial_basis`).

    Attributes:
        matrix: (m, r) the retained polynomial columns at the constraints
            (orthogonal, each of norm sqrt(m)).
        coeffs: (10, r) their monomial coefficients (normalised coordinates):
            ``matrix = poly_matrix(pts_n) @ coeffs``.
        rank: r, 0..10 (the affine part first: ``n_affine`` of its 4 terms).
        n_affine: how many of r span affine functions (4; 3 on a plane).
        singular: (10,) the singular values of the affine block and of the
            quadratic block beyond it, relative to the largest, each block
            in descending order.
        weakest: the smallest relative singular value kept (1.0 when r = 0).
        cut: (2,) the relative cuts of the two blocks (values at or below
            them were dropped).
        note: what was dropped and why ("" when nothing was).
    """

    matrix: np.ndarray
    coeffs: np.ndarray
    rank: int
    n_affine: int
    singular: np.ndarray
    weakest: float
    cut: np.ndarray
    note: str = ""


def _monomial_gradient_norms(pts_n: np.ndarray) -> np.ndarray:
    """(10,) ``||grad p_j||`` (2-norm over the points) of the monomials."""
    m = pts_n.shape[0]
    gx, gy, gz = np.sum(pts_n * pts_n, axis=0)
    return np.sqrt(np.array([0.0, m, m, m, 4 * gx, gx + gy, gx + gz, 4 * gy, gy + gz, 4 * gz]))


def _independent_block(cols: np.ndarray, noise: float, cut_rel: float):
    """SVD of ``cols`` (m, c), unit-scaled columns: (u_kept (m, r), map (c, r)
    with ``cols @ map = u_kept``, all singular values, the absolute cut)."""
    if cols.shape[1] == 0:
        return np.zeros((cols.shape[0], 0)), np.zeros((0, 0)), np.zeros(0), 0.0
    u, s, vt = np.linalg.svd(cols, full_matrices=False)
    cut = max(cut_rel, POLY_NOISE_FACTOR * noise)
    r = int(np.count_nonzero(s > cut))
    return u[:, :r], vt[:r].T / s[:r], s, cut


def polynomial_basis(pts_n: np.ndarray, precision: float,
                     rtol: Optional[float] = None) -> PolyBasis:
    """The numerically independent part of Pi_2 at the points ``pts_n``
    (m, 3), normalised coordinates known to ``precision`` (normalised units).

    A rank-revealing factorisation in two blocks, so that affine functions
    stay exactly reproduced wherever the points determine them: the affine
    monomials (1, x, y, z), scaled to unit columns, by an SVD; then the 6
    quadratic monomials, scaled, with their affine part projected out (the
    quadratic directions the points see beyond the affine ones), by an SVD.
    In each block a direction is dropped when its singular value is within
    POLY_NOISE_FACTOR times the first-order bound of the coordinates'
    rounding on the block (``||dP_j|| <= precision ||grad p_j||`` per
    column), or below POLY_RANK_RTOL (or ``rtol``, the fit's check, see
    :meth:`TriharmonicRBF.fit`) of the largest singular value.  Such a
    direction is a quadric (a sphere, cylinder or cone: one quadratic
    direction; a plane: its normal coordinate and 3 quadratic ones) the points
    lie on up to their precision: its coefficient would be fitted to the
    rounding, with wild derivatives off the surface, so it is left out.
    """
    # tall, 10 columns: OpenBLAS's threads only contend here (20,000 points on
    # the loaded 2-core machine: 8 ms on one thread, 70-160 ms on two)
    with single_blas_thread():
        return _polynomial_basis(pts_n, precision, rtol)


def _polynomial_basis(pts_n: np.ndarray, precision: float, rtol: Optional[float]) -> PolyBasis:
    m = pts_n.shape[0]
    p = poly_matrix(pts_n)
    norms = np.linalg.norm(p, axis=0)
    safe = np.where(norms > 0, norms, 1.0)
    rel_noise = precision * _monomial_gradient_norms(pts_n) / safe
    ps = p / safe
    scale_s = float(np.linalg.norm(ps, 2))
    cut_rel = max(POLY_RANK_RTOL, rtol or 0.0) * scale_s
    # affine block
    n1 = 4
    u1, map1, s1, cut1 = _independent_block(ps[:, :n1], float(np.linalg.norm(rel_noise[:n1])), cut_rel)
    r1 = u1.shape[1]
    # quadratic block beyond the affine span
    quad = ps[:, n1:]
    proj = u1.T @ quad  # (r1, 6)
    quad_rest = quad - u1 @ proj
    u2, map2, s2, cut2 = _independent_block(quad_rest, float(np.linalg.norm(rel_noise[n1:])), cut_rel)
    r2 = u2.shape[1]
    # monomial coefficients of the kept columns (scaled columns -> monomials)
    coef = np.zeros((N_POLY, r1 + r2))
    coef[:n1, :r1] = map1
    coef[n1:, r1:] = map2
    # quad_rest @ map2 = quad @ map2 - u1 @ (proj @ map2), u1 = affine @ map1
    coef[:n1, r1:] = -map1 @ (proj @ map2)
    coeffs = coef / safe[:, None] * np.sqrt(m)
    matrix = p @ coeffs
    sv = np.concatenate([s1, s2]) / scale_s
    kept = np.concatenate([s1[:r1], s2[:r2]]) / scale_s
    weakest = float(kept.min()) if kept.size else 1.0
    r = r1 + r2
    note = ""
    if r == 0:
        note = "polynomial dropped: no direction of it is determined by the constraints"
    elif r < N_POLY:
        dropped = np.concatenate([s1[r1:], s2[r2:]]) / scale_s
        note = (f"polynomial reduced to {r} of {N_POLY} terms ({r1} affine): the constraints lie "
                f"on a quadric up to their precision (dropped s/s_max "
                f"{', '.join(f'{v:.1e}' for v in dropped)}; cuts {cut1 / scale_s:.1e} affine, "
                f"{cut2 / scale_s:.1e} quadratic; coordinate precision {precision:.1e} of the "
                f"half extent)")
    return PolyBasis(matrix=matrix, coeffs=coeffs, rank=r, n_affine=r1, singular=sv,
                     weakest=weakest, cut=np.array([cut1, cut2]) / scale_s, note=note)


class SingularSystemError(SolverError):
    """The exact LU system cannot be solved; ``reason`` says how it is singular
    (``method="auto"`` then falls back to the incremental QR)."""

    def __init__(self, reason: str, advice: str):
        super().__init__(f"the exact RBF system is {reason}; {advice}")
        self.reason = reason


def solve_constraints(points, values, method: str = "auto", tol: float = IQR_DEFAULT_TOL,
                      max_centers: Optional[int] = None,
                      progress: Optional[ProgressFn] = None,
                      poly_rtol: Optional[float] = None) -> FitSolution:
    """Validate, normalise, merge duplicates and solve ``f(points) = values``.

    The arguments, the duplicate, polynomial and method rules are those of
    :meth:`splatedit.deform.rbf.TriharmonicRBF.fit` (documented there);
    ``poly_rtol`` additionally drops polynomial directions with singular value
    below ``poly_rtol`` times the largest (the fit's check, see
    :func:`polynomial_basis`).
    Raises ParameterError for bad arguments and SolverError when the system
    cannot be solved.
    """
    pts, vals, tol, max_centers = _validate(points, values, method, tol, max_centers, progress)
    m_in = pts.shape[0]
    vals_in = vals
    notes: list = []

    # normalisation by the constraint bounding box
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    shift = 0.5 * (lo + hi)
    extent = float(np.max(hi - lo))
    scale = 0.5 * extent if extent > 0 else 1.0
    pts_n = (pts - shift) / scale
    diag = float(np.linalg.norm(hi - lo))

    # duplicates
    keep, n_merged = _merge_duplicates(pts_n, vals, DUPLICATE_POINT_REL * diag / scale)
    if n_merged:
        pts_n = pts_n[keep]
        vals = vals[keep]
        notes.append(f"merged {n_merged} duplicate constraint point(s) with identical values")
    m = pts_n.shape[0]

    # polynomial: its numerically independent part on the constraint set
    precision = coordinate_precision(pts) / scale
    if m < N_POLY:
        poly = None
        notes.append(f"polynomial dropped: {m} < {N_POLY} constraints cannot determine a quadratic")
    else:
        poly = polynomial_basis(pts_n, precision, rtol=poly_rtol)
        poly_sv, poly_weakest = poly.singular, poly.weakest
        if poly.note:
            notes.append(poly.note)
        if poly.rank == 0:
            poly = None
    use_poly = poly is not None
    if not use_poly and m == 1:
        raise SolverError(
            "a single (distinct) constraint point cannot be fitted: without the "
            "polynomial the kernel matrix is [phi(0)] = [0]; give at least 2 distinct points")

    # method
    if method == "lu" and max_centers is not None and max_centers < m:
        raise ParameterError(
            "max_centers", f"method='lu' uses all {m} constraints as centers; "
            f"max_centers={max_centers} needs method='iqr'")
    if method == "lu" and m > LU_MAX_CONSTRAINTS:
        raise ParameterError(
            "method", f"method='lu' with {m} constraints needs a dense {m + N_POLY}^2 system "
            f"(> {LU_MAX_CONSTRAINTS} constraints); use method='iqr' or 'auto'")
    head: list = []
    if method == "auto":
        if m <= AUTO_EXACT_MAX_CONSTRAINTS and (max_centers is None or max_centers >= m):
            used = "lu"
            head.append(f"auto: exact LU solve since m = {m} <= {AUTO_EXACT_MAX_CONSTRAINTS}")
        else:
            used = "iqr"
            why = (f"m = {m} > {AUTO_EXACT_MAX_CONSTRAINTS}" if m > AUTO_EXACT_MAX_CONSTRAINTS
                   else f"max_centers = {max_centers} < m = {m}")
            head.append(f"auto: incremental QR since {why}")
    else:
        used = method

    report(progress, PROGRESS_STAGE, 0.0)
    if used == "lu":
        try:
            w, q, idx, residuals, rcond = _fit_lu(pts_n, vals, poly)
        except SingularSystemError as exc:
            if method != "auto":
                raise
            # dense scans give near-duplicate constraint points (further apart
            # than the duplicate merge radius, yet nearly equal rows): the
            # least-squares QR picks well-separated centres and still fits them
            used = "iqr"
            head.append(f"auto: incremental QR since the exact system is {exc.reason}")
    if used == "lu":
        history = None
        head.append(f"lu: exact solve with all {m} constraints as centers, "
                    f"rcond {rcond:.1e}")
    else:
        rcond = None
        w, q, idx, residuals, history, iqr_notes = _fit_iqr(
            pts_n, vals, poly, tol, max_centers, progress)
        head.extend(iqr_notes)
    notes = head + notes
    report(progress, PROGRESS_STAGE, 1.0)

    info = FitInfo(method=used, polynomial=use_poly, residuals=residuals,
                    residual_history=history, notes=notes, n_constraints=m,
                    n_input_constraints=m_in, tol=tol, rcond=rcond,
                    poly_rank=poly.rank if use_poly else 0,
                    poly_singular=None if m < N_POLY else poly_sv,
                    poly_weakest=poly.weakest if use_poly else 1.0, precision=precision)
    return FitSolution(points=pts, values=vals_in, centers_n=pts_n[idx], weights=w,
                       poly_coeffs=q, shift=shift, scale=scale, center_indices=keep[idx],
                       info=info)


# ---------------------------------------------------------------------------
# the two solvers (normalised coordinates)
# ---------------------------------------------------------------------------

def relative_residuals(res_norm: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Scale-free ``res_norm / ||b||`` per column (both 2-norms over the m
    constraints, so a uniform error e on values of RMS size s gives e / s
    whatever m); the absolute ``res_norm`` where ``b`` is identically 0."""
    bn = np.linalg.norm(b, axis=0)
    nz = bn > 0
    out = np.array(res_norm, dtype=np.float64, copy=True)
    out[..., nz] = out[..., nz] / bn[nz]
    return out


def _fit_lu(pts_n, vals, poly):
    m, k = vals.shape
    use_poly = poly is not None
    npoly = poly.rank if use_poly else 0
    size = m + npoly
    a = np.zeros((size, size), order="F")
    kernel_matrix(pts_n, pts_n, out=a[:m, :m])
    if use_poly:
        p = poly.matrix
        a[:m, m:] = p
        a[m:, :m] = p.T
    rhs = np.zeros((size, k))
    rhs[:m] = vals
    anorm = float(np.max(np.sum(np.abs(a), axis=0)))
    lu, piv, info = lapack.dgetrf(a, overwrite_a=0)
    if info > 0:
        raise SingularSystemError(f"singular (zero pivot at {info - 1})",
                                  "use method='iqr' or remove degenerate constraints")
    rcond, _ = lapack.dgecon(lu, anorm, norm="1")
    if not rcond >= LU_MIN_RCOND:
        raise SingularSystemError(f"numerically singular (rcond {rcond:.1e} < {LU_MIN_RCOND:g})",
                                  "use method='iqr' or remove near-duplicate constraints")
    x, info = lapack.dgetrs(lu, piv, rhs)
    res = np.linalg.norm(a @ x - rhs, axis=0)
    residuals = relative_residuals(res, vals)
    w = x[:m]
    q = poly.coeffs @ x[m:] if use_poly else None
    return w, q, np.arange(m), residuals, float(rcond)


def _fit_iqr(pts_n, vals, poly, tol, max_centers, progress):
    m, k = vals.shape
    use_poly = poly is not None
    npoly = poly.rank if use_poly else 0
    n_rows = m + npoly
    cap = m if max_centers is None else min(max_centers, m)
    max_cols = npoly + cap
    rhs = np.zeros((n_rows, k))
    rhs[:m] = vals
    qr = IncrementalQR(n_rows, max_cols, rhs)
    sampler = FarthestPointSampler(pts_n)
    p_all = poly.matrix if use_poly else None
    order_parts = []
    hist_parts = []  # residuals for center counts 0, 1, ...
    bn = np.linalg.norm(vals, axis=0)
    scale_c = np.where(bn > 0, 1.0 / np.where(bn > 0, bn, 1.0), 0.0)
    panel_w = max(IQR_PANEL_COLUMNS, npoly + 1)
    running_min = np.full(k, np.inf)
    stop_cols = None
    while qr.n_cols < max_cols:
        j0 = qr.n_cols
        block = qr.panel(panel_w)
        width = block.shape[1]
        c0 = 0
        if j0 == 0 and use_poly:
            block[:m, :npoly] = p_all
            block[m:, :npoly] = 0.0
            c0 = npoly
        idx = sampler.take(width - c0)
        order_parts.append(idx)
        kernel_matrix(pts_n, pts_n[idx], out=block[:m, c0:])
        if use_poly:
            block[m:, c0:] = p_all[idx].T
        tails = qr.add_panel()  # prefixes n = j0 .. j0 + width
        res = tails * scale_c  # (width + 1, k)
        first_n = max(j0 + (0 if j0 == 0 else 1), npoly)
        res = res[first_n - j0:]
        res = np.minimum.accumulate(np.vstack([running_min[None, :], res]), axis=0)[1:]
        running_min = res[-1]
        below = np.flatnonzero(np.all(res < tol, axis=1))
        if below.size:
            stop_cols = first_n + int(below[0])
            hist_parts.append(res[: below[0] + 1])
            break
        hist_parts.append(res)
        report(progress, PROGRESS_STAGE, qr.n_cols / max_cols)
    notes = []
    if stop_cols is None:
        stop_cols = max_cols
    n_centers = stop_cols - npoly
    history = np.concatenate(hist_parts, axis=0)
    residuals = history[-1].copy()
    x = qr.solve(stop_cols)
    order = np.concatenate(order_parts)[:n_centers] if order_parts else np.zeros(0, np.intp)
    w = x[npoly:]
    q = poly.coeffs @ x[:npoly] if use_poly else None
    summary = (f"iqr: {n_centers} of {m} constraints as centers, residual "
               f"{np.max(residuals):.2g}")
    if np.max(residuals) < tol:
        summary += f" < tol {tol:g}"
    notes.append(summary)
    if np.max(residuals) >= tol:
        if max_centers is not None and n_centers == max_centers < m:
            notes.append(f"max_centers = {max_centers} reached before tol {tol:g}")
        elif tol > 0:
            notes.append(f"all {m} centers used and tol {tol:g} still not reached "
                         "(rounding limits the residual)")
    diag = np.abs(qr.r_diagonal(stop_cols))
    if diag.size and diag.min() < IQR_R_DIAG_RTOL * diag.max():
        notes.append(f"R is nearly singular (min/max |diag| = {diag.min() / diag.max():.1e}); "
                     "weights may be inaccurate")
    return w, q, order, residuals, history, notes
