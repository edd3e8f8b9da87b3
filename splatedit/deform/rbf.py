"""Triharmonic RBF fitting and evaluation (Botsch & Kobbelt 2005, Sect. 4-5).

A fitted :class:`TriharmonicRBF` is the vector-valued function

    f(x) = sum_j w_j phi(||c_j - x||) + p(x),   phi(r) = r^3,  p in Pi_2,

fitted to constraints ``f(x_i) = b_i`` either exactly (``method="lu"``, system
(3) of the paper) or by the paper's incremental least-squares QR
(``method="iqr"``, Sect. 5).

Coordinates are normalised before any matrix is built: ``xn = (x - shift) /
scale`` with ``shift`` the centre of the constraint bounding box and ``scale``
half its largest extent, so the normalised constraints lie in [-1, 1]^3.  This
does not change the interpolant (``phi`` is homogeneous and Pi_2 is invariant
under affine maps) but keeps the matrix entries O(1).  The fitted object
evaluates in the original coordinates; gradients carry the chain-rule factor
``1 / scale``.
"""

from __future__ import annotations

import math
import numbers
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Optional

import numpy as np
from scipy.linalg import lapack

from splatedit.deform.centers import FarthestPointSampler
from splatedit.deform.kernels import (
    N_POLY,
    augmented_centers,
    poly_gradient_coefficients,
    evaluation_squared_distances,
    kernel_matrix,
    poly_gradient,
    poly_matrix,
    squared_distances,
)
from splatedit.errors import ParameterError, SolverError
from splatedit.progress import ProgressFn, report
from splatedit.tolerances import (
    AUTO_EXACT_MAX_CONSTRAINTS,
    DUPLICATE_POINT_REL,
    DUPLICATE_VALUE_RTOL,
    EVAL_CHUNK_MAX_BYTES,
    EVAL_CHUNK_ROWS,
    EVAL_THREADS,
    IQR_DEFAULT_TOL,
    IQR_PANEL_COLUMNS,
    IQR_R_DIAG_RTOL,
    LU_MAX_CONSTRAINTS,
    RESIDUAL_NOTE_FACTOR,
    RESIDUAL_NOTE_MIN,
    LU_MIN_RCOND,
    POLY_RANK_RTOL,
)

METHODS = ("auto", "iqr", "lu")
PROGRESS_STAGE = "fitting deformation"


# ---------------------------------------------------------------------------
# input validation and preprocessing
# ---------------------------------------------------------------------------

def _as_float_array(name: str, value) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ParameterError(name, f"not a numeric array ({exc})") from None
    return arr


def _validate(points, values, method, tol, max_centers, progress):
    pts = _as_float_array("points", points)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ParameterError("points", f"expected shape (m, 3), got {pts.shape}")
    m = pts.shape[0]
    if m < 1:
        raise ParameterError("points", "need at least one constraint point")
    if not np.all(np.isfinite(pts)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(pts), axis=1))[0])
        raise ParameterError("points", f"row {bad} is not finite")
    vals = _as_float_array("values", values)
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


# ---------------------------------------------------------------------------
# the incremental (blocked) Householder QR of Sect. 5
# ---------------------------------------------------------------------------

