"""Curve tool (K): click points on the support to build a control curve,
drag a dot to bend it; draws the curve as it will act and its dots."""

from __future__ import annotations

import numpy as np

from splatedit.app.ui.keymap import Action, Section
from splatedit.app.tools.shapes import Dot, Polyline
from splatedit.app.tools.base import DragMode, Tool
from splatedit.tolerances import EDITOR_CURVE_DOT_PICK_PX

#: colour of the control curve and its dots
CURVE_RGB = (255, 150, 30)


class CurveTool(Tool):
    section = Section.CURVE

    def actions(self):
        return {Action.CURVE_TOOL: self.toggle, Action.CLEAR_CURVE: lambda: self.ctx.document.clear_curve(),
                Action.REMOVE_CURVE_POINT: self.remove_point}

    def toggle(self) -> None:
        s = self.ctx.document
        s.curve_mode = not s.curve_mode
        self.ctx.say("curve tool: click on the support to add points, drag a dot to bend"
                     if s.curve_mode else "curve tool off")

    def remove_point(self) -> None:
        if self.ctx.document.curve_points:
            self.ctx.document.remove_curve_point()

    # ------------------------------------------------------------ geometry
    def _project(self, pts, w: int, h: int) -> np.ndarray:
        """(m, 2) pixels of world points ``pts`` (m, 3) (NaN behind the eye)."""
        px, d = self.ctx.camera.project(pts, w, h)
        px = np.array(px, float)
        px[np.asarray(d) <= 0] = np.nan
        return px

    def dots(self, w: int, h: int) -> np.ndarray:
        """(k + 1, 2) pixel positions of the (moved) picked curve points (NaN behind the eye)."""
        pts = self.ctx.document.curve_point_positions()
        if not len(pts):
            return np.zeros((0, 2))
        return self._project(pts, w, h)

    def dot_hit(self, x: float, y: float) -> int | None:
        w, h = self.ctx.size
        px = self.dots(w, h)
        if not len(px):
            return None
        with np.errstate(invalid="ignore"):
            d = np.hypot(px[:, 0] - x, px[:, 1] - y)
        d = np.where(np.isfinite(d), d, np.inf)
        j = int(np.argmin(d))
        return j if d[j] <= EDITOR_CURVE_DOT_PICK_PX else None

    # --------------------------------------------------------------- mouse
    def press(self, e):
        c = self.ctx
        s = c.document
        if e.button != c.keys.MOUSE_BUTTON_LEFT or not s.curve_mode:
            return None
        x, y = e.x, e.y
        j = self.dot_hit(x, y)
        if j is not None:
            if s.begin_curve_point(j, c.tool("gizmo").view_info(s.curve_point_positions()[j]), (x, y)):
                c.redraw()
                return DragMode.MANIP
            c.say("the curve is still being fitted" if s.fitting else
                  f"cannot bend: {s.fit_error}" if s.fit_error else "add a second curve point")
            return DragMode.NONE
        i = c.splat_under(x, y)
        if i < 0 or not s.selection.support[i]:
            c.say("curve points go on the support (blue): paint it first (1)")
        elif s.add_curve_point(s.cloud.positions[i]):
            c.redraw()
        return DragMode.NONE

    def release(self, mode):
        self.ctx.tool("gizmo").release(mode)

    # ------------------------------------------------------------- drawing
    def shapes(self, w, h):
        """The control curve c'(t) as a line strip and its picked points as
        dots (the one being dragged white and larger, the one the transform
        fields edit ringed)."""
        s = self.ctx.document
        out = []
        poly = s.curve_polyline()
        if poly is not None:
            out.append(Polyline(self._project(poly, w, h), CURVE_RGB, 3.0, halo=False))
        active = s.manip_target[1] if (s.manip_target and s.manip_target[0] == "curve") else None
        chosen = s.active_curve_point() if s.curve_mode else None     # the transform fields' point: ringed
        for j, q in enumerate(self.dots(w, h)):
            if j == chosen and j != active:
                out.append(Dot(q, (255, 255, 255), 7.0))
            out.append(Dot(q, (255, 255, 255) if j == active else CURVE_RGB, 7.0 if j == active else 5.0))
        return out
