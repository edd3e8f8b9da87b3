"""Precomputed deformation bases B, Bx, By, Bz (paper Sect. 6 and 7).

One :class:`TriharmonicRBF` is fitted with all K columns of the affine
weights ``M`` as right-hand sides at once (fixed band: 0): 4 per rigid handle
(its frame's affine coordinates), k + 1 per control curve (the non-negative
displacement weights of its samples, paper Sect. 6 end), in the block layout of the
constraint groups (handles first, then curves).  Evaluating it and its
gradient at every support splat gives the (N, K) bases with which, for
control-point displacements ``dC`` (K, 3):

    p'      = p + B dC
    J[i, j] = delta_ij + sum_k dC[k, i] * Bj[k],     Bj in (Bx, By, Bz)
    u'      = J u,   v' = J v     (so the normal follows J^-T n)

Free splats (support minus handles) use the RBF; handle splats use their exact
affine coordinates (they move rigidly with their handle) and the constant
gradient of those coordinates, and zeros in every other group's columns;
splats outside the support are not in the basis (``indices`` lists the
support splats, sorted) and are copied bitwise.  Curves have no member splats:
their samples are constraint points only.

CPU hot path (``apply``): :mod:`splatedit.deform.apply_plan` (three cached
(N, K + 3) arrays in run-plan order, three chunked GEMMs per frame).
"""

from __future__ import annotations

import copy
import time

import numpy as np

from splatedit.deform.apply_plan import APPLY_STAGE, CHECK_STAGE, apply_hot_path, build_hot_path
from splatedit.deform.curve_frames import CurveFrameDisplacement, curve_frame_displacement, frames_terms
from splatedit.deform.constraints import Constraints, build_constraints
from splatedit.deform.frames import affine_coordinate_gradients, affine_coordinates
from splatedit.deform.modes import DeformationMode
from splatedit.deform.rbf import TriharmonicRBF
from splatedit.deform.rotation import blend_jacobians, blend_terms, handle_blocks, split_displacement
from splatedit.deform.rotation_centre import StretchProbe, rotation_displacement
from splatedit.deform.transform import apply_affine, as_affine
from splatedit.blas import single_blas_thread
from splatedit.errors import ParameterError
from splatedit.progress import report
from splatedit.tolerances import BAND_RINGS, FAST_EVAL_TOL, IQR_DEFAULT_TOL, POLY_CHECK_PROBE_SPLATS

#: progress stage name of the basis evaluation
PROGRESS_STAGE = "precomputing deformation basis"
#: support splats per chunk when computing the Jacobians
_BASIS_CHUNK = 65536
#: free splats per call of the far-field basis evaluation (its (rows, 4K)
#: float64 result and box tree; larger calls make larger far-field boxes)
_FAST_CHUNK = 1 << 18