class IncrementalQR:
    """Householder QR of a tall matrix grown panel by panel (left-looking).

    Implements Sect. 5 of the paper with BLAS-3 panels instead of single
    columns.  For every new panel of columns:

    1. the reflectors of every previous panel are applied to it, one blocked
       ``dgemqrt`` call per previous panel (compact WY form ``I - V T V^T``
       with the ``T`` stored at factorisation time, so it is never recomputed);
    2. the panel's lower part is factored by ``dgeqrt`` (recursive, BLAS-3);
    3. its reflectors are applied to the right-hand sides, so ``Q^T b`` is
       always current;
    4. the residual of *every* prefix column count inside the panel follows
       for free: ``||b - A[:, :n] x*|| = ||(Q^T b)[n:]||``.  Rows ``n:`` are
       only ever touched by orthogonal reflectors from column ``n`` on, so the
       tail norm is the same whether read right after column ``n`` or later.

    The working panel is kept as a C-ordered (n_rows, w) array: its transpose
    is Fortran-ordered and every row block ``[off:]`` of the panel is a
    Fortran-contiguous column block of the transpose, so step 1 runs
    ``dgemqrt(side="R")`` on the transpose in place, without copies.

    Storage: the reflector blocks ``V_p`` (trapezoidal, the used columns of
    A below the diagonal), their ``T`` factors, and R as per-panel column
    blocks ``R[:j1, j0:j1]``; nothing is allocated for columns never used, so
    memory is O(n_rows * n) for n used columns.
    """

    def __init__(self, n_rows: int, max_cols: int, rhs: np.ndarray):
        if max_cols > n_rows:
            raise ValueError("IncrementalQR needs max_cols <= n_rows")
        self.n_rows = n_rows
        self.max_cols = max_cols
        self.r_blocks = []  # column blocks R[:j1, j0:j1] of the upper triangle
        self.qtb = np.array(rhs, dtype=np.float64, order="F", copy=True)
        if self.qtb.ndim != 2 or self.qtb.shape[0] != n_rows:
            raise ValueError("rhs must have shape (n_rows, k)")
        self.panels = []  # (offset, V (n_rows - offset, w) Fortran, T (w, w))
        self.n_cols = 0
        self._panel = None

    def panel(self, width: int) -> np.ndarray:
        """A writable (n_rows, w) block for the next ``w <= width`` columns."""
        width = min(width, self.max_cols - self.n_cols)
        self._panel = np.empty((self.n_rows, width), dtype=np.float64, order="C")
        return self._panel

    def add_panel(self) -> np.ndarray:
        """Factor the columns written into the last :meth:`panel` block.

        Returns ``tails`` of shape (w + 1, k): ``tails[i] = ||(Q^T b)[j0+i:]||``
        for the prefixes ``n = j0 .. j0 + w`` columns.
        """
        c = self._panel
        if c is None:
            raise ValueError("call panel() first")
        self._panel = None
        j0 = self.n_cols
        width = c.shape[1]
        j1 = j0 + width
        ct = c.T  # Fortran-ordered (w, n_rows) view of the same memory
        # 1. previous reflectors: C[off:] <- Q_p^T C[off:]  <=>  Ct[:, off:] <- Ct[:, off:] Q_p
        for off, v, t in self.panels:
            blk = ct[:, off:]
            out, info = lapack.dgemqrt(v, t, blk, side="R", trans="N", overwrite_c=1)
            if info != 0:  # pragma: no cover - argument error, a bug
                raise SolverError(f"LAPACK dgemqrt failed (info={info})")
            if not np.shares_memory(out, blk):  # pragma: no cover - f2py copied
                blk[...] = out
        # 2. factor the part on and below the diagonal
        v, t, info = lapack.dgeqrt(width, np.asfortranarray(c[j0:]), overwrite_a=1)
        if info != 0:  # pragma: no cover
            raise SolverError(f"LAPACK dgeqrt failed (info={info})")
        self.r_blocks.append(np.vstack([c[:j0], np.triu(v[:width])]))
        self.panels.append((j0, v, t))
        # 3. update Q^T b
        y = np.asfortranarray(self.qtb[j0:])
        y, info = lapack.dgemqrt(v, t, y, side="L", trans="T", overwrite_c=1)
        self.qtb[j0:] = y
        self.n_cols = j1
        # 4. tail norms ||(Q^T b)[n:]|| for n = j0..j1: reverse cumulative sums
        #    (summed from the bottom, so small tails keep their accuracy)
        sq = y * y
        tails_sq = np.zeros((sq.shape[0] + 1, sq.shape[1]))  # last row: empty tail
        tails_sq[:-1] = np.cumsum(sq[::-1], axis=0)[::-1]
        return np.sqrt(tails_sq[: width + 1])

    def r_factor(self, n: Optional[int] = None) -> np.ndarray:
        """The upper-triangular n x n factor R (a new Fortran array)."""
        n = self.n_cols if n is None else n
        if not 0 <= n <= self.n_cols:
            raise ValueError(f"n must be in [0, {self.n_cols}]")
        r = np.zeros((n, n), order="F")
        for (j0, _, _), blk in zip(self.panels, self.r_blocks):
            if j0 >= n:
                break
            w = min(blk.shape[1], n - j0)
            r[: min(blk.shape[0], n), j0:j0 + w] = blk[:n, :w]
        return r

    def r_diagonal(self, n: Optional[int] = None) -> np.ndarray:
        """The first ``n`` diagonal entries of R."""
        n = self.n_cols if n is None else n
        d = [np.diag(blk[j0:]) for (j0, _, _), blk in zip(self.panels, self.r_blocks)]
        return np.concatenate(d)[:n] if d else np.zeros(0)

    def solve(self, n: int) -> np.ndarray:
        """Least-squares solution using the first ``n`` columns: R x = (Q^T b)[:n]."""
        if n == 0:
            return np.zeros((0, self.qtb.shape[1]))
        x, info = lapack.dtrtrs(self.r_factor(n), self.qtb[:n])
        if info > 0:
            raise SolverError(
                f"the least-squares system is singular: R[{info - 1},{info - 1}] = 0 "
                f"(linearly dependent basis functions)")
        if info < 0:  # pragma: no cover
            raise SolverError(f"LAPACK dtrtrs failed (info={info})")
        return x


