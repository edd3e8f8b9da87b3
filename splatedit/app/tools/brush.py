"""Brush tool: paints the support / the active handle, erases, and runs the
selection tools (grow, shrink, connected, invert) with closure; owns the
pick map of the current view and the brush cursor overlay."""

from __future__ import annotations

import numpy as np

from splatedit.app.ui import overlay as ov
from splatedit.app.document import revision
from splatedit.app.document import selection as seltools
from splatedit.app.tools.pick_brush import BrushPicker, picker_for_view, stroke_points
from splatedit.select.selection import HANDLE, SUPPORT
from splatedit.app.ui.keymap import Action, Section
from splatedit.app.tools.base import DragMode, Tool
from splatedit.tolerances import (EDITOR_BRUSH_KEY_STEP, EDITOR_BRUSH_MAX_PX, EDITOR_BRUSH_MIN_PX,
                                  EDITOR_BRUSH_WHEEL_STEP, EDITOR_PICK_TOL_PX)

ERASE_RGB = (230, 60, 60)


class BrushTool(Tool):
    section = Section.SELECTION

    def __init__(self, ed):
        super().__init__(ed)
        self.radius = 24.0               # pixels
        self.erase_toggle = False
        self.stroke_changed = False
        self.stroke_before = None      # the selection before an erase stroke (Selection)
        self.picker: BrushPicker | None = None
        self.picker_key = None
        self.tools = seltools.SelectionTools(ed.start_graph_job)
        self._warned_no_graph = False

    def actions(self):
        return {Action.BRUSH_MODE: self.toggle_mode, Action.ERASE_TOGGLE: self.toggle_erase,
                Action.BRUSH_SUPPORT: lambda: self.set_target(SUPPORT),
                Action.BRUSH_HANDLE: lambda: self.set_target(HANDLE),
                Action.NEXT_HANDLE: lambda: self.next_handle(1), Action.PREV_HANDLE: lambda: self.next_handle(-1),
                Action.NEW_HANDLE: self.new_handle, Action.REMOVE_HANDLE: self.remove_handle,
                Action.BRUSH_SMALLER: lambda: self.set_radius(self.radius / EDITOR_BRUSH_KEY_STEP),
                Action.BRUSH_LARGER: lambda: self.set_radius(self.radius * EDITOR_BRUSH_KEY_STEP),
                Action.CLEAR_SELECTION: lambda: self.session.clear(None),
                Action.CLEAR_HANDLES: lambda: self.session.clear(HANDLE),
                Action.GROW: lambda: self.selection_tool("grow"),
                Action.SHRINK: lambda: self.selection_tool("shrink"),
                Action.INVERT: lambda: self.selection_tool("invert"),
                Action.SELECT_ALL: lambda: self.selection_tool("all"),
                Action.CONNECTED: lambda: self.selection_tool("connected", *self.ed.mouse),
                Action.CONNECTED_ALL: lambda: self.selection_tool("connected", *self.ed.mouse, whole=True)}

    # ------------------------------------------------------------ settings
    @property
    def mode(self) -> str:
        return self.tools.mode

    def mode_note(self) -> str | None:
        """While the 3D brush waits for the neighbour graph: what it does
        meanwhile and how far the graph is (shown in the panel), else None."""
        if self.tools.mode != seltools.BRUSH_3D or self.ed.session is None:
            return None
        done = self.tools.building(self.session.cloud)
        if done is None:
            return None
        return f"3D brush: visible-only until the neighbour graph is ready ({done * 100:.0f}%)"

    def toggle_mode(self) -> None:
        mode = self.tools.toggle_mode()
        self.ed.say("brush: 3D (everything inside the sphere, front and back)" if mode == seltools.BRUSH_3D
                    else "brush: visible splats only")

    def toggle_erase(self) -> None:
        self.erase_toggle = not self.erase_toggle

    def set_radius(self, r: float) -> None:
        self.radius = float(np.clip(r, EDITOR_BRUSH_MIN_PX, EDITOR_BRUSH_MAX_PX))

    def scroll(self, e) -> None:
        """Ctrl+wheel: brush radius."""
        self.set_radius(self.radius * (EDITOR_BRUSH_WHEEL_STEP ** e.dy))

    def set_target(self, target: str) -> None:
        self.session.brush_target = target

    def next_handle(self, step: int) -> None:
        s = self.session
        if len(s.selection.handles) > 1:
            s.cycle_handle(step)
            s.brush_target = HANDLE
        else:
            s.brush_target = HANDLE if s.brush_target == SUPPORT else SUPPORT

    def new_handle(self) -> None:
        s = self.session
        if s.add_handle():
            self.ed.say(f"handle {len(s.selection.handles)}: paint it with the handle brush")
        else:
            self.ed.say("the active handle is empty: paint it with the handle brush")

    def remove_handle(self) -> None:
        s = self.session
        if s.remove_handle():
            self.ed.say(f"handle removed ({len(s.selection.handles)} left)")

    def erasing(self) -> bool:
        return self.erase_toggle or bool(self.ed.window.mods() & self.ed.g.MOD_CONTROL)

    # ------------------------------------------------------------- picking
    def pick_key(self) -> tuple:
        """What the pick map depends on: camera, size, the cloud's and the
        basis' revisions, the displacement drawn."""
        ed, s = self.ed, self.session
        w, h = ed.size
        dc = ed.viewport.dc
        return (ed.cam.state(), w, h, revision.of(s.cloud), revision.of(s.basis),
                None if dc is None or not dc.any() else dc.tobytes())

    def picker_current(self) -> bool:
        return self.picker is not None and self.picker_key == self.pick_key()

    def get_picker(self) -> BrushPicker:
        ed, s = self.ed, self.session
        w, h = ed.size
        key = self.pick_key()
        if self.picker is None or self.picker_key != key:
            ready = ed.frames.take_pick(key)     # drawn in chunks after the view's refinement
            idx, front = ready if ready is not None else ed.viewport.pick(ed.cam, w, h)
            self.picker = picker_for_view(idx, front, ed.cam, s.cloud.positions, s.cloud.radii, EDITOR_PICK_TOL_PX)
            self.picker_key = key
        return self.picker

    def splat_under(self, x: float, y: float) -> int:
        p = self.get_picker().pick
        ix, iy = int(x), int(y)
        if 0 <= iy < p.shape[0] and 0 <= ix < p.shape[1]:
            return int(p[iy, ix])
        return -1

    def _displaced(self) -> bool:
        dc = self.ed.viewport.dc
        return dc is not None and bool(dc.any())

    def paint_at(self, points) -> None:
        ed, s = self.ed, self.session
        erase = self.erasing()
        picker = self.get_picker()
        graph = self.tools.graph(s.cloud) if self.tools.mode == seltools.BRUSH_3D else None
        if self.tools.mode == seltools.BRUSH_3D and graph is None and not self._warned_no_graph:
            self._warned_no_graph = True
            ed.say("3D brush: the neighbour graph is being built, painting visible splats meanwhile")
        displaced = self._displaced()
        changed = False
        for x, y in points:
            if graph is not None:
                sph = seltools.brush_sphere(picker, ed.cam, s.cloud.positions, x, y, self.radius, ed.size, displaced)
                idx = seltools.splats_in_sphere(graph.tree, sph) if sph is not None else np.zeros(0, np.int64)
            else:
                idx = picker.query(x, y, self.radius)
            # the dab's 3D reach (its circle through the model): closure may add there only
            reach = None if erase else picker.covered(x, y, self.radius)
            if ed.mirror.painting:             # symmetric painting: the dab's mirror image too
                idx = ed.mirror.with_mirror(idx)
                reach = None if reach is None else ed.mirror.with_mirror(reach)
            changed |= s.paint(idx, erase=erase, reach=reach)
        if changed:
            self.stroke_changed = True
            ed.motion()

    # ---------------------------------------------------------------- mouse
    def press(self, e):
        if e.button != self.ed.g.MOUSE_BUTTON_LEFT:
            return None
        self.stroke_changed = False
        # an erase stroke: the selection before it bounds what closure may give back
        self.stroke_before = self.session.selection.copy() if self.erasing() else None
        self.paint_at([(e.x, e.y)])
        return DragMode.PAINT

    def drag(self, mode, x, y, dx, dy, last):
        if mode is DragMode.PAINT:
            self.paint_at(stroke_points(last[0], last[1], x, y, self.radius))

    def release(self, mode):
        if mode is not DragMode.PAINT:
            return
        s = self.session
        before, self.stroke_before = self.stroke_before, None
        if self.stroke_changed and before is not None:
            target = lambda sel: sel.support if s.brush_target == SUPPORT else sel.handle  # noqa: E731
            self.tools.close(s, within=before)
            msg = seltools.erase_message(target(before), target(s.selection),
                                         "support" if s.brush_target == SUPPORT else "handle")
            if msg:
                self.ed.say(msg)
        elif self.stroke_changed:
            added = self.tools.close(s)
            if added:
                self.ed.say(f"closure added {added:,} splats")
        s.end_stroke(self.stroke_changed)
        self.stroke_changed = False

    # ------------------------------------------------------ selection tools
    def close_pending_selection(self) -> None:
        """The neighbour graph arrived after a selection change: close it now (an undo step)."""
        s = self.session
        if s.manip is not None:
            return
        n = self.tools.close(s)
        if n:
            s.push("fill holes")
            self.ed.say(f"closure added {n:,} splats")

    def selection_tool(self, tool: str, x: float | None = None, y: float | None = None,
                       whole: bool = False) -> None:
        """Run ``tool`` ("grow", "shrink", "connected", "invert", "all") on the brush
        target (support or active handle), close the selection: one undo step."""
        ed, s = self.ed, self.session
        if s.manip is not None:
            return
        target = s.brush_target
        what = "support" if target == SUPPORT else "handle"
        graph = self.tools.graph(s.cloud)
        if graph is None and tool not in ("invert", "all"):
            ed.say("the neighbour graph is still being built: try again in a moment")
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
            sph = seltools.brush_sphere(self.get_picker(), ed.cam, s.cloud.positions, x, y, self.radius, ed.size,
                                        self._displaced())
            if sph is None:
                ed.say("select connected: put the cursor on the model")
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
        if not self.tools.apply(s, target, mask, f"{tool} {what}"):
            ed.say(f"{tool}: the {what} did not change")
            return
        n = s.selection.counts[i] - before
        added = self.tools.last_added
        ed.say(f"{tool} {what}: {n:+,} splats" + (f", closure added {added:,}" if added else ""))

    # -------------------------------------------------------------- drawing
    def cursor_colour(self) -> tuple:
        if self.erasing():
            return ERASE_RGB
        return ov.SUPPORT_RGB if self.session.brush_target == SUPPORT else ov.HANDLE_RGB

    def underlay(self, w, h):
        """What the last closure added (flashes yellow)."""
        s, ed = self.session, self.ed
        hl = self.tools.highlighted(s.cloud)
        if hl is None:
            return []
        px, d = ed.cam.project(s.cloud.positions[hl], w, h)
        p = seltools.points_patch(np.where((d > 0)[:, None], px, np.nan), (w, h))
        return [] if p is None else [p]

    def overlay(self, w, h):
        """The brush circle and its mode tag at the cursor."""
        ed, s = self.ed, self.session
        if ed.drag.camera or s.manip is not None or ed.modal() or not ed.cursor_inside:
            return []
        col = self.cursor_colour()
        img = ov.ring(int(round(self.radius)), col)
        mx, my = ed.mouse
        out = [ov.Patch(int(mx) - img.shape[1] // 2, int(my) - img.shape[0] // 2, img)]
        tag = ov.text_panel(("3D" if self.tools.mode == seltools.BRUSH_3D else "VIS",), size=11,
                            fg=tuple(col) + (255,), pad=2, bg=(20, 22, 28, 150))
        r = int(round(self.radius * 0.7071))
        out.append(ov.Patch(int(mx) + r + 2, int(my) + r + 2, tag))
        return out
