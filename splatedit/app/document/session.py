"""The edit session state machine (no window, no GPU: unit-testable).

States::

    SELECT --(handle painted)--> fit runs in a worker thread (FITTING)
    FITTING --(done)--> READY (basis available; the handle can be moved)
    READY --G/R/S or drag--> MANIPULATE (matrix changes every mouse move)
    MANIPULATE --Enter / release--> commit: the deformed cloud becomes the
        new base (the selection is kept, a new fit starts for the next edit);
        a long commit goes through COMMITTING (a background job,
        :mod:`splatedit.app.document.commit_job`: document changes refused) first
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
pushes a :class:`~splatedit.app.document.history.Snapshot`; undo/redo restore them
(and restart the fit for the restored selection).  Committed edits are
recorded as script edits (``indices`` support + ``indices`` handles +
``matrix`` transforms + ``curves`` with ``points`` and ``move``), deleted or
cropped splats (:meth:`Session.remove_splats`) as ``delete`` / ``crop``
items with ``indices``, and :meth:`Session.edit_script` returns an
:class:`~splatedit.script.EditScript` with the session's solver settings, so
``splatedit deform INPUT --edit script.json`` reproduces the saved cloud.

The deformation mode of new edits (:attr:`Session.deformation`, the B key:
rotation -> detail -> linear) picks the basis: rotation and linear share a
:class:`~splatedit.deform.basis.DeformationBasis`, detail fits a
:class:`~splatedit.deform.detail.DetailBasis` (the kind is part of the fit's
key, so switching to or from detail refits); each committed edit records it.

Parts kept in their own modules: the history (:mod:`splatedit.app.document.session_history`:
snapshots, undo, redo; an owned object, ``session.history_part``), editing the rig
(:mod:`splatedit.app.document.session_rig`: handles, curve points; owned, ``session.rig_part``),
selection editing (:mod:`splatedit.app.document.selection_edit`: strokes, their closure, region
edits; owned, ``session.selection_edit``),
the pose and its manipulation (:mod:`splatedit.app.document.session_pose`: G/R/S, finish,
commit; owned, ``session.pose_part``), the rig's pose and curve
(:mod:`splatedit.app.document.rig`), the fit scheduling (:mod:`splatedit.app.document.fitting`),
a G/R/S move (:mod:`splatedit.app.document.manipulation`), the live distortion
figures (:mod:`splatedit.app.document.distortion_feed`), the selection masks
(:mod:`splatedit.select.selection`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from splatedit.app.document import revision
from splatedit.app.document.commit_job import CommitOutcome, CommitProgress, CommitRunner
from splatedit.app.document.distortion_feed import DistortionFeed
from splatedit.app.document.fitting import FitProgress, FitScheduler, FitStats, fitted_kind
from splatedit.app.document.gaussian import DETAIL_UNAVAILABLE, gaussians_of
from splatedit.app.document.history import History
from splatedit.app.document.manipulation import GRAB, ROTATE, SCALE, Manipulation, ViewInfo  # noqa: F401 (API)
from splatedit.app.document.rig import Rig
from splatedit.app.document.selection_edit import SelectionEdit
from splatedit.app.document.session_history import SessionHistory
from splatedit.app.document.session_pose import PoseEditing
from splatedit.app.document.session_rig import HANDLE_COLUMNS, MAX_CURVE_POINTS, RigEditing, columns_needed  # noqa: F401 (API)
from splatedit.deform.modes import DeformationMode
from splatedit.select.selection import SUPPORT, Selection
from splatedit.tolerances import EDITOR_COMMIT_SYNC_MS, IQR_DEFAULT_TOL, RENDER_MAX_BASIS_COLUMNS


@dataclass(frozen=True)
class LastEdit:
    """The last committed edit, kept to show its distortion after the commit:
    the cloud it deformed, its basis and dC (deforming ``cloud`` by ``dc``
    gives the committed cloud), its history label and number (1-based), and
    the history state it produced (it is shown while that state is current)."""
    cloud: object
    basis: object
    dc: object
    label: str
    number: int
    state: object


@dataclass(frozen=True)
class SessionStats:
    """What the panel and the status file show of a session."""
    state: str                  # select / fitting / ready / manipulate / committing / error
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
    commit: CommitProgress | None = None   # the running background commit


class Session:
    """The document (cloud, edits, history) with its selection, its rig
    (:class:`~splatedit.app.document.rig.Rig`: pose and curve), the fit scheduling
    (:class:`~splatedit.app.document.fitting.FitScheduler`) and the running
    manipulation.

    Args:
        cloud: the loaded :class:`SplatCloud`.
        method, tol, max_centers: solver settings (also written to exported scripts).
        fit_sync: run fits on the calling thread (tests); commits then never
            run in the background either.
        graphs: the neighbour-graph and closure service of the selection
            edits (:class:`~splatedit.app.document.selection.SelectionTools`,
            the editor's); None: selection edits are not closed.

    Commits (:meth:`commit`) estimated at ``commit_sync_ms`` or more run in
    the background (:mod:`splatedit.app.document.commit_job`); meanwhile
    :attr:`committing` is True and every change of the document is refused
    (the methods return False) until :meth:`poll` lands it.
    """

    def __init__(self, cloud, *, method: str = "auto", tol: float = IQR_DEFAULT_TOL,
                 max_centers: int | None = None, fit_sync: bool = False, on_change=None, graphs=None):
        self.method, self.tol, self.max_centers = method, tol, max_centers
        #: deformation mode of new edits (the editor's B key; carried into exported scripts)
        self.deformation = DeformationMode.ROTATION
        self.fit_sync = fit_sync
        self.on_change = on_change or (lambda: None)
        self.fit = FitScheduler(sync=fit_sync, on_change=self.on_change)
        self.cloud = cloud
        self.selection = Selection(cloud.n)
        #: the selection edit API: brush target, strokes and their closure, region
        #: edits (:class:`~splatedit.app.document.selection_edit.SelectionEdit`)
        self.selection_edit = SelectionEdit(self, graphs)
        self.rig = Rig()
        #: handle and curve-point editing (:class:`~splatedit.app.document.session_rig.RigEditing`)
        self.rig_part = RigEditing(self)
        #: pose, G/R/S moves, finish and commit (:class:`~splatedit.app.document.session_pose.PoseEditing`)
        self.pose_part = PoseEditing(self)
        self.edits: tuple = ()
        self.history = History()
        #: push / undo / redo of the document (:class:`~splatedit.app.document.session_history.SessionHistory`)
        self.history_part = SessionHistory(self)
        self.history.reset(self.history_part.snapshot("open"))
        self.manip: Manipulation | None = None
        self.manip_target = None      # ("handle", i) or ("curve", j)
        self.brush_target = SUPPORT
        #: the picked curve point the transform fields edit (last added / dragged / chosen)
        self.curve_active = 0
        self.version = 0          # bumps whenever cloud or selection changes
        self.last_commit_seconds = 0.0
        #: commits estimated at this many ms or more run in the background
        self.commit_sync_ms = float("inf") if fit_sync else EDITOR_COMMIT_SYNC_MS
        self.committer = CommitRunner(self.on_change)
        #: how the last background commit ended (the editor shows it and clears it)
        self.commit_outcome: CommitOutcome | None = None
        self._distortion = DistortionFeed(self.on_change, sync=fit_sync)
        self.last_edit: LastEdit | None = None
        self._erasing = False       # the stroke being painted erases (its history name)
        #: why moves and fits wait (e.g. an out-of-core document loading the
        #: support's region at full resolution, :mod:`splatedit.app.document.outofcore`); None: they do not
        self.waiting: str | None = None
        #: why splats cannot be deleted or cropped (an out-of-core document keeps
        #: every point of its file); None: they can
        self.splats_fixed: str | None = None

    # ------------------------------------------------------------ history
    # (the session's face of its history_part, SessionHistory)
    def push(self, label: str) -> None:
        """Record the current state (after a stroke, clear, pose change or commit)."""
        self.history_part.push(label)

    def undo(self) -> bool:
        """Cancel a running move, else step back (False: nothing to undo, or a commit runs)."""
        return self.history_part.undo()

    def redo(self) -> bool:
        """Step forward (False: nothing to redo, a move or a commit runs)."""
        return self.history_part.redo()

    def adopt_recovered(self, script, label: str) -> None:
        """Make a recovery entry's edit script this document's committed edits
        (:meth:`SessionHistory.adopt_recovered
        <splatedit.app.document.session_history.SessionHistory.adopt_recovered>`)."""
        self.history_part.adopt_recovered(script, label)

    @property
    def dirty(self) -> bool:
        """Unsaved changes (a commit still running counts: quitting asks first)."""
        return self.history_part.dirty

    # ---------------------------------------------------------------- rig
    # (the session's face of its rig_part, RigEditing; each change is an undo step)
    def add_handle(self) -> bool:
        """Start a new handle (active; the brush then paints it).  An empty
        active handle is reused.  Raises SplatEditError over 16 columns."""
        return self.rig_part.add_handle()

    def remove_handle(self) -> bool:
        """Remove the active handle (and its pending transform)."""
        return self.rig_part.remove_handle()

    def select_handle(self, i: int) -> bool:
        """Make handle ``i`` (modulo the count) the active one (not an undo step)."""
        return self.rig_part.select_handle(i)

    def cycle_handle(self, step: int = 1) -> bool:
        """Make the handle ``step`` after the active one active (not an undo step)."""
        return self.rig_part.cycle_handle(step)

    def curve(self):
        """The :class:`ControlCurve` through the picked points (None below 2)."""
        return self.rig_part.curve()

    def add_curve_point(self, point) -> bool:
        """Append a picked point (2..16 per curve; consecutive ones distinct)."""
        return self.rig_part.add_curve_point(point)

    def remove_curve_point(self) -> bool:
        """Remove the last picked point."""
        return self.rig_part.remove_curve_point()

    def clear_curve(self) -> bool:
        """Remove every picked point."""
        return self.rig_part.clear_curve()

    def active_curve_point(self) -> int | None:
        """Index of the picked point the transform fields edit, None without curve points."""
        return self.rig_part.active_curve_point()

    def select_curve_point(self, j: int) -> bool:
        """Make picked point ``j`` (modulo the count) the active one (not an undo step)."""
        return self.rig_part.select_curve_point(j)

    def curve_point_positions(self, live: bool = True) -> np.ndarray:
        """(k + 1, 3) current (moved) picked points."""
        return self.rig_part.curve_point_positions(live)

    def curve_polyline(self, count: int = 160, live: bool = True) -> np.ndarray | None:
        """(>= count, 3) points of the moved curve for drawing (None below 2 points;
        :meth:`RigEditing.curve_polyline <splatedit.app.document.session_rig.RigEditing.curve_polyline>`)."""
        return self.rig_part.curve_polyline(count, live)

    # --------------------------------------------------- pose, moves, commit
    # (the session's face of its pose_part, PoseEditing)
    @property
    def single_rig(self) -> bool:
        """One handle and no curve: ending a manipulation commits at once."""
        return self.pose_part.single_rig

    @property
    def pose_pending(self) -> bool:
        """Some handle or curve point has a pending (uncommitted) move."""
        return self.pose_part.pose_pending

    @property
    def committing(self) -> bool:
        """A commit is running in the background (document changes are refused)."""
        return self.pose_part.committing

    def handle_matrix(self, k: int, live: bool = True) -> np.ndarray:
        """Pending (4, 4) matrix of handle ``k`` (with the running manipulation when ``live``)."""
        return self.pose_part.handle_matrix(k, live)

    def live_curve_moves(self, live: bool = True) -> np.ndarray:
        """(k + 1, 3) pending moves of the picked curve points (with the running drag when ``live``)."""
        return self.pose_part.live_curve_moves(live)

    def inputs(self, live: bool = True) -> list:
        """Per-group inputs of ``basis.displacement`` (fitted handles, then the curve)."""
        return self.pose_part.inputs(live)

    def reset_pose(self) -> bool:
        """Discard the pending transforms and curve moves (an undo step)."""
        return self.pose_part.reset_pose()

    def handle_centroid(self, k: int | None = None) -> np.ndarray:
        """(3,) centroid of handle ``k`` (default: the active one) moved by its pending matrix."""
        return self.pose_part.handle_centroid(k)

    def active_fitted(self) -> bool:
        """The active handle is part of the fitted basis."""
        return self.pose_part.active_fitted()

    def begin(self, mode: str, view: ViewInfo, mouse: tuple[float, float], pivot=None, frame=None,
              frame_name: str = "") -> bool:
        """Start G/R/S of the active handle about ``pivot`` with constraint axes
        ``frame`` (:meth:`PoseEditing.begin <splatedit.app.document.session_pose.PoseEditing.begin>`)."""
        return self.pose_part.begin(mode, view, mouse, pivot, frame, frame_name)

    def begin_curve_point(self, j: int, view: ViewInfo, mouse: tuple[float, float]) -> bool:
        """Start dragging picked curve point ``j`` (needs a basis with the curve)."""
        return self.pose_part.begin_curve_point(j, view, mouse)

    def current_matrix(self) -> np.ndarray:
        """(4, 4) matrix of the running manipulation (identity without one)."""
        return self.pose_part.current_matrix()

    def current_dc(self):
        """dC of the whole pose, live manipulation included (None without
        basis), in the session's :attr:`deformation` mode."""
        return self.pose_part.current_dc()

    def cancel(self) -> None:
        """Drop the running manipulation (the pose keeps its earlier moves)."""
        self.pose_part.cancel()

    def finish(self) -> str:
        """End the running manipulation: ``"commit"``, ``"pose"`` or ``""``
        (:meth:`PoseEditing.finish <splatedit.app.document.session_pose.PoseEditing.finish>`)."""
        return self.pose_part.finish()

    def commit(self) -> bool:
        """Apply the pose (running manipulation included) as one edit, at once
        or in the background (:meth:`PoseEditing.commit
        <splatedit.app.document.session_pose.PoseEditing.commit>`)."""
        return self.pose_part.commit()

    def poll_commit(self) -> bool:
        """Land a finished background commit (or restore the pose after its
        error, :attr:`commit_outcome`); True when the state changed."""
        return self.pose_part.poll_commit()

    def wait_commit(self, timeout: float = 120.0) -> bool:
        """Block until a background commit lands (tests, scripted use); True when none is left."""
        return self.pose_part.wait_commit(timeout)

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

    # ------------------------------------------------------------ selection
    def paint(self, indices, erase: bool = False, reach=None) -> bool:
        """Paint the current brush target (no history entry: call
        :meth:`end_stroke` when the stroke ends); ``reach``: the splats the
        dab covered at any depth (see :meth:`Selection.paint`)."""
        if self.manip is not None or self.committing:
            return False
        changed = self.selection.paint(indices, self.brush_target, erase, reach=reach)
        self._erasing = erase
        if changed:
            self.version += 1
        return changed

    def end_stroke(self, changed: bool) -> None:
        if changed:
            self.push(f"{'Erase' if self._erasing else 'Paint'} {self.brush_target}")

    def clear(self, target: str | None = None) -> None:
        if self.manip is None and not self.committing and self.selection.clear(target):
            self.pose = [np.eye(4)]
            self.push("clear")

    def set_selection(self, support, handle, label: str = "select") -> None:
        if self.committing:
            return
        handles = handle if isinstance(handle, (list, tuple)) else [handle]
        self.selection = Selection(self.cloud.n, support, handles=handles)
        self.pose = [np.eye(4)]
        self.push(label)

    def remove_splats(self, keep: bool = False) -> int:
        """Delete the support splats from the document (``keep``: crop, keep
        only them): one undo step and one ``delete`` / ``crop`` item of the
        edit script (indices of the current cloud), so a saved file replays.
        The selection, the curve and the pending pose are cleared.  Returns
        the number of splats removed; 0 (nothing done) without a support,
        when nothing would be left, during a move, with pending moves or
        while an edit is applied."""
        from splatedit.app.document.gaussian import subset_document
        from splatedit.script import Removal
        from splatedit.select.regions import Indices
        if self.manip is not None or self.committing or self.pose_pending or self.splats_fixed:
            return 0
        sup = self.selection.support
        kept = sup.copy() if keep else ~sup
        if not sup.any() or not kept.any():
            return 0
        item = Removal(Indices(tuple(int(i) for i in np.flatnonzero(sup))), keep)
        self.cloud = subset_document(self.cloud, kept)
        self.edits = self.edits + (item,)
        self.fit.clear()
        self.selection = Selection(self.cloud.n)
        self.rig.clear_curve()
        self.rig.reset_pose(1)
        self.push(item.key)
        return int((~kept).sum())

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
        if self.fit.current(key) or self.committing or self.waiting:    # a landing commit refits
            return
        self.fit.clear()
        if self.fit.recall(key):      # undo / redo back to a fitted selection: no refit
            self.on_change()
            return
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
        """Land a finished background commit, collect a finished fit; True
        when the state changed."""
        if self.poll_commit():
            return True
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
        if self.committing:
            return "committing"
        if self.manip is not None:
            return "manipulate"
        if self.waiting:
            return "waiting"
        if self.fit_job is not None:
            return "fitting"
        if self.basis is not None:
            return "ready"
        if self.fit_error:
            return "error"
        return "select"


    #: the B key's cycle of deformation modes
    DEFORMATION_CYCLE = (DeformationMode.ROTATION, DeformationMode.DETAIL, DeformationMode.LINEAR)

    #: why the detail mode cannot be chosen for a Gaussian scene (as ``splatedit deform`` says)
    DETAIL_UNAVAILABLE = DETAIL_UNAVAILABLE

    @property
    def detail_available(self) -> bool:
        """The detail mode can be chosen: not for a Gaussian document (the
        Gaussians' covariance and SH transport needs the plain basis'
        Jacobians; ``splatedit deform`` and ``render --edit`` refuse it too)."""
        return gaussians_of(self.cloud) is None

    def deformation_cycle(self) -> tuple:
        """The modes B cycles through for this document (detail left out where unavailable)."""
        return tuple(m for m in self.DEFORMATION_CYCLE
                     if m is not DeformationMode.DETAIL or self.detail_available)

    def cycle_deformation(self) -> DeformationMode:
        """Switch the mode of new edits: rotation -> detail -> linear -> rotation
        (rotation <-> linear for a Gaussian document, :attr:`detail_available`).
        Rotation and linear share the fitted basis (the live pose is shown in
        the new mode at once); switching to or from detail refits (a
        :class:`~splatedit.deform.detail.DetailBasis`: base surface plus normal
        offsets), the pose is kept and drawn again when the fit is done.  Not
        an undo step (a setting, like the brush mode); each committed edit
        records its mode."""
        cyc = self.deformation_cycle()
        at = cyc.index(self.deformation) if self.deformation in cyc else -1
        return self.set_deformation(cyc[(at + 1) % len(cyc)])

    def set_deformation(self, mode) -> DeformationMode:
        """Make ``mode`` (a DeformationMode or its name) the mode of new edits
        (refits when the kind of basis changes, see :meth:`cycle_deformation`).

        Raises:
            SplatEditError: DETAIL for a Gaussian document (nothing changes)."""
        if self.committing:
            return self.deformation
        mode = DeformationMode(mode)
        if mode is DeformationMode.DETAIL and not self.detail_available:
            from splatedit.errors import SplatEditError
            raise SplatEditError(self.DETAIL_UNAVAILABLE)
        self.deformation = mode
        self.request_fit()          # a no-op unless the basis kind changed
        self.on_change()
        return self.deformation

    def distortion(self):
        """:class:`~splatedit.deform.distortion.DistortionStats` of the support
        for the current pose (live manipulation included), else of the last
        committed edit while it is :meth:`shown_edit`; None without either, or
        before the first figures are ready (computed off the UI thread:
        :class:`~splatedit.app.document.distortion_feed.DistortionFeed`)."""
        dc = self.current_dc()
        if dc is not None and dc.any():
            return self._distortion.stats(self.basis, self.cloud, dc)
        last = self.shown_edit()
        return None if last is None else self._distortion.stats(last.basis, last.cloud, last.dc)

    def edit_label(self) -> str:
        """The history name of the edit a commit now makes: the running
        move's (``Grab 0.12``, ``Rotate 45 deg about Z``, ``Scale x1.38``,
        a typed transform), else what the pending pose moves (``Curve``,
        ``Move 2 handles``, ``Curve + 1 handle``)."""
        if self.manip is not None and self.single_rig:
            return self.manip.label()
        hidx, curve = self.basis_groups
        moved = sum(1 for k in hidx if not np.array_equal(self.handle_matrix(k), np.eye(4)))
        parts = (["Curve"] if curve is not None and self.live_curve_moves().any() else [])
        if moved:
            parts.append(f"Move {moved} handle" + ("s" if moved > 1 else ""))
        return " + ".join(parts) or "Edit"

    def remember_edit(self, before, basis, dc) -> None:
        """Keep the edit just committed (``before`` deformed by ``dc`` of
        ``basis``) for :meth:`shown_edit`."""
        cur = self.history.current
        self.last_edit = LastEdit(before, basis, dc, cur.label, len(self.edits), cur)

    def shown_edit(self) -> LastEdit | None:
        """The last committed edit while the document is still what it made
        (no change since: a stroke, an undo, another edit ... ends it) and no
        move is live or pending; else None."""
        last = self.last_edit
        if last is None or self.history.current is not last.state or self.manip is not None or self.pose_pending:
            return None
        return last

    def display_state(self, heat_map: bool) -> tuple:
        """(cloud, basis, dC) the viewport draws: the document with the live
        pose, or with the heat map on and nothing moving, the last committed
        edit's cloud, basis and dC (:meth:`shown_edit`: the same deformed
        surface, its stretch coloured)."""
        last = self.shown_edit() if heat_map else None
        if last is not None and not getattr(last.dc, "curves", ()):
            # (a curve-frame edit is not redrawn from its base on the GPU, which has
            # no frames: the document itself is shown, without the heat colours)
            return last.cloud, last.basis, last.dc
        dc = self.current_dc() if self.basis is not None else None
        if getattr(dc, "curves", ()) and gaussians_of(self.cloud) is None:
            # moved curves in the rotation mode carry frames, which the GPU pass
            # cannot draw: the pose is shown as a CPU-deformed copy (as committed).
            # A Gaussian scene keeps its GPU preview (the linear curve edit): its
            # CPU deformation re-decomposes every Gaussian
            return self._frame_preview(dc), None, None
        return self.cloud, self.basis, dc

    def _frame_preview(self, dc):
        """The document deformed by ``dc`` (a CurveFrameDisplacement) on the
        CPU, kept while the cloud, basis and pose stay the same."""
        key = (self.cloud, self.basis, dc.tobytes())
        cached = getattr(self, "_frame_preview_cache", None)
        if cached is None or cached[0][0] is not key[0] or cached[0][1] is not key[1] or cached[0][2] != key[2]:
            cached = self._frame_preview_cache = (key, self.basis.apply(self.cloud, dc))
        return cached[1]

    # ---------------------------------------------------------------- export
    def edit_script(self):
        from splatedit.script import EditScript, SolverSettings
        return EditScript(tuple(self.edits), SolverSettings(self.method, self.tol, self.max_centers))

    def _selection_counts(self) -> tuple[int, int, tuple[int, ...]]:
        """(support, handle splats, per-handle sizes), counted once per
        selection change (:attr:`version`): the panels ask every frame, and
        counting the masks of a 1M-splat cloud took ~3 ms a frame (issue 19 item 9)."""
        sel = self.selection
        key = (self.version, id(sel), id(sel.support), tuple(id(h) for h in sel.handles))
        cached = getattr(self, "_counts_cache", None)
        if cached is None or cached[0] != key:
            sizes = tuple(int(np.count_nonzero(h)) for h in sel.handles)
            cached = self._counts_cache = (key, (int(np.count_nonzero(sel.support)), sum(sizes), sizes))
        return cached[1]

    def stats(self) -> SessionStats:
        sel = self.selection
        fit = self.fit.stats()
        support, handle, sizes = self._selection_counts()
        return SessionStats(
            state=self.state, support=support, handle=handle, edits=len(self.edits),
            handles=len(sel.handles), active_handle=sel.active,
            handle_sizes=sizes, curve_points=len(self.curve_points),
            pose_pending=self.pose_pending,
            columns=fit.columns if fit is not None else columns_needed(len(sel.nonempty()), len(self.curve_points)),
            fit=fit, progress=self.fit.progress(), error=self.waiting or self.fit_error,
            commit=self.committer.progress())

    def close(self) -> None:
        """Cancel the running fit and commit (a commit's result is dropped:
        the document stays as it was)."""
        self.committer.cancel()
        self.fit.close()