def blocked_qr(a: np.ndarray, b: np.ndarray, panel: int = IQR_PANEL_COLUMNS):
    """Blocked incremental QR of a prebuilt matrix with all its columns.

    Returns ``(qr, tails)`` where ``qr`` is the :class:`IncrementalQR` state and
    ``tails[n] = ||(Q^T b)[n:]||`` for ``n = 0..ncols``.  Used by tests (oracle:
    ``scipy.linalg.qr``) and the benchmark; the RBF fit builds its columns
    lazily instead.
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if b.ndim == 1:
        b = b[:, None]
    qr = IncrementalQR(a.shape[0], a.shape[1], b)
    tails = [None]
    j = 0
    while j < a.shape[1]:
        w = min(panel, a.shape[1] - j)
        qr.panel(w)[...] = a[:, j:j + w]
        t = qr.add_panel()
        if tails[0] is None:
            tails[0] = t[:1]
        tails.append(t[1:])
        j += w
    if tails[0] is None:
        tails[0] = np.sqrt(np.sum(b * b, axis=0))[None, :]
    return qr, np.concatenate(tails, axis=0)


# ---------------------------------------------------------------------------
# the fitted function
# ---------------------------------------------------------------------------

@dataclass
class _FitInfo:
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


class TriharmonicRBF:
    """A fitted triharmonic RBF ``R^3 -> R^k``; build it with :meth:`fit`.

    Attributes
    ----------
    centers : (n, 3) array, original coordinates (farthest-point order for IQR)
    center_indices : (n,) indices of the centers into the ``points`` passed to fit
    n_centers : int
    weights : (n, k) RBF weights, in normalised coordinates (float64)
    poly_coeffs : (10, k) monomial coefficients in normalised coordinates, or
        None when the polynomial was dropped
    polynomial : bool, False when the polynomial was dropped
    shift, scale : the normalisation ``xn = (x - shift) / scale``
    method : "lu" or "iqr", the method actually used
    residual : float, max over columns of ``||f(x_i) - b_i|| / ||b||``: the
        residual the returned weights achieve, evaluated at *every* constraint
        point passed to fit (merged duplicates included; 2-norms over the
        points, so it is scale-free and independent of m; absolute for an
        all-zero column).  It exposes what the solver's bookkeeping cannot
        see, e.g. near-duplicate points with different values.
    residuals : (k,) the same per column
    solver_residual : float, the solver's own figure in the same measure:
        ``||A x - b|| / ||b||`` of the system incl. the 10 side-condition
        rows (LU), or the QR tail norm the IQR stopped at
    residual_history : (n_centers + 1, k) the IQR's stopping residual
        ``||(Q^T b)[n:]|| / ||b||`` with 0, 1, ..., n_centers centers (None
        for LU).  Non-increasing: the QR tail norms are monotone in exact
        arithmetic and the stored history is clamped with a running minimum
        against rounding-level wiggles across panels.
    notes : list of str, every decision taken (method, polynomial dropped,
        duplicates merged, max_centers reached, ...)
    message : str, ``"; ".join(notes)``
    """

    def __init__(self, *, centers_n, weights, poly_coeffs, shift, scale,
                 center_indices, info: _FitInfo):
        self._centers_n = np.ascontiguousarray(centers_n, dtype=np.float64)
        self.weights = np.ascontiguousarray(weights, dtype=np.float64)
        self.poly_coeffs = None if poly_coeffs is None else np.ascontiguousarray(poly_coeffs)
        self.shift = np.asarray(shift, dtype=np.float64)
        self.scale = float(scale)
        self.center_indices = np.asarray(center_indices, dtype=np.intp)
        self.centers = self._centers_n * self.scale + self.shift
        self.method = info.method
        self.polynomial = info.polynomial
        self.residuals = info.residuals
        self.residual = float(np.max(info.residuals)) if info.residuals.size else 0.0
        self.solver_residual = self.residual
        self.residual_history = info.residual_history
        self.notes = list(info.notes)
        self.n_constraints = info.n_constraints
        self.n_input_constraints = info.n_input_constraints
        self.tol = info.tol
        self.rcond = info.rcond
        self.fit_seconds = info.seconds
        k = self.weights.shape[1]
        c = self._centers_n
        # [W, c_x W, c_y W, c_z W]: one GEMM with the distance matrix gives
        # sum_j w_j r_ij and sum_j w_j r_ij c_jd for the gradient
        self._centers_aug = augmented_centers(self._centers_n)
        self._poly_grad_coeffs = (None if self.poly_coeffs is None
                                  else poly_gradient_coefficients(self.poly_coeffs))
        self._grad_weights = np.ascontiguousarray(np.concatenate(
            [self.weights] + [c[:, d:d + 1] * self.weights for d in range(3)], axis=1))
        self._k = k

    # -- summary ---------------------------------------------------------
    @property
    def n_centers(self) -> int:
        return self._centers_n.shape[0]

    @property
    def n_outputs(self) -> int:
        return self._k

    @property
    def message(self) -> str:
        return "; ".join(self.notes)

    def __repr__(self) -> str:
        return (f"TriharmonicRBF(method={self.method!r}, n_centers={self.n_centers}, "
                f"n_constraints={self.n_constraints}, k={self._k}, "
                f"polynomial={self.polynomial}, residual={self.residual:.3g})")

    # -- fitting -----------------------------------------------------------
    @classmethod
    def fit(cls, points, values, method: str = "auto", tol: float = IQR_DEFAULT_TOL,
            max_centers: Optional[int] = None,
            progress: Optional[ProgressFn] = None) -> "TriharmonicRBF":
        """Fit ``f`` with ``f(points[i]) = values[i]`` (exactly or to ``tol``).

        Parameters
        ----------
        points : (m, 3) constraint positions, finite, m >= 1.
        values : (m, k) constraint values (e.g. displacements, k = 3, or the
            columns of the basis right-hand sides of Sect. 6), finite.
        method : "lu" — the exact square system (3), every constraint a
            center, solved by LAPACK LU with partial pivoting (dgetrf/dgetrs,
            like the paper).  "iqr" — the incremental least-squares QR of
            Sect. 5: centers in farthest-point order, polynomial columns
            first, 10 extra rows carrying the side conditions P^T w = 0,
            blocked Householder panels of IQR_PANEL_COLUMNS columns; stops at
            the first center count whose residual is below ``tol`` for every
            column.  "auto" — "lu" when m <= AUTO_EXACT_MAX_CONSTRAINTS and
            ``max_centers`` does not ask for fewer centers than m, else "iqr".
            The threshold is where the dense solve stops being cheap and IQR
            starts to win: measured here (2 cores, OpenBLAS, incl. building
            the matrix) the LU fit takes 0.03-0.1 s at m=1000, 0.4 s at
            m=3000 (1.3 s with the machine loaded) and 1.6-2.5 s at m=5000,
            growing as m^3; IQR costs O(m n^2) for n centres, and at the
            default tol needs 60-97% of the constraints as centres on
            realistic edits (docs/PERFORMANCE.md).  Below ~3000 the exact
            answer costs under half a second, so it is preferred; above it
            LU's m^3 and (m + 10)^2 memory dominate.
        tol : the relative residual ``||Ax - b|| / ||b||`` (per column,
            2-norms over the constraint rows) at which IQR stops (default
            IQR_DEFAULT_TOL).  Unlike the paper's ``/(m ||b||)`` it does not
            loosen as m grows; the default keeps the IQR deformation within
            0.5% of the handle displacement of the exact one up to m = 20,000
            (docs/PERFORMANCE.md).  0 means "use every center" (up to
            ``max_centers``).  Ignored by "lu".
        max_centers : cap on the number of RBF centers for IQR (the fit stops
            there even if ``tol`` is not reached; a note says so).
            ``method="lu"`` with ``max_centers < m`` is a ParameterError.
        progress : optional ``progress(stage, fraction)`` callback, called
            once per QR panel.

        Duplicates: constraint points closer than DUPLICATE_POINT_REL times
        the bounding-box diagonal are merged (first one kept) when their
        values agree within DUPLICATE_VALUE_RTOL, and raise SolverError
        otherwise (the interpolation problem has no solution).

        Polynomial: dropped (as in the paper, Sect. 4) when m < 10 or the
        normalised 10-column monomial matrix P has
        ``s_min / s_max < POLY_RANK_RTOL`` (all constraints on a quadric,
        e.g. a sphere or a plane); ``polynomial`` is False and a note says why.

        Raises ParameterError for bad arguments and SolverError when the
        system cannot be solved (conflicting duplicates; a singular system,
        e.g. a single constraint point, whose kernel matrix is [0]).
        """
        t_start = time.perf_counter()
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

        # polynomial or not
        use_poly = True
        if m < N_POLY:
            use_poly = False
            notes.append(f"polynomial dropped: {m} < {N_POLY} constraints cannot determine a quadratic")
        else:
            s = np.linalg.svd(poly_matrix(pts_n), compute_uv=False)
            ratio = s[-1] / s[0]
            if not ratio > POLY_RANK_RTOL:
                use_poly = False
                notes.append(f"polynomial dropped: constraints lie on a quadric "
                             f"(monomial matrix s_min/s_max = {ratio:.1e} < {POLY_RANK_RTOL:g})")
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
            w, q, idx, residuals, rcond = _fit_lu(pts_n, vals, use_poly)
            history = None
            head.append(f"lu: exact solve with all {m} constraints as centers, "
                        f"rcond {rcond:.1e}")
        else:
            rcond = None
            w, q, idx, residuals, history, iqr_notes = _fit_iqr(
                pts_n, vals, use_poly, tol, max_centers, progress)
            head.extend(iqr_notes)
        notes = head + notes
        report(progress, PROGRESS_STAGE, 1.0)

        info = _FitInfo(method=used, polynomial=use_poly, residuals=residuals,
                        residual_history=history, notes=notes, n_constraints=m,
                        n_input_constraints=m_in, tol=tol, rcond=rcond)
        f = cls(centers_n=pts_n[idx], weights=w, poly_coeffs=q, shift=shift, scale=scale,
                center_indices=keep[idx], info=info)
        # the honest residual: what the returned weights achieve at every input
        # constraint (the solver's own figure is blind to rounding, e.g. when
        # near-duplicate points with different values make the system singular)
        f._set_achieved(achieved_residuals(f, pts, vals_in), residuals)
        f.fit_seconds = time.perf_counter() - t_start
        return f

    def _set_achieved(self, achieved: np.ndarray, solver: np.ndarray) -> None:
        self.residuals = achieved
        self.residual = float(np.max(achieved)) if achieved.size else 0.0
        self.solver_residual = float(np.max(solver)) if solver.size else 0.0
        self.notes.append(f"residual {self.residual:.2g} (||f(x_i) - b_i|| / ||b|| over all "
                          f"{self.n_input_constraints} constraints)")
        limit = max(self.tol if self.method == "iqr" else 0.0, RESIDUAL_NOTE_MIN) * RESIDUAL_NOTE_FACTOR
        if self.residual > limit:
            self.notes.append(
                f"the fitted field misses its constraints by {self.residual:.2g} relative "
                f"(the solver's own figure: {self.solver_residual:.2g}): the system is "
                "ill-conditioned (near-duplicate constraint points with different values?)")

    # -- evaluation --------------------------------------------------------
    def _normalise_query(self, x) -> np.ndarray:
        xa = _as_float_array("x", x)
        if xa.ndim != 2 or xa.shape[1] != 3:
            raise ParameterError("x", f"expected shape (N, 3), got {xa.shape}")
        return (xa - self.shift) / self.scale

    def _chunk_rows(self) -> int:
        per_row = 8 * max(1, self.n_centers)
        return int(max(1, min(EVAL_CHUNK_ROWS, EVAL_CHUNK_MAX_BYTES // per_row)))

    def _eval(self, x, want_values: bool, want_grad: bool):
        xn = self._normalise_query(x)
        n_pts, k = xn.shape[0], self._k
        vals = np.empty((n_pts, k)) if want_values else None
        grads = np.empty((n_pts, k, 3)) if want_grad else None
        step = self._chunk_rows()
        starts = list(range(0, n_pts, step))

        def one_chunk(s):
            self._eval_chunk(xn[s:s + step], None if vals is None else vals[s:s + step],
                             None if grads is None else grads[s:s + step])

        # numpy's element-wise passes run on one core and release the GIL, so
        # chunks are spread over EVAL_THREADS threads (each writes its own rows)
        workers = min(EVAL_THREADS, len(starts))
        if workers > 1:
            with ThreadPoolExecutor(max_workers=workers) as pool:
                list(pool.map(one_chunk, starts))
        else:
            for s in starts:
                one_chunk(s)
        return vals, grads

    def _eval_chunk(self, xc, v, g):
        """Fill values ``v`` (rows, k) and/or gradients ``g`` (rows, k, 3) at
        normalised points ``xc`` (rows, 3)."""
        k = self._k
        if self.n_centers:
            d2 = evaluation_squared_distances(xc, self._centers_aug)
            r = np.sqrt(d2)
        if v is not None:
            if self.n_centers:
                d2 *= r  # Phi = r^3, in place
                np.matmul(d2, self.weights, out=v)
            else:
                v[...] = 0.0
            if self.poly_coeffs is not None:
                v += poly_matrix(xc) @ self.poly_coeffs
        if g is not None:
            if self.n_centers:
                # grad = 3 sum_j w_j r_ij (x_i - c_j) = 3 (x_i S0 - S_d)
                sums = r @ self._grad_weights  # (rows, 4k)
                for d in range(3):
                    g[:, :, d] = 3.0 * (xc[:, d:d + 1] * sums[:, :k]
                                        - sums[:, (d + 1) * k:(d + 2) * k])
            else:
                g[...] = 0.0
            if self.poly_coeffs is not None:
                # the quadratic's gradient is affine in x: [1, x, y, z] @ G_d
                x1 = np.empty((len(xc), 4))
                x1[:, 0] = 1.0
                x1[:, 1:] = xc
                for d in range(3):
                    g[:, :, d] += x1 @ self._poly_grad_coeffs[d]
            g /= self.scale  # chain rule: d/dx = (1/scale) d/dxn

    def __call__(self, x) -> np.ndarray:
        """Values at ``x`` (N, 3) -> (N, k), evaluated in bounded-memory chunks."""
        return self._eval(x, True, False)[0]

    def gradient(self, x) -> np.ndarray:
        """Gradients at ``x`` (N, 3) -> (N, k, 3); ``[i, c, d] = d f_c / d x_d``."""
        return self._eval(x, False, True)[1]

    def value_and_gradient(self, x):
        """``(values (N, k), gradients (N, k, 3))`` with one distance matrix per chunk."""
        return self._eval(x, True, True)


# ---------------------------------------------------------------------------
# the two solvers (normalised coordinates)
# ---------------------------------------------------------------------------

def _relative_residuals(res_norm: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Scale-free ``res_norm / ||b||`` per column (both 2-norms over the m
    constraints, so a uniform error e on values of RMS size s gives e / s
    whatever m); the absolute ``res_norm`` where ``b`` is identically 0."""
    bn = np.linalg.norm(b, axis=0)
    nz = bn > 0
    out = np.array(res_norm, dtype=np.float64, copy=True)
    out[..., nz] = out[..., nz] / bn[nz]
    return out


