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

import time
from concurrent.futures import ThreadPoolExecutor
from typing import Optional

import numpy as np

from splatedit.deform.kernels import (
    augmented_centers,
    evaluation_squared_distances,
    poly_gradient_coefficients,
    poly_matrix,
)
from splatedit.deform.qr import IncrementalQR, blocked_qr
from splatedit.deform.rbf_fit import (
    METHODS,
    PROGRESS_STAGE,
    FitSolution,
    as_float_array,
    FitInfo,
    relative_residuals,
    solve_constraints,
)
from splatedit.blas import single_blas_thread
from splatedit.errors import ParameterError
from splatedit.progress import ProgressFn
from splatedit.tolerances import (
    EVAL_CHUNK_MAX_BYTES,
    EVAL_CHUNK_ROWS,
    EVAL_THREADS,
    IQR_DEFAULT_TOL,
    POLY_CHECK_FACTOR,
    POLY_CHECK_RTOL,
    RESIDUAL_NOTE_FACTOR,
    RESIDUAL_NOTE_MIN,
)

#: the QR and the fit drivers live in splatedit.deform.qr / .rbf_fit; their
#: public names stay importable from here
__all__ = ["METHODS", "PROGRESS_STAGE", "IncrementalQR", "TriharmonicRBF", "achieved_residuals",
           "blocked_qr"]


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
                 center_indices, info: FitInfo):
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
        #: terms of the quadratic kept (0..10; fewer where the constraints lie
        #: on a quadric up to their precision), the relative singular values
        #: of its affine and quadratic blocks (None below 10 constraints) and
        #: the smallest one kept
        self.poly_rank = info.poly_rank
        self.poly_singular = info.poly_singular
        self.poly_weakest = info.poly_weakest
        self.coordinate_precision = info.precision * self.scale
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
            progress: Optional[ProgressFn] = None, probe=None) -> "TriharmonicRBF":
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

        Polynomial: by its numerical rank on the constraint set.  The paper
        (Sect. 4) drops it when all constraints lie on a quadric (system (3)
        is singular then); a decision on exact singularity fails for points a
        rounding away from a quadric (spheres, cylinders, cones, planes stored
        in float32 or with a few decimals): the quadric's coefficient is then
        fitted to the rounding, and the field's normal derivative explodes
        (a 2,000-point sphere at 7 decimals: 3x3 Jacobian stretch 218x, PCA
        splat axes 4.9x; docs/PERFORMANCE.md).  So the column-scaled monomial
        matrix is factored by an SVD (:func:`~splatedit.deform.rbf_fit.polynomial_basis`)
        and only the directions whose singular value stands above
        POLY_NOISE_FACTOR times the first-order effect of the coordinates'
        precision (:func:`~splatedit.deform.rbf_fit.coordinate_precision`:
        half the decimal grid they lie on, else float32 rounding) and above
        POLY_RANK_RTOL are kept: ``poly_rank`` of 10 terms (9 on a sphere,
        cylinder or cone, 6 on a plane, 0 below 10 constraints), the side
        conditions ``P_r^T w = 0`` on those only, in every method.  Then the
        fit is checked rather than trusted: when a kept direction is weak
        (s/s_max < POLY_CHECK_RTOL) the fit without the weak directions is
        computed too, and taken when the polynomial one's largest Jacobian
        (at the constraints and the ``probe`` points) is POLY_CHECK_FACTOR
        times steeper and it meets its constraints as well; a note says
        which.  ``polynomial`` is False when no term is kept.

        probe : optional (p, 3) points (e.g. free support splats) where that
            check also measures the Jacobian.

        Raises ParameterError for bad arguments and SolverError when the
        system cannot be solved (conflicting duplicates; a singular system,
        e.g. a single constraint point, whose kernel matrix is [0]).
        """
        t_start = time.perf_counter()
        args = (points, values, method, tol, max_centers, progress)
        sol: FitSolution = solve_constraints(*args)
        f = cls._from_solution(sol)
        info = sol.info
        if info.poly_rank and info.poly_weakest < POLY_CHECK_RTOL:
            # weak polynomial directions: check the fit against the one without
            # them rather than trusting it (near-quadric constraints with more
            # relief than their rounding, e.g. noisy float64 data)
            g = cls._from_solution(solve_constraints(*args, poly_rtol=POLY_CHECK_RTOL))
            f = _checked_choice(f, g, sol.points, probe)
        f.fit_seconds = time.perf_counter() - t_start
        return f

    @classmethod
    def _from_solution(cls, sol: FitSolution) -> "TriharmonicRBF":
        f = cls(centers_n=sol.centers_n, weights=sol.weights, poly_coeffs=sol.poly_coeffs,
                shift=sol.shift, scale=sol.scale, center_indices=sol.center_indices,
                info=sol.info)
        # the honest residual: what the returned weights achieve at every input
        # constraint (the solver's own figure is blind to rounding, e.g. when
        # near-duplicate points with different values make the system singular)
        f._set_achieved(achieved_residuals(f, sol.points, sol.values), sol.info.residuals)
        return f

    def _residual_limit(self) -> float:
        """The achieved residual above which a note calls the fit ill-conditioned."""
        return max(self.tol if self.method == "iqr" else 0.0, RESIDUAL_NOTE_MIN) * RESIDUAL_NOTE_FACTOR

    def _set_achieved(self, achieved: np.ndarray, solver: np.ndarray) -> None:
        self.residuals = achieved
        self.residual = float(np.max(achieved)) if achieved.size else 0.0
        self.solver_residual = float(np.max(solver)) if solver.size else 0.0
        self.notes.append(f"residual {self.residual:.2g} (||f(x_i) - b_i|| / ||b|| over all "
                          f"{self.n_input_constraints} constraints)")
        if self.residual > self._residual_limit():
            self.notes.append(
                f"the fitted field misses its constraints by {self.residual:.2g} relative "
                f"(the solver's own figure: {self.solver_residual:.2g}): the system is "
                "ill-conditioned (near-duplicate constraint points with different values?)")

    # -- evaluation --------------------------------------------------------
    def _normalise_query(self, x) -> np.ndarray:
        xa = as_float_array("x", x)
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
            # those threads already fill the cores: OpenBLAS's own threads on top
            # of them oversubscribe (4.5-9x slower at a 1M support, see docs/PERFORMANCE.md)
            with single_blas_thread(), ThreadPoolExecutor(max_workers=workers) as pool:
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

    def value_and_gradient_fast(self, x, *, tol: float, value_scale: float):
        """``(values (N, k), gradients (N, k, 3), stats)`` by far-field
        interpolation (:func:`splatedit.deform.fast_eval.evaluate`): within
        about ``tol * value_scale`` of :meth:`value_and_gradient` (values, and
        gradients times the normalisation ``scale``), checked per box.
        ``tol = 0`` evaluates every point directly (exact)."""
        from splatedit.deform.fast_eval import RBFField, evaluate
        xn = self._normalise_query(x)
        fld = RBFField(self._centers_n, self.weights, self.poly_coeffs)
        out, stats = evaluate(fld, xn, tol=tol, value_scale=value_scale, far_field=tol > 0)
        k = self._k
        grads = out[:, k:].reshape(len(xn), 3, k).transpose(0, 2, 1) / self.scale
        return out[:, :k], grads, stats


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
    return relative_residuals(np.sqrt(res_sq), values)


def field_roughness(f: "TriharmonicRBF", points: np.ndarray) -> float:
    """The largest Frobenius norm of the fitted field's Jacobian (k, 3) over
    ``points`` (N, 3), model units: how steep the field gets, the quantity a
    wild polynomial term (a quadric's coefficient fitted to rounding) blows
    up in the directions the constraints do not see (a surface's normal)."""
    out = 0.0
    step = max(1, f._chunk_rows())
    for s in range(0, len(points), step):
        g = f.gradient(points[s:s + step])
        out = max(out, float(np.sqrt(np.max(np.einsum("nkd,nkd->n", g, g)))))
    return out


def _checked_choice(f: "TriharmonicRBF", g: "TriharmonicRBF", points: np.ndarray,
                    probe) -> "TriharmonicRBF":
    """``f`` (the polynomial with weak directions) or ``g`` (without them):
    ``g`` when ``f`` is POLY_CHECK_FACTOR times steeper (:func:`field_roughness`
    at the constraints and the ``probe`` points) and ``g`` meets its
    constraints as well (achieved residual within its note limit or ``f``'s)."""
    pts = points if probe is None else np.vstack([points, as_float_array("probe", probe).reshape(-1, 3)])
    rf, rg = field_roughness(f, pts), field_roughness(g, pts)
    ok = g.residual <= max(f.residual, g._residual_limit())
    weak = f.poly_rank - g.poly_rank
    what = (f"checked against the fit without its {weak} weak polynomial direction(s) "
            f"(s/s_max < {POLY_CHECK_RTOL:g}): largest Jacobian {rf:.3g} vs {rg:.3g}")
    if ok and rf > POLY_CHECK_FACTOR * rg:
        g.notes.append(what + f": the polynomial's weak directions make the field "
                       f"{rf / rg:.3g}x steeper, dropped")
        return g
    f.notes.append(what + ": kept")
    return f
