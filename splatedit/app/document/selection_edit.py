"""Selection editing of the document: what the brush and the region tools
(box, lasso, mirror, grow ...) change and how, in one place.

An owned part of :class:`~splatedit.app.document.session.Session`
(``session.selection_edit``, a :class:`SelectionEdit`).  The brush target
(the support or the active handle), strokes (dabs that paint or erase, then
the closure that ends them: :mod:`splatedit.select.closure`, bounded by the
selection before an erase stroke), and whole-mask edits (a region, a
mirror image, grow / shrink ...: the target's new mask, closed and recorded
as one undo step; on a large cloud a copy of the selection is changed and
closed by a worker and installed when it lands, unless the selection changed
meanwhile: :meth:`SelectionEdit.background_select`,
:meth:`SelectionEdit.install`).  Closure needs the cloud's neighbour graph; the
:class:`~splatedit.app.document.selection.SelectionTools` that builds it in the
background is given by the editor (``graphs``); without one (a session in a
test) strokes and edits are recorded unclosed.
"""

from __future__ import annotations

import numpy as np

from splatedit.app.document import selection as seltools
from splatedit.select.selection import SUPPORT


class SelectionEdit:
    """The selection edit API of a :class:`~splatedit.app.document.session.Session`.

    Args:
        session: the document whose ``selection`` it edits.
        graphs: the neighbour-graph and closure service
            (:class:`~splatedit.app.document.selection.SelectionTools`), or None.
    """

    def __init__(self, session, graphs: seltools.SelectionTools | None = None):
        self._s = session
        self.graphs = graphs
        self._before = None         # the selection before an erase stroke (bounds its closure)
        self._changed = False       # the stroke being painted changed the selection
        #: splats the last closure added (0: none, or no graph)
        self.last_added = 0

    # ------------------------------------------------------------ target
    @property
    def target(self) -> str:
        """The brush target: ``"support"`` or ``"handle"`` (the active one)."""
        return self._s.brush_target

    @property
    def target_name(self) -> str:
        return "support" if self._s.brush_target == SUPPORT else "handle"

    def target_mask(self) -> np.ndarray:
        """(n,) bool: the brush target's current mask (not a copy)."""
        return seltools.target_mask(self._s.selection, self._s.brush_target)

    # ----------------------------------------------------- whole-mask edits
    def select(self, mask: np.ndarray, label: str) -> bool:
        """Make the brush target's mask ``mask`` (n,) bool with the brush
        rules, close the selection and record it as one undo step; False when
        nothing changed (or a move runs / an edit is applied)."""
        s = self._s
        if s.manip is not None or s.committing:
            return False
        if self.graphs is not None:
            ok = self.graphs.apply(s, s.brush_target, mask, label)
            self.last_added = self.graphs.last_added if ok else 0
            return ok
        if not seltools.set_target(s.selection, s.brush_target, mask):
            return False
        self.last_added = 0
        s.version += 1
        s.push(label)
        return True

    def background_select(self):
        """A :class:`~splatedit.app.document.selection.BackgroundApply` of the
        brush target (the selection copied now, to be changed and closed by a
        worker), or None while the neighbour graph is built (or without a
        graph service)."""
        return None if self.graphs is None else self.graphs.background_apply(self._s)

    def install(self, job, label: str) -> bool:
        """Make a finished background edit's selection this document's (one
        undo step, ``label``); False when it belongs to another document, the
        selection changed since it started, a move runs, or it changed nothing."""
        if self.graphs is None or job.session is not self._s:
            return False
        ok = self.graphs.install(job, label)
        self.last_added = self.graphs.last_added if ok else 0
        return ok

    # ------------------------------------------------------------ strokes
    def begin_stroke(self, erase: bool) -> None:
        """A brush stroke starts (``erase``: it removes splats; the selection
        before it then bounds what closure may give back)."""
        self._changed = False
        self._before = self._s.selection.copy() if erase else None

    def dab(self, indices, erase: bool = False, reach=None) -> bool:
        """Paint (or erase) ``indices`` of the brush target
        (:meth:`Session.paint`; ``reach``: the splats the dab covered at any
        depth); True when the selection changed."""
        changed = self._s.paint(indices, erase=erase, reach=reach)
        self._changed |= changed
        return changed

    def end_stroke(self) -> str:
        """The stroke ends: close the selection (an erase stroke: within the
        selection before it) and record one undo step when it changed.
        Returns the status line to show ("" when there is nothing to say)."""
        s, before = self._s, self._before
        changed, self._before, self._changed = self._changed, None, False
        msg = ""
        if changed and self.graphs is not None:
            if before is not None:
                self.graphs.close(s, within=before)
                msg = seltools.erase_message(seltools.target_mask(before, s.brush_target),
                                             self.target_mask(), self.target_name)
            else:
                added = self.graphs.close(s)
                if added:
                    msg = f"closure added {added:,} splats"
        s.end_stroke(changed)
        return msg

    def close_pending(self) -> int:
        """The neighbour graph arrived after a selection change: close it now
        (one undo step, "fill holes"); returns the splats it added."""
        s = self._s
        if s.manip is not None or self.graphs is None:
            return 0
        n = self.graphs.close(s)
        if n:
            s.push("fill holes")
        return n or 0
