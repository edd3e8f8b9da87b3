"""Editing the session's rig: handles (add, remove, select) and the
control curve's picked points (add, remove, clear, positions, polyline).

An object a :class:`~splatedit.app.document.session.Session` owns (``session.rig_part``;
``session.rig`` is the rig's state, :class:`~splatedit.app.document.rig.Rig`); the
session's handle and curve methods delegate to it.  The
rig's columns are checked against ``RENDER_MAX_BASIS_COLUMNS`` before a
handle or a curve point is added: 4 per handle, k + 1 for a curve of
k + 1 >= 2 points.
"""

from __future__ import annotations

import numpy as np

from splatedit.deform.modes import DeformationMode
from splatedit.errors import SplatEditError
from splatedit.select.selection import HANDLE
from splatedit.tolerances import RENDER_MAX_BASIS_COLUMNS

#: basis columns per rigid handle
HANDLE_COLUMNS = 4
#: at most this many picked points per control curve
MAX_CURVE_POINTS = 16


def columns_needed(n_handles: int, n_curve_points: int) -> int:
    """Basis columns of a rig: 4 per handle, k + 1 for a curve of k + 1 >= 2 points."""
    return HANDLE_COLUMNS * n_handles + (n_curve_points if n_curve_points >= 2 else 0)


class RigEditing:
    """Handles and curve points of a Session (each change is an undo step).

    Args:
        session: the :class:`~splatedit.app.document.session.Session` whose selection's
            handles and rig's curve points it edits (refused while a move or
            a commit runs, as every change of the document).
    """

    def __init__(self, session):
        self.s = session

    # -------------------------------------------------------------- handles
    def _check_columns(self, n_handles: int, n_points: int, what: str) -> None:
        k = columns_needed(n_handles, n_points)
        if k > RENDER_MAX_BASIS_COLUMNS:
            raise SplatEditError(
                f"cannot {what}: the basis would need {k} columns (4 per handle + 1 per curve point "
                f"from 2 points on), at most {RENDER_MAX_BASIS_COLUMNS} are supported")

    def _n_handles_planned(self) -> int:
        """Handles that take basis columns (all but a lone empty one)."""
        hs = self.s.selection.handles
        return len(hs) if (len(hs) > 1 or hs[0].any()) else 0

    def add_handle(self) -> bool:
        """Start a new handle (active; the brush then paints it).  An empty
        active handle is reused.  Raises SplatEditError over 16 columns."""
        if self.s.manip is not None or self.s.committing:
            return False
        self.s.brush_target = HANDLE
        if not self.s.selection.handle.any():
            return False
        self._check_columns(len(self.s.selection.handles) + 1, len(self.s.curve_points), "add a handle")
        self.s.selection.add_handle()
        self.s.push("new handle")
        return True

    def remove_handle(self) -> bool:
        """Remove the active handle (and its pending transform)."""
        if self.s.manip is not None or self.s.committing:
            return False
        i = self.s.selection.active
        several = len(self.s.selection.handles) > 1
        if not self.s.selection.remove_handle(i):
            return False
        if several:
            del self.s.pose[i]
        else:
            self.s.pose = [np.eye(4)]
        self.s.push("remove handle")
        return True

    def select_handle(self, i: int) -> bool:
        """Make handle ``i`` (modulo the count) the active one (not an undo step)."""
        if self.s.manip is not None or self.s.committing or not self.s.selection.select_handle(i):
            return False
        self.s.version += 1
        self.s.on_change()
        return True

    def cycle_handle(self, step: int = 1) -> bool:
        """Make the handle ``step`` after the active one active (not an undo step)."""
        return self.select_handle(self.s.selection.active + step)

    # ---------------------------------------------------------------- curve
    def curve(self):
        """The :class:`ControlCurve` through the picked points (None below 2)."""
        return self.s.rig.curve()

    def add_curve_point(self, point) -> bool:
        """Append a picked point (2..16 per curve; consecutive ones distinct)."""
        if self.s.manip is not None or self.s.committing:
            return False
        p = np.array(point, dtype=np.float64).reshape(3)
        if len(self.s.curve_points) >= MAX_CURVE_POINTS:
            raise SplatEditError(f"a curve has at most {MAX_CURVE_POINTS} points")
        self._check_columns(self._n_handles_planned(), len(self.s.curve_points) + 1, "add a curve point")
        if self.s.curve_points:
            from splatedit.deform.curves import first_coincident_point
            # the same check (consecutive points distinct) as building the curve
            if first_coincident_point(np.array(self.s.curve_points + [p])) is not None:
                raise SplatEditError("this point is the curve's last point: pick another one")
        self.s.curve_points.append(p)
        self.s.curve_moves = np.vstack([self.s.curve_moves, np.zeros((1, 3))])
        self.s.curve_active = len(self.s.curve_points) - 1
        self.s.push("curve point")
        return True

    def remove_curve_point(self) -> bool:
        """Remove the last picked point."""
        if self.s.manip is not None or self.s.committing or not self.s.curve_points:
            return False
        self.s.curve_points.pop()
        self.s.curve_moves = self.s.curve_moves[:-1].copy()
        self.s.push("remove curve point")
        return True

    def clear_curve(self) -> bool:
        """Remove every picked point."""
        if self.s.manip is not None or self.s.committing or not self.s.curve_points:
            return False
        self.s.rig.clear_curve()
        self.s.push("clear curve")
        return True

    def active_curve_point(self) -> int | None:
        """Index of the picked point the transform fields edit (the last one
        added, dragged or chosen), None without curve points."""
        if not self.s.curve_points:
            return None
        return min(max(int(self.s.curve_active), 0), len(self.s.curve_points) - 1)

    def select_curve_point(self, j: int) -> bool:
        """Make picked point ``j`` (modulo the count) the active one (not an undo step)."""
        if not self.s.curve_points:
            return False
        self.s.curve_active = int(j) % len(self.s.curve_points)
        self.s.on_change()
        return True

    def curve_point_positions(self, live: bool = True) -> np.ndarray:
        """(k + 1, 3) current (moved) picked points."""
        if not self.s.curve_points:
            return np.zeros((0, 3))
        return np.array(self.s.curve_points) + self.s.live_curve_moves(live)

    def curve_polyline(self, count: int = 160, live: bool = True) -> np.ndarray | None:
        """(>= count, 3) points of the moved curve for drawing (through every
        moved picked point; None below 2 points): in the linear mode
        ``c'(t) = c(t) + W(t) dq``, exactly the targets the fitted deformation
        gives the curve's samples; otherwise the curve whose frame the splats
        follow, the Catmull-Rom spline through the moved points
        (:mod:`splatedit.deform.curve_frames`)."""
        c = self.curve()
        if c is None:
            return None
        t = np.union1d(np.linspace(0.0, 1.0, count), c.params)
        moved = c.points + self.s.live_curve_moves(live)
        if self.s.deformation is DeformationMode.LINEAR:
            return c.evaluate(t, moved)
        return c.shape_weights(t) @ moved
