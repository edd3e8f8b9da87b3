"""The session's history: snapshots of the document, push / undo / redo.

An object a :class:`~splatedit.app.document.session.Session` owns
(``session.history_part``; ``session.history`` is the snapshot stack,
:class:`~splatedit.app.document.history.History`).  It works on the session's
``cloud``, ``selection``, ``rig``, ``edits``, ``history`` and ``version``;
the session's ``push``, ``undo``, ``redo``, ``adopt_recovered`` and
``dirty`` delegate to it.  Every user action that changes the document pushes a
:class:`~splatedit.app.document.history.Snapshot`; undo / redo restore one and
restart the fit for the restored selection.
"""

from __future__ import annotations

from splatedit.app.document.history import Snapshot
from splatedit.select.selection import Selection


class SessionHistory:
    """Snapshots, push, undo, redo and the unsaved-changes flag of a Session.

    Args:
        session: the :class:`~splatedit.app.document.session.Session` whose document it
            records and restores (a restore also cancels its manipulation and
            restarts its fit).
    """

    def __init__(self, session):
        self.s = session

    # ---------------------------------------------------------- snapshots
    def snapshot(self, label: str) -> Snapshot:
        """The session's document now, as a history step named ``label``."""
        s = self.s
        return Snapshot.make(s.cloud, s.selection.support, s.selection.handles, s.edits,
                             label, active=s.selection.active, rig=s.rig.as_tuple(),
                             memory=s.selection.memory())

    def _restore(self, snap: Snapshot) -> None:
        ses = self.s
        ses.cloud = snap.cloud
        s, _ = snap.masks()
        ses.selection = Selection(len(s), s, handles=snap.handle_masks(), active=snap.active)
        ses.selection.set_memory(snap.memory)
        ses.rig.restore(snap.rig)
        self._sync_pose()
        ses.edits = snap.edits
        ses.manip = None
        ses.manip_target = None
        ses.version += 1
        ses.request_fit()
        ses.on_change()

    def _sync_pose(self) -> None:
        self.s.rig.sync_pose(len(self.s.selection.handles))

    def push(self, label: str) -> None:
        """Record the current state (after a stroke, clear, pose change or commit)."""
        ses = self.s
        self._sync_pose()
        ses.history.push(self.snapshot(label))
        ses.version += 1
        ses.request_fit()
        ses.on_change()

    def undo(self) -> bool:
        """Cancel a running move, else step back (False: nothing to undo, or a commit runs)."""
        ses = self.s
        if ses.committing:
            return False
        if ses.manip is not None:
            ses.cancel()
            return True
        snap = ses.history.undo()
        if snap is None:
            return False
        self._restore(snap)
        return True

    def redo(self) -> bool:
        """Step forward (False: nothing to redo, a move or a commit runs)."""
        ses = self.s
        if ses.manip is not None or ses.committing:
            return False
        snap = ses.history.redo()
        if snap is None:
            return False
        self._restore(snap)
        return True

    def adopt_recovered(self, script, label: str) -> None:
        """Make ``script``'s edits (an EditScript from a recovery entry,
        :mod:`splatedit.app.document.recovery`) this document's committed edits, with
        its solver settings: the history restarts at one unsaved step
        ``label``, so a save writes the model and a script that replays from
        the original source."""
        ses = self.s
        ses.edits = tuple(script.edits)
        ses.method, ses.tol, ses.max_centers = script.solver.method, script.solver.tol, script.solver.max_centers
        ses.history.reset(self.snapshot(label))
        ses.history.saved_pos = -1
        ses.version += 1
        ses.on_change()

    @property
    def dirty(self) -> bool:
        """Unsaved changes (a commit still running counts: quitting asks first)."""
        return self.s.history.geometry_dirty or self.s.committing
