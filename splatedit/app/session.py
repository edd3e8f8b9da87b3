"""The edit session state machine (no window, no GPU: unit-testable).

States::

    SELECT --(handle painted)--> fit runs in a worker thread (FITTING)
    FITTING --(done)--> READY (basis available; the handle can be moved)
    READY --G/R/S or drag--> MANIPULATE (matrix changes every mouse move)
    MANIPULATE --Enter / release--> commit: the deformed cloud becomes the
        new base (the selection is kept, a new fit starts for the next edit)
    MANIPULATE --Esc / right click--> cancel (back to READY)

The *rig* of an edit (paper Sect. 3 and 6 end): one support, one or more
disjoint handles (one active, moved by the manipulator) and optionally one
non-rigid control curve (2..16 picked points, a centripetal Catmull-Rom
curve through them, :class:`~splatedit.deform.curves.ControlCurve`).  One basis is
fitted for all of them at once: 4 columns per non-empty handle, k + 1 for
the curve, at most ``RENDER_MAX_BASIS_COLUMNS`` (16) in total.  The *pose*
is a pending matrix per handle plus a pending displacement per picked curve
point; every frame ``dC = basis.displacement(pose)`` for all columns.

When the rig is a single handle without curve, ending a manipulation
commits the edit at once (as before).  Otherwise ending a manipulation only
stores it in the pose (the other handles keep theirs) and :meth:`Session.
commit` (Enter) applies the whole pose as one edit; :meth:`Session.
reset_pose` (Esc) discards it.  A commit consumes the curve (its points are
cleared; undo brings them back) and keeps support and handles.

Every user action that changes the document (a stroke, a clear, a commit)
pushes a :class:`~splatedit.app.history.Snapshot`; undo/redo restore them
(and restart the fit for the restored selection).  Committed edits are
recorded as script edits (``indices`` support + ``indices`` handles +
``matrix`` transforms + ``curves`` with ``points`` and ``move``) and :meth:`Session.edit_script` returns an
:class:`~splatedit.script.EditScript` with the session's solver settings, so
``splatedit deform INPUT --edit script.json`` reproduces the saved cloud.

The deformation mode of new edits (:attr:`Session.deformation`, the B key:
rotation -> detail -> linear) picks the basis: rotation and linear share a
:class:`~splatedit.deform.basis.DeformationBasis`, detail fits a
:class:`~splatedit.deform.detail.DetailBasis` (the kind is part of the fit's
key, so switching to or from detail refits); each committed edit records it.

Parts kept in their own modules: the rig's pose and curve
(:mod:`splatedit.app.rig`), the fit scheduling (:mod:`splatedit.app.fitting`),
a G/R/S move (:mod:`splatedit.app.manipulation`), the live distortion
figures (:mod:`splatedit.app.distortion_feed`), the selection masks
(:mod:`splatedit.select.selection`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from splatedit.app import revision
from splatedit.app.distortion_feed import DistortionFeed
from splatedit.app.fitting import FitProgress, FitScheduler, FitStats, fitted_kind
from splatedit.app.gaussian_doc import commit_cloud
from splatedit.app.history import History, Snapshot
from splatedit.app.manipulation import GRAB, ROTATE, SCALE, Manipulation, ViewInfo  # noqa: F401 (API)
from splatedit.app.rig import Rig, _matrix_tuple
from splatedit.deform.modes import DeformationMode
from splatedit.errors import SplatEditError
from splatedit.select.selection import HANDLE, SUPPORT, Selection
from splatedit.tolerances import IQR_DEFAULT_TOL, RENDER_MAX_BASIS_COLUMNS

#: basis columns per rigid handle
HANDLE_COLUMNS = 4
#: at most this many picked points per control curve
MAX_CURVE_POINTS = 16


def columns_needed(n_handles: int, n_curve_points: int) -> int:
    """Basis columns of a rig: 4 per handle, k + 1 for a curve of k + 1 >= 2 points."""
    return HANDLE_COLUMNS * n_handles + (n_curve_points if n_curve_points >= 2 else 0)


@dataclass(frozen=True)
class SessionStats:
    """What the panel and the status file show of a session."""
    state: str                  # select / fitting / ready / manipulate / error
    support: int                # splats
    handle: int                 # splats of the active handle
    edits: int
    handles: int
    active_handle: int
    handle_sizes: tuple
    curve_points: int
    pose_pending: bool
    columns: int                # basis columns the rig needs (the basis' own once fitted)
    fit: FitStats | None        # figures of the fitted basis
    progress: FitProgress | None   # the running fit
    error: str | None           # why there is no basis


class Session:
    """The document (cloud, edits, history) with its selection, its rig
    (:class:`~splatedit.app.rig.Rig`: pose and curve), the fit scheduling
    (:class:`~splatedit.app.fitting.FitScheduler`) and the running
    manipulation.

    Args:
        cloud: the loaded :class:`SplatCloud`.
        method, tol, max_centers: solver settings (also written to exported scripts).
        fit_sync: run fits on the calling thread (tests).
    """

    def __init__(self, cloud, *, method: str = "auto", tol: float = IQR_DEFAULT_TOL,
                 max_centers: int | None = None, fit_sync: bool = False, on_change=None):
        self.method, self.tol, self.max_centers = method, tol, max_centers
        #: deformation mode of new edits (the editor's B key; carried into exported scripts)
        self.deformation = DeformationMode.ROTATION
        self.fit_sync = fit_sync
        self.on_change = on_change or (lambda: None)
        self.fit = FitScheduler(sync=fit_sync, on_change=self.on_change)
        self.cloud = cloud
        self.selection = Selection(cloud.n)
        self.rig = Rig()
        self.edits: tuple = ()
        self.history = History()
        self.history.reset(self._snapshot("open"))
        self.manip: Manipulation | None = None
        self.manip_target = None      # ("handle", i) or ("curve", j)
        self.brush_target = SUPPORT
        self.version = 0          # bumps whenever cloud or selection changes
        self.last_commit_seconds = 0.0
        self._distortion = DistortionFeed(self.on_change, sync=fit_sync)

    # ------------------------------------------- the rig and the fit's state
    # (kept as attributes of the session: the editor, the tools and the tests use them)
    def _delegate(owner: str, name: str, doc: str):  # noqa: N805 - a property factory
        return property(lambda self: getattr(getattr(self, owner), name),
                        lambda self, v: setattr(getattr(self, owner), name, v), doc=doc)

    pose = _delegate("rig", "pose", "pending (4, 4) matrix per handle")
    curve_points = _delegate("rig", "curve_points", "picked points (3,) of the control curve")
    curve_moves = _delegate("rig", "curve_moves", "(k, 3) pending displacement per picked point")
    curve_mode = _delegate("rig", "curve_mode", "the editor's curve tool is on")
    basis = _delegate("fit", "basis", "the fitted DeformationBasis (None while fitting / without handle)")
    basis_key = _delegate("fit", "key", "the selection key the basis was fitted for")
    basis_groups = _delegate("fit", "groups", "(fitted handle indices, ControlCurve or None) of the basis")
    fit_job = _delegate("fit", "job", "the running fit Job, or None")
    fit_error = _delegate("fit", "error", "why there is no basis, or None")
    del _delegate

    # ---------------------------------------------------------- snapshots
    def _snapshot(self, label: str) -> Snapshot:
        return Snapshot.make(self.cloud, self.selection.support, self.selection.handles, self.edits,
                             label, active=self.selection.active, rig=self.rig.as_tuple())

    def _restore(self, snap: Snapshot) -> None:
        self.cloud = snap.cloud
        s, _ = snap.masks()
        self.selection = Selection(len(s), s, handles=snap.handle_masks(), active=snap.active)
        self.rig.restore(snap.rig)
        self._sync_pose()
        self.edits = snap.edits
        self.manip = None
        self.manip_target = None
        self.version += 1
        self.request_fit()
        self.on_change()

    def _sync_pose(self) -> None:
        self.rig.sync_pose(len(self.selection.handles))

    def push(self, label: str) -> None:
        """Record the current state (after a stroke, clear, pose change or commit)."""
        self._sync_pose()
        self.history.push(self._snapshot(label))
        self.version += 1
        self.request_fit()
        self.on_change()

    def undo(self) -> bool:
        if self.manip is not None:
            self.cancel()
            return True
        snap = self.history.undo()
        if snap is None:
            return False
        self._restore(snap)
        return True

    def redo(self) -> bool:
        if self.manip is not None:
            return False
        snap = self.history.redo()
        if snap is None:
            return False
        self._restore(snap)
        return True

    @property
    def dirty(self) -> bool:
        return self.history.geometry_dirty

    # ------------------------------------------------------------ selection
    def paint(self, indices, erase: bool = False) -> bool:
        """Paint the current brush target (no history entry: call
        :meth:`end_stroke` when the stroke ends)."""
        if self.manip is not None:
            return False
        changed = self.selection.paint(indices, self.brush_target, erase)
        if changed:
            self.version += 1
        return changed

    def end_stroke(self, changed: bool) -> None:
        if changed:
            self.push(f"paint {self.brush_target}")

    def clear(self, target: str | None = None) -> None:
        if self.manip is None and self.selection.clear(target):
            self.pose = [np.eye(4)]
            self.push("clear")

    def set_selection(self, support, handle, label: str = "select") -> None:
        handles = handle if isinstance(handle, (list, tuple)) else [handle]
        self.selection = Selection(self.cloud.n, support, handles=handles)
        self.pose = [np.eye(4)]
        self.push(label)

    # -------------------------------------------------------------- handles
    def _check_columns(self, n_handles: int, n_points: int, what: str) -> None:
        k = columns_needed(n_handles, n_points)
        if k > RENDER_MAX_BASIS_COLUMNS:
            raise SplatEditError(
                f"cannot {what}: the basis would need {k} columns (4 per handle + 1 per curve point "
                f"from 2 points on), at most {RENDER_MAX_BASIS_COLUMNS} are supported")

    def _n_handles_planned(self) -> int:
        """Handles that take basis columns (all but a lone empty one)."""
        hs = self.selection.handles
        return len(hs) if (len(hs) > 1 or hs[0].any()) else 0

    def add_handle(self) -> bool:
        """Start a new handle (active; the brush then paints it).  An empty
        active handle is reused.  Raises SplatEditError over 16 columns."""
        if self.manip is not None:
            return False
        self.brush_target = HANDLE
        if not self.selection.handle.any():
            return False
        self._check_columns(len(self.selection.handles) + 1, len(self.curve_points), "add a handle")
        self.selection.add_handle()
        self.push("new handle")
        return True

    def remove_handle(self) -> bool:
        """Remove the active handle (and its pending transform)."""
        if self.manip is not None:
            return False
        i = self.selection.active
        several = len(self.selection.handles) > 1
        if not self.selection.remove_handle(i):
            return False
        if several:
            del self.pose[i]
        else:
            self.pose = [np.eye(4)]
        self.push("remove handle")
        return True

    def select_handle(self, i: int) -> bool:
        """Make handle ``i`` (modulo the count) the active one (not an undo step)."""
        if self.manip is not None or not self.selection.select_handle(i):
            return False
        self.version += 1
        self.on_change()
        return True

    def cycle_handle(self, step: int = 1) -> bool:
        return self.select_handle(self.selection.active + step)

    # ---------------------------------------------------------------- curve
    def curve(self):
        """The :class:`ControlCurve` through the picked points (None below 2)."""
        return self.rig.curve()

    def add_curve_point(self, point) -> bool:
        """Append a picked point (2..16 per curve; consecutive ones distinct)."""
        if self.manip is not None:
            return False
        p = np.array(point, dtype=np.float64).reshape(3)
        if len(self.curve_points) >= MAX_CURVE_POINTS:
            raise SplatEditError(f"a curve has at most {MAX_CURVE_POINTS} points")
        self._check_columns(self._n_handles_planned(), len(self.curve_points) + 1, "add a curve point")
        if self.curve_points:
            from splatedit.deform.curves import first_coincident_point
            # the same check (consecutive points distinct) as building the curve
            if first_coincident_point(np.array(self.curve_points + [p])) is not None:
                raise SplatEditError("this point is the curve's last point: pick another one")
        self.curve_points.append(p)
        self.curve_moves = np.vstack([self.curve_moves, np.zeros((1, 3))])
        self.push("curve point")
        return True

    def remove_curve_point(self) -> bool:
        """Remove the last picked point."""
        if self.manip is not None or not self.curve_points:
            return False
        self.curve_points.pop()
        self.curve_moves = self.curve_moves[:-1].copy()
        self.push("remove curve point")
        return True

    def clear_curve(self) -> bool:
        if self.manip is not None or not self.curve_points:
            return False
        self.rig.clear_curve()
        self.push("clear curve")
        return True

    def curve_point_positions(self, live: bool = True) -> np.ndarray:
        """(k + 1, 3) current (moved) picked points."""
        if not self.curve_points:
            return np.zeros((0, 3))
        return np.array(self.curve_points) + self.live_curve_moves(live)

    def curve_polyline(self, count: int = 160, live: bool = True) -> np.ndarray | None:
        """(>= count, 3) points of the moved curve ``c'(t) = c(t) + W(t) dq``
        for drawing: exactly the targets the fitted deformation gives the
        curve's samples (through every moved picked point; None below 2
        points)."""
        c = self.curve()
        if c is None:
            return None
        t = np.union1d(np.linspace(0.0, 1.0, count), c.params)
        return c.evaluate(t, c.points + self.live_curve_moves(live))

    # --------------------------------------------------------------- fitting
    def selection_key(self):
        """What a fit depends on: the cloud, the selection, the curve and the
        kind of basis the deformation mode draws with (:func:`fitted_kind`)."""
        return ((revision.of(self.cloud),) + self.selection.key() + (self.rig.curve_key(),)
                + (fitted_kind(self.deformation),))

    def request_fit(self) -> None:
        """Start (or restart) a background fit of all non-empty handles and
        the curve (when it has at least 2 points)."""
        key = self.selection_key()
        if self.fit.current(key):
            return
        self.fit.clear()
        hidx = self.selection.nonempty()
        curve = self.curve()
        if not hidx and curve is None:
            return
        if not self.selection.support.any():
            self.fit_error = "paint a support region first (1)"
            return
        k = columns_needed(len(hidx), len(self.curve_points))
        if k > RENDER_MAX_BASIS_COLUMNS:
            self.fit_error = (f"{k} basis columns needed (4 per handle + 1 per curve point), at most "
                              f"{RENDER_MAX_BASIS_COLUMNS}: remove a handle or curve points")
            return
        support = self.selection.support.copy()
        handles = [self.selection.handles[k].copy() for k in hidx]
        work = self.fit.work(self.cloud, support, handles, [curve] if curve is not None else [],
                             self.deformation, method=self.method, tol=self.tol,
                             max_centers=self.max_centers)
        # fits run one at a time on the scheduler's worker (a cancelled one ends at its
        # next progress report); fit_sync runs it here
        self.fit.start(key, (tuple(hidx), curve), work)

    def poll(self) -> bool:
        """Collect a finished fit; True when the state changed."""
        got = self.fit.poll(self.selection_key())
        if got is None:             # fitted for a selection that has changed since
            self.request_fit()
            return True
        return got

    def wait_fit(self, timeout: float = 120.0) -> bool:
        """Block until the fit finishes (tests and scripted use)."""
        t0 = time.perf_counter()
        while self.fit_job is not None and time.perf_counter() - t0 < timeout:
            self.fit_job.wait(0.05)
            self.poll()
        return self.basis is not None

    @property
    def fitting(self) -> bool:
        return self.fit_job is not None

    @property
    def state(self) -> str:
        if self.manip is not None:
            return "manipulate"
        if self.fit_job is not None:
            return "fitting"
        if self.basis is not None:
            return "ready"
        if self.fit_error:
            return "error"
        return "select"

    # ------------------------------------------------------------------ pose
    @property
    def single_rig(self) -> bool:
        """One handle and no curve: ending a manipulation commits at once."""
        return len(self.selection.handles) == 1 and not self.curve_points

    @property
    def pose_pending(self) -> bool:
        """Some handle or curve point has a pending (uncommitted) move."""
        return self.rig.pending

    def handle_matrix(self, k: int, live: bool = True) -> np.ndarray:
        """Pending matrix of handle ``k`` (with the running manipulation when ``live``)."""
        m = self.pose[k] if k < len(self.pose) else np.eye(4)
        if live and self.manip is not None and self.manip_target == ("handle", k):
            m = self.manip.matrix() @ m
        return m

    def live_curve_moves(self, live: bool = True) -> np.ndarray:
        mv = self.curve_moves.copy()
        if live and self.manip is not None and self.manip_target and self.manip_target[0] == "curve":
            j = self.manip_target[1]
            p = self.curve_points[j] + mv[j]
            m = self.manip.matrix()
            mv[j] = m[:3, :3] @ p + m[:3, 3] - self.curve_points[j]
        return mv

    def inputs(self, live: bool = True) -> list:
        """Per-group inputs of ``basis.displacement`` (fitted handles, then the curve)."""
        hidx, curve = self.basis_groups
        out = [self.handle_matrix(k, live) for k in hidx]
        if curve is not None:
            out.append(self.live_curve_moves(live))  # the curve's controls are its picked points
        return out

    def reset_pose(self) -> bool:
        """Discard the pending transforms and curve moves (an undo step)."""
        if self.manip is not None:
            self.cancel()
        if not self.pose_pending:
            return False
        self.rig.reset_pose(len(self.selection.handles))
        self.push("reset pose")
        return True

    # ---------------------------------------------------------- manipulation
    def handle_centroid(self, k: int | None = None) -> np.ndarray:
        """Centroid of handle ``k`` (default: the active one) moved by its pending matrix."""
        k = self.selection.active if k is None else k
        c = self.cloud.positions[self.selection.handles[k]].mean(axis=0)
        m = self.pose[k] if k < len(self.pose) else np.eye(4)
        return m[:3, :3] @ c + m[:3, 3]

    def active_fitted(self) -> bool:
        """The active handle is part of the fitted basis."""
        return self.basis is not None and self.selection.active in self.basis_groups[0]

    def begin(self, mode: str, view: ViewInfo, mouse: tuple[float, float]) -> bool:
        """Start G/R/S of the active handle (needs a basis that includes it)."""
        if self.manip is not None or not self.active_fitted():
            return False
        self.manip = Manipulation(mode, self.handle_centroid(), view, mouse)
        self.manip_target = ("handle", self.selection.active)
        return True

    def begin_curve_point(self, j: int, view: ViewInfo, mouse: tuple[float, float]) -> bool:
        """Start dragging picked curve point ``j`` (needs a basis with the curve)."""
        if self.manip is not None or self.basis is None or self.basis_groups[1] is None:
            return False
        if not 0 <= j < len(self.curve_points):
            return False
        self.manip = Manipulation(GRAB, self.curve_points[j] + self.curve_moves[j], view, mouse)
        self.manip_target = ("curve", int(j))
        return True

    def current_matrix(self) -> np.ndarray:
        return np.eye(4) if self.manip is None else self.manip.matrix()

    def current_dc(self):
        """dC of the whole pose, live manipulation included (None without
        basis), in the session's :attr:`deformation` mode (a
        RotationDisplacement in rotation mode)."""
        if self.basis is None:
            return None
        return self.basis.displacement(self.inputs(), mode=self.deformation)

    #: the B key's cycle of deformation modes
    DEFORMATION_CYCLE = (DeformationMode.ROTATION, DeformationMode.DETAIL, DeformationMode.LINEAR)

    def cycle_deformation(self) -> DeformationMode:
        """Switch the mode of new edits: rotation -> detail -> linear -> rotation.
        Rotation and linear share the fitted basis (the live pose is shown in
        the new mode at once); switching to or from detail refits (a
        :class:`~splatedit.deform.detail.DetailBasis`: base surface plus normal
        offsets), the pose is kept and drawn again when the fit is done.  Not
        an undo step (a setting, like the brush mode); each committed edit
        records its mode."""
        cyc = self.DEFORMATION_CYCLE
        return self.set_deformation(cyc[(cyc.index(self.deformation) + 1) % len(cyc)])

    def set_deformation(self, mode) -> DeformationMode:
        """Make ``mode`` (a DeformationMode or its name) the mode of new edits
        (refits when the kind of basis changes, see :meth:`cycle_deformation`)."""
        self.deformation = DeformationMode(mode)
        self.request_fit()          # a no-op unless the basis kind changed
        self.on_change()
        return self.deformation

    def distortion(self):
        """:class:`~splatedit.deform.distortion.DistortionStats` of the support
        for the current pose (live manipulation included), or None without a
        basis, when nothing is moved, or before the first figures are ready
        (computed off the UI thread: :class:`~splatedit.app.distortion_feed.DistortionFeed`)."""
        dc = self.current_dc()
        if dc is None or not dc.any():
            return None
        return self._distortion.stats(self.basis, self.cloud, dc)

    def cancel(self) -> None:
        self.manip = None
        self.manip_target = None
        self.on_change()

    def _check_manip(self) -> None:
        """Raise SplatEditError (state unchanged) when the running manipulation's
        typed value cannot be applied (e.g. a scale factor <= 0)."""
        bad = self.manip.problem() if self.manip is not None else None
        if bad:
            raise SplatEditError(bad)

    def _bake(self) -> None:
        """Store the running manipulation in the pose."""
        t = self.manip_target
        if t[0] == "handle":
            self.pose[t[1]] = self.handle_matrix(t[1])
        else:
            self.curve_moves = self.live_curve_moves()
        self.manip = None
        self.manip_target = None

    def finish(self) -> str:
        """End the running manipulation: commit at once for a single-handle
        rig ("commit", or "" when nothing moved); else keep it in the pose
        ("pose") for a later :meth:`commit`."""
        if self.manip is None:
            return ""
        self._check_manip()
        if self.single_rig:
            return "commit" if self.commit() else ""
        moved = not np.array_equal(self.manip.matrix(), np.eye(4))
        what = "move handle" if self.manip_target[0] == "handle" else "move curve point"
        self._bake()
        if moved:
            self.push(what)
        else:
            self.on_change()
        return "pose" if moved else ""

    def commit(self) -> bool:
        """Apply the pose (running manipulation included) as one edit: the
        deformed cloud becomes the new base, the edit is recorded, support and
        handles are kept, the curve is consumed.  Raises InputError (state
        unchanged) when a splat degenerates."""
        from splatedit.script import Curve, Edit, Matrix
        from splatedit.select.regions import Indices
        if self.basis is None:
            return False
        self._check_manip()
        inputs = self.inputs(live=True)
        moves = self.live_curve_moves(live=True)
        hidx, curve = self.basis_groups
        mats = inputs[:len(hidx)]
        if all(np.array_equal(m, np.eye(4)) for m in mats) and not (curve is not None and moves.any()):
            self.manip = None
            self.manip_target = None
            self.on_change()
            return False
        t0 = time.perf_counter()
        dc = self.basis.displacement(inputs, mode=self.deformation)
        # the same arrays and the same checks as ``splatedit deform`` and as reading the
        # saved file: the whole cloud is validated (SplatCloud.validate: the minimum axis
        # length is relative to the *whole* cloud's diagonal, which the edit may change)
        # a Gaussian document: the Gaussians deformed on the CPU (covariances, SH) and re-wrapped
        new = commit_cloud(self.basis, self.cloud, dc)     # raises InputError on a degenerate splat
        self.last_commit_seconds = time.perf_counter() - t0
        sel = self.selection
        idx = lambda m: Indices(tuple(int(i) for i in np.flatnonzero(m)))  # noqa: E731
        curves = ()
        if curve is not None:
            curves = (Curve(tuple(tuple(float(x) for x in p) for p in self.curve_points),
                            tuple(tuple(float(x) for x in d) for d in moves), None),)
        edit = Edit(idx(sel.support), tuple(idx(sel.handles[k]) for k in hidx),
                    tuple(Matrix(_matrix_tuple(m)) for m in mats), "$", curves,
                    fill_holes=False,  # the editor's closed selection, replayed as is
                    deformation=self.deformation)
        self.manip = None
        self.manip_target = None
        self.cloud = new
        self.edits = self.edits + (edit,)
        self.fit.clear()
        self.rig.reset_pose(len(sel.handles))
        self.rig.clear_curve()
        self.push("edit")
        return True

    # ---------------------------------------------------------------- export
    def edit_script(self):
        from splatedit.script import EditScript, SolverSettings
        return EditScript(tuple(self.edits), SolverSettings(self.method, self.tol, self.max_centers))

    def stats(self) -> SessionStats:
        sel = self.selection
        fit = self.fit.stats()
        return SessionStats(
            state=self.state, support=sel.counts[0], handle=sel.counts[1], edits=len(self.edits),
            handles=len(sel.handles), active_handle=sel.active,
            handle_sizes=tuple(int(h.sum()) for h in sel.handles), curve_points=len(self.curve_points),
            pose_pending=self.pose_pending,
            columns=fit.columns if fit is not None else columns_needed(len(sel.nonempty()), len(self.curve_points)),
            fit=fit, progress=self.fit.progress(), error=self.fit_error)

    def close(self) -> None:
        self.fit.close()
