"""Brush tool: paints the support / the active handle, erases, and runs the
selection tools (grow, shrink, connected, invert); draws the brush cursor
and the last closure's highlight.  The selection editing itself (the
target's rules, strokes and the closure that ends them) is the document's
(:mod:`splatedit.app.document.selection_edit`), called through the tool context."""

from __future__ import annotations

import numpy as np

from splatedit.app.ui import overlay as ov
from splatedit.app.document import selection as seltools
from splatedit.app.tools.pick_brush import stroke_points
from splatedit.app.tools.shapes import Circle, Label, Points
from splatedit.select.selection import HANDLE, SUPPORT
from splatedit.app.ui.keymap import Action, Section
from splatedit.app.tools.base import DragMode, Tool
from splatedit.tolerances import (EDITOR_BRUSH_KEY_STEP, EDITOR_BRUSH_MAX_PX, EDITOR_BRUSH_MIN_PX,
                                  EDITOR_BRUSH_WHEEL_STEP)

ERASE_RGB = (230, 60, 60)


class BrushTool(Tool):
    section = Section.SELECTION

    def __init__(self, ed):
        super().__init__(ed)
        self.radius = 24.0               # pixels
        self.erase_toggle = False
        self._warned_no_graph = False

    def actions(self):
        return {Action.BRUSH_MODE: self.toggle_mode, Action.ERASE_TOGGLE: self.toggle_erase,
                Action.BRUSH_SUPPORT: lambda: self.set_target(SUPPORT),
                Action.BRUSH_HANDLE: lambda: self.set_target(HANDLE),
                Action.NEXT_HANDLE: lambda: self.next_handle(1), Action.PREV_HANDLE: lambda: self.next_handle(-1),
                Action.NEW_HANDLE: self.new_handle, Action.REMOVE_HANDLE: self.remove_handle,
                Action.BRUSH_SMALLER: lambda: self.set_radius(self.radius / EDITOR_BRUSH_KEY_STEP),
                Action.BRUSH_LARGER: lambda: self.set_radius(self.radius * EDITOR_BRUSH_KEY_STEP),
                Action.CLEAR_SELECTION: lambda: self.ctx.document.clear(None),
                Action.CLEAR_HANDLES: lambda: self.ctx.document.clear(HANDLE),
                Action.GROW: lambda: self.selection_tool("grow"),
                Action.SHRINK: lambda: self.selection_tool("shrink"),
                Action.INVERT: lambda: self.selection_tool("invert"),
                Action.SELECT_ALL: lambda: self.selection_tool("all"),
                Action.CONNECTED: lambda: self.selection_tool("connected", *self.ctx.mouse),
                Action.CONNECTED_ALL: lambda: self.selection_tool("connected", *self.ctx.mouse, whole=True)}

    # ------------------------------------------------------------ settings
    @property
    def mode(self) -> str:
        """``BRUSH_3D`` (through) or ``BRUSH_VISIBLE`` (V toggles)."""
        return self.ctx.graphs.mode

    def mode_note(self) -> str | None:
        """While the 3D brush waits for the neighbour graph: what it does
        meanwhile and how far the graph is (shown in the panel), else None."""
        c = self.ctx
        if c.graphs.mode != seltools.BRUSH_3D or c.document is None:
            return None
        done = c.graphs.building(c.document.cloud)
        if done is None:
            return None
        return f"3D brush: visible-only until the neighbour graph is ready ({done * 100:.0f}%)"

    def toggle_mode(self) -> None:
        mode = self.ctx.graphs.toggle_mode()
        self.ctx.say("brush: 3D (everything inside the sphere, front and back)" if mode == seltools.BRUSH_3D
                     else "brush: visible splats only")

    def toggle_erase(self) -> None:
        self.erase_toggle = not self.erase_toggle

    def set_radius(self, r: float) -> None:
        self.radius = float(np.clip(r, EDITOR_BRUSH_MIN_PX, EDITOR_BRUSH_MAX_PX))

    def scroll(self, e) -> None:
        """Ctrl+wheel: brush radius."""
        self.set_radius(self.radius * (EDITOR_BRUSH_WHEEL_STEP ** e.dy))

    def set_target(self, target: str) -> None:
        self.ctx.document.brush_target = target

    def next_handle(self, step: int) -> None:
        s = self.ctx.document
        if len(s.selection.handles) > 1:
            s.cycle_handle(step)
            s.brush_target = HANDLE
        else:
            s.brush_target = HANDLE if s.brush_target == SUPPORT else SUPPORT

    def new_handle(self) -> None:
        s = self.ctx.document
        if s.add_handle():
            self.ctx.say(f"handle {len(s.selection.handles)}: paint it with the handle brush")
        else:
            self.ctx.say("the active handle is empty: paint it with the handle brush")

    def remove_handle(self) -> None:
        s = self.ctx.document
        if s.remove_handle():
            self.ctx.say(f"handle removed ({len(s.selection.handles)} left)")

    def erasing(self) -> bool:
        """A stroke now erases (E on, or Ctrl held)."""
        return self.ctx.erasing()

    # ------------------------------------------------------------ painting
    def paint_at(self, points) -> None:
        c = self.ctx
        s, edit = c.document, c.selection_edit
        erase = self.erasing()
        picker = c.visible()
        three_d = c.graphs.mode == seltools.BRUSH_3D
        graph = c.neighbour_graph() if three_d else None
        if three_d and graph is None and not self._warned_no_graph:
            self._warned_no_graph = True
            c.say("3D brush: the neighbour graph is being built, painting visible splats meanwhile")
        displaced = c.displaced()
        mirror = c.tool("mirror")
        changed = False
        for x, y in points:
            if graph is not None:
                sph = seltools.brush_sphere(picker, c.camera, s.cloud.positions, x, y, self.radius, c.size, displaced)
                idx = seltools.splats_in_sphere(graph.tree, sph) if sph is not None else np.zeros(0, np.int64)
            else:
                idx = picker.query(x, y, self.radius)
            # the dab's 3D reach (its circle through the model): closure may add there only
            reach = None if erase else picker.covered(x, y, self.radius)
            if mirror.painting:             # symmetric painting: the dab's mirror image too
                idx = mirror.with_mirror(idx)
                reach = None if reach is None else mirror.with_mirror(reach)
            changed |= edit.dab(idx, erase=erase, reach=reach)
        if changed:
            c.redraw()

    # ---------------------------------------------------------------- mouse
    def press(self, e):
        if e.button != self.ctx.keys.MOUSE_BUTTON_LEFT:
            return None
        # an erase stroke: the selection before it bounds what closure may give back
        self.ctx.selection_edit.begin_stroke(self.erasing())
        self.paint_at([(e.x, e.y)])
        return DragMode.PAINT

    def drag(self, mode, x, y, dx, dy, last):
        if mode is DragMode.PAINT:
            self.paint_at(stroke_points(last[0], last[1], x, y, self.radius))

    def release(self, mode):
        if mode is not DragMode.PAINT:
            return
        msg = self.ctx.selection_edit.end_stroke()      # closure, one undo step
        if msg:
            self.ctx.say(msg)

    # ------------------------------------------------------ selection tools
    def selection_tool(self, tool: str, x: float | None = None, y: float | None = None,
                       whole: bool = False) -> None:
        """Run ``tool`` ("grow", "shrink", "connected", "invert", "all") on the brush
        target (support or active handle), close the selection: one undo step."""
        c = self.ctx
        s = c.document
        if s.manip is not None:
            return
        target = s.brush_target
        what = "support" if target == SUPPORT else "handle"
        graph = c.neighbour_graph()
        if graph is None and tool not in ("invert", "all"):
            c.say("the neighbour graph is still being built: try again in a moment")
            return
        sel = s.selection
        if tool == "grow":
            mask = seltools.grown(sel, graph, target)
        elif tool == "shrink":
            mask = seltools.shrunk(sel, graph, target)
        elif tool == "invert":
            mask = seltools.inverted(sel, target)
        elif tool == "all":
            mask = seltools.everything(sel, target)
        elif tool == "connected":
            sph = seltools.brush_sphere(c.visible(), c.camera, s.cloud.positions, x, y, self.radius, c.size,
                                        c.displaced())
            if sph is None:
                c.say("select connected: put the cursor on the model")
                return
            reach = None
            if not whole:
                reach = np.zeros(s.cloud.n, bool)
                reach[seltools.splats_in_sphere(graph.tree, sph)] = True
            mask = seltools.target_mask(sel, target) | seltools.connected_region(graph, sph.seed, reach)
        else:
            raise ValueError(tool)
        i = 0 if target == SUPPORT else 1
        before = s.selection.counts[i]
        if not c.select(mask, f"{tool} {what}"):
            c.say(f"{tool}: the {what} did not change")
            return
        n = s.selection.counts[i] - before
        added = c.selection_edit.last_added
        c.say(f"{tool} {what}: {n:+,} splats" + (f", closure added {added:,}" if added else ""))

    # -------------------------------------------------------------- drawing
    def cursor_colour(self) -> tuple:
        if self.erasing():
            return ERASE_RGB
        return ov.SUPPORT_RGB if self.ctx.target == SUPPORT else ov.HANDLE_RGB

    def shapes(self, w, h):
        """What the last closure added (flashes yellow, under everything) and,
        over the model, the brush circle with its mode tag at the cursor."""
        c = self.ctx
        s, out = c.document, []
        hl = c.graphs.highlighted(s.cloud)
        if hl is not None:
            px, d = c.camera.project(s.cloud.positions[hl], w, h)
            out.append(Points(np.where((d > 0)[:, None], px, np.nan), seltools.CLOSURE_RGB))
        if s.manip is not None or not c.pointer_free():
            return out
        rgb = self.cursor_colour()
        (mx, my), r = c.mouse, float(self.radius)
        out.append(Circle((mx, my), r, rgb, 2.0))
        k = r * 0.7071
        out.append(Label((mx + k + 1, my + k + 2), "3D" if self.mode == seltools.BRUSH_3D else "VIS",
                         rgb, size=11, bg_alpha=150))
        return out