def achieved_residuals(f: "TriharmonicRBF", points: np.ndarray, values: np.ndarray) -> np.ndarray:
    """(k,) ``||f(points) - values|| / ||values||`` per column: the residual
    the fitted weights really achieve, evaluated at every constraint point
    (in bounded-memory chunks), whatever the solver's own bookkeeping says.

    Args:
        f: the fitted RBF.
        points: (m, 3) constraint points (model units).
        values: (m, k) their values.
    """
    res_sq = np.zeros(values.shape[1])
    step = max(1, f._chunk_rows())
    for s in range(0, len(points), step):
        d = f(points[s:s + step]) - values[s:s + step]
        res_sq += np.einsum("ij,ij->j", d, d)
    return _relative_residuals(np.sqrt(res_sq), values)


def _fit_lu(pts_n, vals, use_poly):
    m, k = vals.shape
    npoly = N_POLY if use_poly else 0
    size = m + npoly
    a = np.zeros((size, size), order="F")
    kernel_matrix(pts_n, pts_n, out=a[:m, :m])
    if use_poly:
        p = poly_matrix(pts_n)
        a[:m, m:] = p
        a[m:, :m] = p.T
    rhs = np.zeros((size, k))
    rhs[:m] = vals
    anorm = float(np.max(np.sum(np.abs(a), axis=0)))
    lu, piv, info = lapack.dgetrf(a, overwrite_a=0)
    if info > 0:
        raise SolverError(
            f"the exact RBF system is singular (zero pivot at {info - 1}); "
            "use method='iqr' or remove degenerate constraints")
    rcond, _ = lapack.dgecon(lu, anorm, norm="1")
    if not rcond >= LU_MIN_RCOND:
        raise SolverError(
            f"the exact RBF system is numerically singular (rcond {rcond:.1e} < "
            f"{LU_MIN_RCOND:g}); use method='iqr' or remove near-duplicate constraints")
    x, info = lapack.dgetrs(lu, piv, rhs)
    res = np.linalg.norm(a @ x - rhs, axis=0)
    residuals = _relative_residuals(res, vals)
    w = x[:m]
    q = x[m:] if use_poly else None
    return w, q, np.arange(m), residuals, float(rcond)


def _fit_iqr(pts_n, vals, use_poly, tol, max_centers, progress):
    m, k = vals.shape
    npoly = N_POLY if use_poly else 0
    n_rows = m + npoly
    cap = m if max_centers is None else min(max_centers, m)
    max_cols = npoly + cap
    rhs = np.zeros((n_rows, k))
    rhs[:m] = vals
    qr = IncrementalQR(n_rows, max_cols, rhs)
    sampler = FarthestPointSampler(pts_n)
    p_all = poly_matrix(pts_n) if use_poly else None
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
    q = x[:npoly] if use_poly else None
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
