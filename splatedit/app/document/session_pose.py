"""The session's pose and manipulation: pending matrices per handle and
moves per curve point, a running G/R/S move, finishing it and committing
the whole pose as one edit.

An object a :class:`~splatedit.app.document.session.Session` owns (``session.pose_part``;
the pose itself lives in ``session.rig``, the running move in
``session.manip``); the session's pose, move and commit methods delegate to
it.  Ending
a manipulation of a single-handle rig without curve commits at once;
otherwise it is kept in the pose until :meth:`PoseEditing.commit` (Enter).
A commit records a script edit (``indices`` support and handles,
``matrix`` transforms, ``curves``) so the saved cloud can be replayed.
"""

from __future__ import annotations

import time

import numpy as np

from splatedit.app.document.manipulation import GRAB, Manipulation, ViewInfo
from splatedit.app.document.rig import matrix_tuple
from splatedit.errors import SplatEditError


class PoseEditing:
    """Pose, manipulation, finish and commit of a Session.

    Args:
        session: the :class:`~splatedit.app.document.session.Session` whose pose (in its
            rig), running move (``manip``, ``manip_target``) and committed edits
            it changes; a commit lands through its ``push`` and ``remember_edit``.
    """

    def __init__(self, session):
        self.s = session
        self._rig_before_commit = None      # the rig as it was when a background commit started

    # ------------------------------------------------------------------ pose
    @property
    def single_rig(self) -> bool:
        """One handle and no curve: ending a manipulation commits at once."""
        return len(self.s.selection.handles) == 1 and not self.s.curve_points

    @property
    def pose_pending(self) -> bool:
        """Some handle or curve point has a pending (uncommitted) move."""
        return self.s.rig.pending

    def handle_matrix(self, k: int, live: bool = True) -> np.ndarray:
        """Pending matrix of handle ``k`` (with the running manipulation when ``live``)."""
        m = self.s.pose[k] if k < len(self.s.pose) else np.eye(4)
        if live and self.s.manip is not None and self.s.manip_target == ("handle", k):
            m = self.s.manip.matrix() @ m
        return m

    def live_curve_moves(self, live: bool = True) -> np.ndarray:
        mv = self.s.curve_moves.copy()
        if live and self.s.manip is not None and self.s.manip_target and self.s.manip_target[0] == "curve":
            j = self.s.manip_target[1]
            p = self.s.curve_points[j] + mv[j]
            m = self.s.manip.matrix()
            mv[j] = m[:3, :3] @ p + m[:3, 3] - self.s.curve_points[j]
        return mv

    def inputs(self, live: bool = True) -> list:
        """Per-group inputs of ``basis.displacement`` (fitted handles, then the curve)."""
        hidx, curve = self.s.basis_groups
        out = [self.handle_matrix(k, live) for k in hidx]
        if curve is not None:
            out.append(self.live_curve_moves(live))  # the curve's controls are its picked points
        return out

    def reset_pose(self) -> bool:
        """Discard the pending transforms and curve moves (an undo step)."""
        if self.committing:
            return False
        if self.s.manip is not None:
            self.cancel()
        if not self.pose_pending:
            return False
        self.s.rig.reset_pose(len(self.s.selection.handles))
        self.s.push("reset pose")
        return True

    # ---------------------------------------------------------- manipulation
    def handle_centroid(self, k: int | None = None) -> np.ndarray:
        """Centroid of handle ``k`` (default: the active one) moved by its pending matrix."""
        k = self.s.selection.active if k is None else k
        c = self.s.cloud.positions[self.s.selection.handles[k]].mean(axis=0)
        m = self.s.pose[k] if k < len(self.s.pose) else np.eye(4)
        return m[:3, :3] @ c + m[:3, 3]

    def active_fitted(self) -> bool:
        """The active handle is part of the fitted basis."""
        return self.s.basis is not None and self.s.selection.active in self.s.basis_groups[0]

    def begin(self, mode: str, view: ViewInfo, mouse: tuple[float, float], pivot=None, frame=None,
              frame_name: str = "") -> bool:
        """Start G/R/S of the active handle (needs a basis that includes it)
        about ``pivot`` ((3,) model units; None: the handle's posed centroid),
        constraint axes the columns of ``frame`` ((3, 3); None: the world's)."""
        if self.s.manip is not None or self.committing or self.s.waiting or not self.active_fitted():
            return False
        piv = self.handle_centroid() if pivot is None else np.asarray(pivot, float)
        self.s.manip = Manipulation(mode, piv, view, mouse, frame=None if frame is None else np.asarray(frame, float),
                                  frame_name=frame_name)
        self.s.manip_target = ("handle", self.s.selection.active)
        return True

    def begin_curve_point(self, j: int, view: ViewInfo, mouse: tuple[float, float]) -> bool:
        """Start dragging picked curve point ``j`` (needs a basis with the curve)."""
        if self.s.manip is not None or self.committing or self.s.basis is None or self.s.basis_groups[1] is None:
            return False
        if not 0 <= j < len(self.s.curve_points):
            return False
        self.s.manip = Manipulation(GRAB, self.s.curve_points[j] + self.s.curve_moves[j], view, mouse)
        self.s.manip_target = ("curve", int(j))
        self.s.curve_active = int(j)
        return True

    def current_matrix(self) -> np.ndarray:
        return np.eye(4) if self.s.manip is None else self.s.manip.matrix()

    def current_dc(self):
        """dC of the whole pose, live manipulation included (None without
        basis), in the session's :attr:`deformation` mode (a
        RotationDisplacement in rotation mode)."""
        if self.s.basis is None:
            return None
        return self.s.basis.displacement(self.inputs(), mode=self.s.deformation)

    def cancel(self) -> None:
        self.s.manip = None
        self.s.manip_target = None
        self.s.on_change()

    def _check_manip(self) -> None:
        """Raise SplatEditError (state unchanged) when the running manipulation's
        typed value cannot be applied (e.g. a scale factor <= 0)."""
        bad = self.s.manip.problem() if self.s.manip is not None else None
        if bad:
            raise SplatEditError(bad)

    def _bake(self) -> None:
        """Store the running manipulation in the pose."""
        t = self.s.manip_target
        if t[0] == "handle":
            self.s.pose[t[1]] = self.handle_matrix(t[1])
        else:
            self.s.curve_moves = self.live_curve_moves()
        self.s.manip = None
        self.s.manip_target = None

    def finish(self) -> str:
        """End the running manipulation: commit at once for a single-handle
        rig ("commit", or "" when nothing moved); else keep it in the pose
        ("pose") for a later :meth:`commit`."""
        if self.s.manip is None:
            return ""
        self._check_manip()
        if self.single_rig:
            return "commit" if self.commit() else ""
        moved = not np.array_equal(self.s.manip.matrix(), np.eye(4))
        t = self.s.manip_target
        what = f"{self.s.manip.label()} ({'handle' if t[0] == 'handle' else 'curve point'} {t[1] + 1}, pending)"
        self._bake()
        if moved:
            self.s.push(what)
        else:
            self.s.on_change()
        return "pose" if moved else ""

    def commit(self) -> bool:
        """Apply the pose (running manipulation included) as one edit: the
        deformed cloud becomes the new base, the edit is recorded, support and
        handles are kept, the curve is consumed.  Raises InputError (state
        unchanged) when a splat degenerates.

        A commit estimated at ``commit_sync_ms`` or more
        (:func:`~splatedit.app.document.commit_job.estimate_ms`) runs in the background
        (:attr:`committing`; True is returned at once): the running
        manipulation is stored in the pose, so the viewport keeps drawing the
        edit; :meth:`poll` lands it (the same single undo step) or, on an
        error, restores the pose as it was before the manipulation and leaves
        :attr:`commit_outcome` for the editor to show."""
        if self.s.basis is None or self.committing:
            return False
        self._check_manip()
        plan = self.commit_plan()
        if plan is None:
            self.s.manip = None
            self.s.manip_target = None
            self.s.on_change()
            return False
        if plan.estimate_ms() < self.s.commit_sync_ms:
            t0 = time.perf_counter()
            # the same arrays and the same checks as ``splatedit deform`` and as reading the
            # saved file: the whole cloud is validated (SplatCloud.validate: the minimum axis
            # length is relative to the *whole* cloud's diagonal, which the edit may change);
            # a Gaussian document: the Gaussians deformed on the CPU (covariances, SH) and re-wrapped
            new = plan.run()     # raises InputError on a degenerate splat (nothing changed)
            self.s.last_commit_seconds = time.perf_counter() - t0
            self.s.manip = None
            self.s.manip_target = None
            self._land(plan, new)
            return True
        self._rig_before_commit = self.s.rig.as_tuple()
        if self.s.manip is not None:
            self._bake()            # the pose now draws exactly the frozen edit
        self.s.committer.start(plan)
        self.s.on_change()
        return True

    def commit_plan(self):
        """The pose frozen as a :class:`~splatedit.app.document.commit_job.CommitPlan`
        (None when nothing moves)."""
        from splatedit.app.document.commit_job import CommitPlan
        from splatedit.script import Curve, Edit, Matrix
        from splatedit.select.regions import Indices
        label = self.s.edit_label()                     # before the running move is baked
        inputs = self.inputs(live=True)
        moves = self.live_curve_moves(live=True)
        hidx, curve = self.s.basis_groups
        mats = inputs[:len(hidx)]
        if all(np.array_equal(m, np.eye(4)) for m in mats) and not (curve is not None and moves.any()):
            return None
        dc = self.s.basis.displacement(inputs, mode=self.s.deformation)
        sel = self.s.selection
        support, handles = sel.support.copy(), [sel.handles[k].copy() for k in hidx]
        curves = ()
        if curve is not None:
            curves = (Curve(tuple(tuple(float(x) for x in p) for p in self.s.curve_points),
                            tuple(tuple(float(x) for x in d) for d in moves), None),)
        matrices = tuple(Matrix(matrix_tuple(m)) for m in mats)
        mode = self.s.deformation

        def make_edit():
            idx = lambda m: Indices(tuple(int(i) for i in np.flatnonzero(m)))  # noqa: E731
            return Edit(idx(support), tuple(idx(h) for h in handles), matrices, "$", curves,
                        fill_holes=False,  # the editor's closed selection, replayed as is
                        deformation=mode)
        return CommitPlan(self.s.basis, self.s.cloud, dc, make_edit, len(sel.handles), label, self.s.deformation,
                          tuple(mats) if curve is None or not moves.any() else ())

    def _land(self, plan, result) -> None:
        """``result`` = (deformed cloud, script Edit) of ``plan`` becomes the
        document (one undo step)."""
        new, edit = result
        self.s.cloud = new
        self.s.edits = self.s.edits + (edit,)
        self.s.fit.clear()
        self.s.rig.reset_pose(plan.handles)
        self.s.rig.clear_curve()
        self.s.push(plan.label)
        if plan.outcome.get("refined"):
            # a refined translation (splatedit.deform.refine) is not what the basis
            # and dC draw: its figures and heat map are not shown after the commit
            self.s.last_edit = None
        else:
            self.s.remember_edit(plan.cloud, plan.basis, plan.dc)

    @property
    def committing(self) -> bool:
        """A commit is running in the background (document changes are refused)."""
        return self.s.committer.running

    def poll_commit(self) -> bool:
        """Land a finished background commit (or restore the pose after its
        error, :attr:`commit_outcome`); True when the state changed."""
        from splatedit.app.document.commit_job import CommitOutcome
        got = self.s.committer.collect()
        if got is None:
            return False
        plan, new, error, seconds = got
        if error is None:
            self.s.last_commit_seconds = seconds
            self._land(plan, new)
        else:
            self.s.rig.restore(self._rig_before_commit)
            self.s.version += 1
            self.s.on_change()
        self.s.commit_outcome = CommitOutcome(error, seconds, len(self.s.edits))
        return True

    def wait_commit(self, timeout: float = 120.0) -> bool:
        """Block until a background commit lands (tests, scripted use); True when none is left."""
        self.s.committer.wait(timeout)
        self.poll_commit()
        return not self.committing
