"""The session's history: snapshots of the document, push / undo / redo.

A part of :class:`~splatedit.app.session.Session` (mixed into it; it works
on the session's ``cloud``, ``selection``, ``rig``, ``edits`` and
``history``).  Every user action that changes the document pushes a
:class:`~splatedit.app.history.Snapshot`; undo / redo restore one and
restart the fit for the restored selection.
"""

from __future__ import annotations

from splatedit.app.history import Snapshot
from splatedit.select.selection import Selection


class SessionHistory:
    """Snapshots, push, undo, redo and the unsaved-changes flag of a Session."""

    # ---------------------------------------------------------- snapshots
    def _snapshot(self, label: str) -> Snapshot:
        return Snapshot.make(self.cloud, self.selection.support, self.selection.handles, self.edits,
                             label, active=self.selection.active, rig=self.rig.as_tuple(),
                             memory=self.selection.memory())

    def _restore(self, snap: Snapshot) -> None:
        self.cloud = snap.cloud
        s, _ = snap.masks()
        self.selection = Selection(len(s), s, handles=snap.handle_masks(), active=snap.active)
        self.selection.set_memory(snap.memory)
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
        if self.committing:
            return False
        if self.manip is not None:
            self.cancel()
            return True
        snap = self.history.undo()
        if snap is None:
            return False
        self._restore(snap)
        return True

    def redo(self) -> bool:
        if self.manip is not None or self.committing:
            return False
        snap = self.history.redo()
        if snap is None:
            return False
        self._restore(snap)
        return True

    def adopt_recovered(self, script, label: str) -> None:
        """Make ``script``'s edits (an EditScript from a recovery entry,
        :mod:`splatedit.app.recovery`) this document's committed edits, with
        its solver settings: the history restarts at one unsaved step
        ``label``, so a save writes the model and a script that replays from
        the original source."""
        self.edits = tuple(script.edits)
        self.method, self.tol, self.max_centers = script.solver.method, script.solver.tol, script.solver.max_centers
        self.history.reset(self._snapshot(label))
        self.history.saved_pos = -1
        self.version += 1
        self.on_change()

    @property
    def dirty(self) -> bool:
        """Unsaved changes (a commit still running counts: quitting asks first)."""
        return self.history.geometry_dirty or self.committing