def _spatial_chunks(rows: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``rows`` reordered by a coarse 16^3 grid over ``points`` (x-major), so
    that consecutive evaluation chunks are compact slabs of the support
    whatever the file order (a shuffled 400k support evaluated in two chunks
    computed 20% of the splat-centre pairs instead of 12%)."""
    lo = points.min(axis=0)
    ext = float(np.max(points.max(axis=0) - lo)) or 1.0
    g = np.minimum((points - lo) * (16.0 / ext), 15.0).astype(np.int64)
    return rows[np.argsort((g[:, 0] * 16 + g[:, 1]) * 16 + g[:, 2], kind="stable")]


def deformed_copy(cloud, arrays, validate: bool, progress=None):
    """A copy of ``cloud`` with the deformed ``(positions, u, v)`` arrays
    (no ``__init__``: skips the O(n) validation on the hot path), checked
    when ``validate``."""
    out = copy.copy(cloud)
    out.positions, out.u, out.v = arrays
    if validate:
        report(progress, CHECK_STAGE, 0.0)
        out.validate()
        report(progress, CHECK_STAGE, 1.0)
    return out


class DeformationBasis:
    """Precomputed linear deformation bases of one edit (support + handles
    and/or control curves).

    Attributes:
        constraints: the :class:`~splatedit.deform.constraints.Constraints`.
        rbf: the fitted :class:`~splatedit.deform.rbf.TriharmonicRBF`
            (K outputs: the affine-weight fields).
        indices: (N,) sorted cloud indices of the support splats (basis rows).
        B, Bx, By, Bz: (N, K) float64 bases (views of one packed array),
            K = 4 h + sum over curves of (k + 1).
        control_frames: (h, 4, 3) control frames C of the handles.
        stats: dict of fit statistics: ``n_constraints`` (m), ``n_centers``,
            ``residual``, ``method``, ``polynomial``, ``closure_seconds``,
            ``closure_added`` (0 here; a caller that closed the selection
            first fills both in), ``n_conflicts``
            (fixed splats dropped next to handle bands), ``constraints_seconds``
            (bands and control frames), ``fit_seconds`` (the RBF solve),
            ``basis_seconds``, ``n_support``, ``n_free``, ``eval_tol``,
            ``eval_pairs`` (splat-centre pairs the basis evaluation computed;
            exact evaluation: n_free * n_centers), ``eval_interpolated`` (free
            splats whose far field was interpolated), ``n_fixed_band``,
            ``n_handle_band``, ``n_curve_samples``, ``n_curve_dropped``,
            ``spacing``, ``message``.
    """

    def __init__(self, constraints: Constraints, rbf, pack: np.ndarray, stats: dict):
        self.constraints = constraints
        self.rbf = rbf
        self.indices = constraints.support_index
        self._pack = pack  # (N, 4, K): B, Bx, By, Bz
        self.stats = stats
        self._cpu = None  # lazily built hot-path arrays, see _cpu_arrays
        self.stretch_probe = None  # free splats where rotation centres are compared (fit() sets it)
        self.support_positions = None  # (N, 3) positions of the support splats (fit() sets it; curve frames)
        #: move-independent terms of curve frames at the support (splatedit.deform.curve_frames)
        self.frame_cache: dict = {}

    # ------------------------------------------------------------ building
    @classmethod
    def fit(cls, cloud, support, handles=(), *, curves=(), method: str = "auto",
            tol: float = IQR_DEFAULT_TOL, max_centers: int | None = None,
            rings: float = BAND_RINGS, spacing: float | None = None,
            fill_holes: bool = False, graph=None, progress=None,
            eval_tol: float = FAST_EVAL_TOL) -> "DeformationBasis":
        """Build constraints, fit one RBF to all group columns, evaluate bases.

        Args:
            cloud: the base :class:`~splatedit.model.cloud.SplatCloud`.
            support, handles: masks (see :func:`build_constraints`).
            curves: :class:`~splatedit.deform.curves.ControlCurve` objects (or
                (k + 1, 3) picked points), see :func:`build_constraints`.
            method, tol, max_centers: passed to :meth:`TriharmonicRBF.fit`
                ("auto" = exact LU up to AUTO_EXACT_MAX_CONSTRAINTS, else IQR).
            rings, spacing: band thickness (see :func:`build_constraints`).
            fill_holes: must be False (kept so that old calls saying so
                still run).  The fit uses the masks as given: selection policy
                (closing a painted selection, :mod:`splatedit.select.closure`)
                is the caller's, e.g. ``closed_masks(cloud, support, handles)``.
            graph: unused (the closure's graph belonged here before).
            progress: optional ``progress(stage, fraction)``.
            eval_tol: the basis values and gradients at the free splats are
                evaluated by far-field interpolation
                (:mod:`splatedit.deform.fast_eval`) within about this times
                the largest constraint value of the exact float64 RBF (checked
                per box); 0 evaluates them exactly (every splat, every centre).
        Raises:
            ParameterError / SolverError from the constraints and the fit.
        """
        t0 = time.perf_counter()
        if fill_holes:
            raise ParameterError("fill_holes", "the fit takes the selection as given: close it first with "
                                 "splatedit.select.closure.closed_masks (edit scripts and the editor do)")
        t_closure = time.perf_counter()
        con = build_constraints(cloud, support, handles, curves=curves, rings=rings,
                                spacing=spacing)
        t_con = time.perf_counter()
        free = con.free_index
        # the fit's LAPACK calls are small (QR panels of 128 columns, an LU of
        # m <= 3000): OpenBLAS's own threads cost far more than they gain on the
        # shared 2-core machine (load 10: an IQR fit of m = 2069, 1100 centres
        # 8.0 s wall / 3.7 s CPU with them, 0.48 / 0.25 s on one thread; the LU
        # at m = 2900 2.9 s against 1.3-1.9 s), so they are held to one thread
        with single_blas_thread():
            rbf = TriharmonicRBF.fit(con.points, con.values, method=method, tol=tol,
                                     max_centers=max_centers, progress=progress,
                                     probe=cloud.positions[free[::max(1, len(free) // POLY_CHECK_PROBE_SPLATS)]])
        t1 = time.perf_counter()

        pos = cloud.positions
        idx = con.support_index
        n_sup, k = len(idx), con.n_columns
        pack = np.zeros((n_sup, 4, k))
        # handle splats: exact affine coordinates and their constant gradients
        for g, grp in enumerate(con.groups):
            if grp.kind != "handle":
                continue  # curves have no member splats
            cols = con.columns(g)
            rows = np.searchsorted(idx, grp.member_index)
            pack[rows, 0, cols] = affine_coordinates(pos[grp.member_index], grp.controls)
            grad = affine_coordinate_gradients(grp.controls)  # (4, 3)
            for d in range(3):
                pack[rows, 1 + d, cols] = grad[:, d]
        # free splats: the RBF and its gradient
        free_rows = np.searchsorted(idx, con.free_index)
        n_free = len(free_rows)
        report(progress, PROGRESS_STAGE, 0.0)
        # far-field interpolation within eval_tol of the largest constraint value
        # (splatedit.deform.fast_eval); chunks bound the (rows, 4K) temporaries
        value_scale = float(np.max(np.abs(con.values))) if con.values.size else 1.0
        eval_stats = []
        rows = _spatial_chunks(free_rows, pos[idx[free_rows]]) if n_free > _FAST_CHUNK else free_rows
        for s in range(0, n_free, _FAST_CHUNK):
            r = rows[s:s + _FAST_CHUNK]
            val, grad, est = rbf.value_and_gradient_fast(pos[idx[r]], tol=eval_tol,
                                                         value_scale=value_scale)
            eval_stats.append(est)
            pack[r, 0, :] = val
            pack[r, 1:, :] = grad.transpose(0, 2, 1)
            report(progress, PROGRESS_STAGE, (s + len(r)) / n_free)
        t2 = time.perf_counter()
        stats = dict(
            n_constraints=con.n_constraints, n_centers=int(rbf.n_centers),
            residual=float(rbf.residual), method=rbf.method, polynomial=bool(rbf.polynomial),
            closure_seconds=0.0, closure_added=0,
            n_conflicts=sum(c.count for c in con.conflicts),
            constraints_seconds=t_con - t_closure, fit_seconds=t1 - t_con, basis_seconds=t2 - t1,
            n_support=int(n_sup), n_free=int(n_free), eval_tol=float(eval_tol),
            eval_pairs=int(sum(e.pairs for e in eval_stats)),
            eval_interpolated=int(sum(e.n_interpolated for e in eval_stats)),
            n_fixed_band=int(len(con.fixed_index)),
            n_handle_band=[int(len(b)) for b in con.handle_band_index],
            n_curve_samples=[int(len(c.points)) for c in con.curves],
            n_curve_dropped=[int(c.n_dropped) for c in con.curves],
            spacing=float(con.spacing), message=getattr(rbf, "message", ""),
        )
        out = cls(con, rbf, pack, stats)
        out.support_positions = pos[idx].copy()
        if len(free_rows):
            out.stretch_probe = StretchProbe.sample(pack, free_rows, cloud.u[idx[free_rows]],
                                                    cloud.v[idx[free_rows]])
        return out

    # ------------------------------------------------------------ accessors
    @property
    def B(self) -> np.ndarray:
        return self._pack[:, 0, :]

    @property
    def Bx(self) -> np.ndarray:
        return self._pack[:, 1, :]

    @property
    def By(self) -> np.ndarray:
        return self._pack[:, 2, :]

    @property
    def Bz(self) -> np.ndarray:
        return self._pack[:, 3, :]

    @property
    def n_groups(self) -> int:
        """Number of constraint groups (handles + curves)."""
        return len(self.constraints.groups)

    @property
    def n_handles(self) -> int:
        """Number of constraint groups (handles + curves; kept for the
        handle-only callers, see :attr:`n_groups`)."""
        return len(self.constraints.groups)

    @property
    def group_kinds(self) -> list[str]:
        """``"handle"`` or ``"curve"`` per group, in column-block order."""
        return [g.kind for g in self.constraints.groups]

    @property
    def n_columns(self) -> int:
        return self._pack.shape[2]

    @property
    def control_frames(self) -> np.ndarray:
        return self.constraints.control_frames

    def columns_for_group(self, i: int) -> slice:
        """Columns of B (and rows of dC) belonging to group ``i`` (handles
        first, then curves)."""
        return self.constraints.columns(i)

    def columns_for_handle(self, i: int) -> slice:
        """Alias of :meth:`columns_for_group` (group ``i``, handle or curve)."""
        return self.constraints.columns(i)

    def rows_for_gpu(self, handle: int | None = None):
        """``(indices, B, Bx, By, Bz)`` as contiguous float64 arrays.

        ``handle=None``: every support splat, all K columns.  ``handle=i``:
        only group i's columns (4 for a handle, k + 1 for a curve), and only
        the splats they move (the splats of the *other* handles have all-zero
        rows there and are dropped).  The renderer converts to float32.
        """
        if handle is None:
            sub = self._pack
            keep = slice(None)
            ind = self.indices
        else:
            sub = self._pack[:, :, self.columns_for_handle(handle)]
            keep = np.flatnonzero(np.any(sub != 0.0, axis=(1, 2)))
            sub = sub[keep]
            ind = self.indices[keep]
        return (np.array(ind, dtype=np.int64),) + tuple(
            np.ascontiguousarray(sub[:, j, :]) for j in range(4))

    # ----------------------------------------------------------- per frame
    def displacement(self, transforms, mode: DeformationMode = DeformationMode.LINEAR):
        """Control-point displacements ``dC`` (K, 3) from one input per group
        (handles first, then curves, as in :attr:`group_kinds`):

        * handle: a (4, 4) affine map ``m`` (or (3, 4)); ``dC = m(C) - C`` for
          its control frame C;
        * curve: a (k + 1, 3) array ``dq`` of picked-point displacements
          (the curve's controls are its picked points);
        * None: the group does not move.

        A single 2-D array is accepted when there is one group.

        ``mode``: LINEAR (the paper) returns the (K, 3) array; ROTATION returns a
        :class:`~splatedit.deform.rotation.RotationDisplacement` (residual dC
        plus each handle's rotation, see :mod:`splatedit.deform.rotation`)
        when a handle rotates, else the same (K, 3) array as LINEAR (bitwise),
        which :meth:`apply`, :meth:`displacements`, :meth:`jacobians` and the
        renderer take in place of dC.  DETAIL belongs to
        :class:`~splatedit.deform.detail.DetailBasis` (its base deformation is ROTATION).
        """
        mode = DeformationMode(mode)
        if mode is DeformationMode.DETAIL:
            raise ParameterError("mode", "the 'detail' deformation needs a DetailBasis "
                                 "(splatedit.deform.detail.DetailBasis.fit)")
        if isinstance(transforms, np.ndarray) and transforms.ndim == 2:
            transforms = [transforms]
        transforms = list(transforms)
        if mode is DeformationMode.ROTATION and len(transforms) == self.n_groups:
            if "curve" in self.group_kinds:     # moved curves carry their frames
                return curve_frame_displacement(self, transforms)
            return rotation_displacement(self, transforms)
        if len(transforms) != self.n_groups:
            raise ParameterError("transforms", f"need one matrix per handle and one (k + 1, 3) "
                                 f"displacement array per curve ({self.n_groups} groups: "
                                 f"{', '.join(self.group_kinds)}), got {len(transforms)}")
        dc = np.zeros((self.n_columns, 3))
        for i, (t, grp) in enumerate(zip(transforms, self.constraints.groups)):
            if t is None:
                continue
            cols = self.columns_for_group(i)
            if grp.kind == "handle":
                m = as_affine(t, name=f"transforms[{i}]")
                dc[cols] = apply_affine(m, grp.controls) - grp.controls
            else:
                d = np.asarray(t, dtype=np.float64)
                k = grp.n_columns
                if d.shape != (k, 3):
                    raise ParameterError(f"transforms[{i}]", f"curve {i} has {k} control points: "
                                         f"expected a ({k}, 3) displacement array, got shape {d.shape}")
                if not np.isfinite(d).all():
                    raise ParameterError(f"transforms[{i}]", "must be finite")
                dc[cols] = d
        return dc

    def _check_dc(self, dC) -> np.ndarray:
        d = np.asarray(dC, dtype=np.float64)
        if d.shape != (self.n_columns, 3):
            raise ParameterError("dC", f"expected shape ({self.n_columns}, 3), got {d.shape}")
        if not np.isfinite(d).all():
            raise ParameterError("dC", "must be finite")
        return d

    def displacements(self, dC) -> np.ndarray:
        """(N, 3) displacements of the support splats: ``B dC`` (plus the
        blended rotations of a RotationDisplacement, the curves' frame terms
        of a CurveFrameDisplacement)."""
        if isinstance(dC, CurveFrameDisplacement):
            pos = self._support_positions()
            return self.displacements(dC.base()) + frames_terms(dC, self, pos)[0]
        d, rot = split_displacement(dC)
        out = self.B @ self._check_dc(d)
        if rot is not None:
            out += blend_terms(rot, self._pack, handle_blocks(self))[0]
        return out

    def jacobians(self, dC) -> np.ndarray:
        """(N, 3, 3) Jacobians ``J`` of the deformation at the support splats
        (dC: (K, 3) or a RotationDisplacement)."""
        if isinstance(dC, CurveFrameDisplacement):
            out = self.jacobians(dC.base())
            pos = self._support_positions()
            cols = frames_terms(dC, self, pos, list(np.eye(3)[:, None, :].repeat(len(pos), 1)))[1]
            out += np.stack(cols, axis=2)
            return out
        d, rot = split_displacement(dC)
        d = self._check_dc(d)
        blocks = None if rot is None else handle_blocks(self)
        n = self._pack.shape[0]
        out = np.empty((n, 3, 3))
        # in chunks: besides the (N, 3, 3) result only one chunk's temporaries
        for s in range(0, n, _BASIS_CHUNK):
            o = out[s:s + _BASIS_CHUNK]
            np.einsum("njk,ki->nij", self._pack[s:s + _BASIS_CHUNK, 1:, :], d, out=o)
            o += np.eye(3)
            if rot is not None:
                o += blend_jacobians(rot, self._pack[s:s + _BASIS_CHUNK], blocks)
        return out

    def still_tree(self):
        """KD-tree of the splats that do not follow a curve's frame: the fixed
        band and the handles' splats (built once; curve frames), None if none."""
        if not hasattr(self, "_still_tree"):
            from scipy.spatial import cKDTree
            con = self.constraints
            pts = [con.points[:len(con.fixed_index)]]
            pts += [self._support_positions()[np.searchsorted(self.indices, h)] for h in con.handle_index]
            pts = np.concatenate(pts)
            self._still_tree = cKDTree(pts) if len(pts) else None
        return self._still_tree

    def _support_positions(self) -> np.ndarray:
        if self.support_positions is None:
            raise ParameterError("dC", "curve frames need the support's positions (a basis made by fit())")
        return self.support_positions

    def _check_cloud(self, cloud):
        n = self.constraints.n_points
        if len(cloud.positions) != n:
            raise ParameterError("cloud", f"has {len(cloud.positions)} splats, the basis was "
                                 f"built for {n}")

    def _cpu_arrays(self, cloud):
        """Hot-path arrays of :mod:`splatedit.deform.apply_plan`, cached per
        base cloud (the cache holds the arrays it was built from)."""
        c = self._cpu
        if (c is not None and c["positions"] is cloud.positions and c["u"] is cloud.u
                and c["v"] is cloud.v):
            return c
        self._cpu = build_hot_path(self._pack, self.indices, cloud)
        return self._cpu

    def release_cpu_cache(self) -> None:
        """Drop the hot-path arrays (about 24 (4h + 3) bytes per support splat)."""
        self._cpu = None

    def apply_arrays(self, cloud, dC, progress=None):
        """Deformed ``(positions, u, v)`` (n, 3) float64 of ``cloud`` (the
        base cloud the basis was built on).  Splats outside the support are
        copied bitwise; ``dC == 0`` returns bitwise copies.  ``progress``:
        optional ``progress(APPLY_STAGE, fraction of the support's rows done)``
        after each chunk of the run plan (a commit in the editor's background)."""
        self._check_cloud(cloud)
        if isinstance(dC, CurveFrameDisplacement):    # residual and handles, then the curves' frames
            outs = self.apply_arrays(cloud, dC.base(), progress=progress)
            idx = self.indices
            pos = cloud.positions[idx]
            if self.support_positions is not None and np.array_equal(pos, self.support_positions):
                pos = self.support_positions        # the base cloud: its move-independent terms are kept
            dp, (du, dv) = frames_terms(dC, self, pos, (cloud.u[idx], cloud.v[idx]))
            for o, x in zip(outs, (dp, du, dv)):
                o[idx] += x
            return outs
        d, rot = split_displacement(dC)
        d = self._check_dc(d)
        srcs = (cloud.positions, cloud.u, cloud.v)
        if not d.any() and rot is None:
            return tuple(s.copy() for s in srcs)
        c = self._cpu_arrays(cloud)
        blocks = None if rot is None else handle_blocks(self)
        report(progress, APPLY_STAGE, 0.0)
        rows = max(len(c["arrays"][0]), 1)
        done = None if progress is None else (lambda hi: report(progress, APPLY_STAGE, hi / rows))
        return apply_hot_path(c, srcs, d, rot, blocks, progress=done)

    def apply(self, cloud, dC, *, validate: bool = False, progress=None):
        """The deformed cloud (a new :class:`SplatCloud`; colours, faces and
        name shared with ``cloud``).  ``validate=True`` re-checks the splat
        invariants (an extreme deformation can flatten splats).  ``progress``:
        see :meth:`apply_arrays` (then ``CHECK_STAGE`` before the check)."""
        return deformed_copy(cloud, self.apply_arrays(cloud, dC, progress=progress), validate, progress)

    def commit(self, cloud, dC, *, validate: bool = True, progress=None):
        """Apply ``dC`` and return the deformed cloud as the new base for the
        next edit (build a new basis on it to chain edits).  Validated by
        default: a committed cloud must satisfy the model invariants."""
        return self.apply(cloud, dC, validate=validate, progress=progress)

    def __repr__(self) -> str:
        s = self.stats
        return (f"DeformationBasis(N={s['n_support']}, handles={self.n_handles}, "
                f"m={s['n_constraints']}, centers={s['n_centers']}, method={s['method']!r})")
