"""The editor's Dear ImGui interface: menu bar, side panel, help, questions.

:class:`EditorGui` owns a :class:`~splatedit.render.gui.gui.Gui` on the
presenter's Vulkan device.  Each presented frame it builds, between
``new_frame`` and ``render``:

* the **menu bar** (:mod:`splatedit.app.ui.menus`): File
  (:attr:`EditorGui.menus.file_menu <splatedit.app.ui.menus.MenuBar.file_menu>`, a list of :class:`MenuEntry` that other
  parts of the editor extend: Open..., Open recent, Save ...), Edit (undo /
  redo), View (panels, help, frame all);
* the **side panel** (collapsible sections; P hides it, as before; placed at
  the left below the menu bar, or at the right when the gizmo is on the
  left: it never covers the gizmo): tool palette, selection and solver,
  deformation mode, numeric transform of the active handle, display
  options, the edit history (click an entry to jump there), the live G/R/S
  readout and the last message;
* the **help** window (F1): the keymap's help lines, sized to the space
  beside the panel (or the whole window), scrolled by PageUp/PageDown, the
  arrows or the wheel;
* the centred **questions** (quit with unsaved changes, save-as path) and
  **progress** of loads, saves and fits;
* the tools' overlays (:mod:`splatedit.app.ui.gui_overlay`).

Buttons call the keymap's action handlers (:meth:`Editor.run_action`), so a
click and a key share one code path.  ``rects`` keeps the screen rectangle of
every named widget of the last frame (the status file reports them: window
tests click them).
"""

from __future__ import annotations

import time

from imgui_bundle import imgui

from splatedit.app.ui import help as gui_help
from splatedit.app.ui import gui_overlay
from splatedit.app.ui import questions as gui_questions
from splatedit.app.ui import overlay as ov
from splatedit.app.document.gaussian import model_summary
from splatedit.app.ui.menus import MenuBar, MenuEntry  # noqa: F401 (MenuEntry: the File menu's rows)
from splatedit.app.document import selection as seltools
from splatedit.app.ui.keymap import Action
from splatedit.app.ui.panel import PANEL_MARGIN, Box
from splatedit.app.tools.base import DragMode
from splatedit.app.ui.gui_transform import TransformSection
from splatedit.deform.modes import DeformationMode
from splatedit.select.selection import SUPPORT
from splatedit.tolerances import (EDITOR_GUI_FOOTER_MESSAGE_LINES, EDITOR_GUI_LAYOUT_SLACK_PX,
                                  EDITOR_GUI_PANEL_WIDTH, EDITOR_GUI_SETTLE_FRAMES, EDITOR_GUI_SLIDER_WIDTH,
                                  EDITOR_SPLAT_SCALE_MAX, EDITOR_SPLAT_SCALE_MIN)

YELLOW = imgui.ImVec4(1.0, 0.9, 0.47, 1.0)
RED = imgui.ImVec4(1.0, 0.47, 0.47, 1.0)
#: button colour of the palette entry that is on
ACTIVE_BUTTON = imgui.IM_COL32(40, 110, 200, 255)
#: the message line is shown this long (s)
MESSAGE_SECONDS = 8.0


class EditorGui:
    def __init__(self, ed, device):
        from splatedit.render.gui.gui import Gui
        self.ed = ed
        self.gui = Gui(device)
        imgui.get_io().config_flags &= ~imgui.ConfigFlags_.nav_enable_keyboard.value   # keys are the editor's
        #: the menu bar (an owned part, :class:`~splatedit.app.ui.menus.MenuBar`;
        #: its ``file_menu`` rows may be extended)
        self.menus = MenuBar(ed, self.rect)
        self.transform = TransformSection(ed)
        self.rects: dict[str, Box] = {}
        self.panel_box: Box | None = None
        self.help_box: Box | None = None
        self._panel_size = (EDITOR_GUI_PANEL_WIDTH, 200)
        self._sections_h = 400.0           # the panel's scrolling part / footer heights (last frame)
        self._footer_h = 60.0
        self.panel_scrolls = False         # the sections are taller than the room: they scroll
        self.help_scroll_set = None
        self.help_width: float | None = None   # the widest help line, pixels (measured once)
        self.help_visible_rows = 0             # help rows wholly in view (last frame)
        self._history_at: tuple[int, int] | None = None   # (position, entries) the list last scrolled to
        self._history_follow = 0                             # frames left that scroll to the current entry
        self._last = time.perf_counter()
        self.windows: list[Box] = []        # GUI windows of the last frame (mouse routing)
        self._close_menus = False          # Esc was pressed with a menu open
        self._press_in_gui = False
        self._frames_wanted = EDITOR_GUI_SETTLE_FRAMES

    # ---------------------------------------------------------------- input
    def feed(self, ev) -> bool:
        """Give ImGui the event first; True when it is ImGui's (the tools skip it).

        Mouse events are routed by *where* they happen, against the windows
        of the last frame (menu bar, panel, help, questions): ImGui's own
        ``want_capture_mouse`` is only updated once per frame, so in a batch
        of events "click a button, move to the model, click" the second click
        would still be claimed.  Presses on a window, and the moves and the
        release of a drag that started there (a slider), are ImGui's; so is
        every click while a menu is open.  Keys are ImGui's while a text
        field is being edited (:attr:`wants_keyboard`)."""
        self.gui.feed(ev)
        self._frames_wanted = EDITOR_GUI_SETTLE_FRAMES
        kind = ev.kind
        if kind == "key" and self.menus.open and ev.key == self.ed.g.KEY_ESCAPE:
            # Esc closes an open menu (ImGui does not without keyboard navigation, and
            # the menu would then swallow the next click: the first stroke did nothing);
            # the key is the menu's, it cancels nothing else
            if ev.action == 1:
                self._close_menus, self.menus.open = True, False
            return True
        if kind in ("key", "char"):
            return self.wants_keyboard
        if kind == "button":
            if ev.action == 1:                    # press
                self._press_in_gui = self.menus.open or self.owns_point(ev.x, ev.y)
                return self._press_in_gui
            taken, self._press_in_gui = self._press_in_gui, False
            return taken
        if kind == "scroll":
            return self.owns_point(ev.x, ev.y)
        if kind == "move":
            return self._press_in_gui
        return False

    def takes(self, ev) -> bool:
        """The editor's routing: :meth:`feed`, except that the release ending a
        tool's drag always reaches the tool."""
        taken = self.feed(ev)
        if ev.kind == "button" and ev.action == 0 and self.ed.drag is not DragMode.NONE:
            return False
        return taken

    def needs_frames(self) -> bool:
        """ImGui still has input to process: draw the next frames without
        waiting for events (it hands a press and a release of one click to
        two successive frames, and hover / focus changes show a frame later)."""
        return self._frames_wanted > 0

    def owns_point(self, x: float, y: float) -> bool:
        """(x, y) pixels are over a GUI window of the last frame."""
        return any(b.x <= x < b.right and b.y <= y < b.bottom for b in self.windows)

    @property
    def wants_mouse(self) -> bool:
        """The pointer is over a GUI window (or drags one of its widgets)."""
        mx, my = self.ed.mouse
        return self._press_in_gui or self.owns_point(mx, my)

    @property
    def menu_open(self) -> bool:
        """A menu of the menu bar was open in the last frame."""
        return self.menus.open

    @property
    def menu_height(self) -> float:
        """The menu bar's height in pixels (last frame)."""
        return self.menus.height

    @property
    def wants_keyboard(self) -> bool:
        """A text field is being edited (``io.want_text_input``): keys and
        characters are ImGui's.  ImGui's broader ``want_capture_keyboard`` also
        holds while a clicked window keeps the focus, which would swallow the
        editor's keys (Esc after a palette button) though ImGui does nothing
        with them (keyboard navigation is off)."""
        self.gui.make_current()
        return bool(imgui.get_io().want_text_input)

    # ---------------------------------------------------------------- frame
    def build(self, w: int, h: int) -> None:
        """Start the frame and lay out every window (call before :meth:`render_into`)."""
        now = time.perf_counter()
        self._frames_wanted = max(self._frames_wanted - 1, 0)
        self.gui.new_frame(w, h, now - self._last)
        self._last = now
        self.rects = {}
        self.windows = []
        if self._close_menus:
            imgui.internal.close_popups_except_modals()
            self._close_menus = False
        gui_overlay.draw_tools(self.ed, w, h)
        bar = self.menus.draw(w)
        if bar is not None:
            self.windows.append(bar)
        help_full = self.ed.help.shown and self._help_area(w, h)[1]
        if self.ed.panel_visible and not help_full:
            self._panel(w, h)
        else:
            self.panel_box = None
        b = self.panel_box
        self.ed.panel_box = None if b is None else (b.x, b.y, b.w, b.h)
        self._help(w, h)
        self._progress(w, h)
        self._question(w, h)
        gui_overlay.draw_modal_boxes(self.ed, w, h, self.menu_height + PANEL_MARGIN)

    def render_into(self, cb, target):
        """Record the GUI pass over ``target`` (the swapchain image holding the scene)."""
        return self.gui.render_into(cb, target, final="present")

    def discard(self) -> None:
        self.gui.discard_frame()

    def recover(self) -> None:
        """After an exception while a frame was laid out: close it (ImGui's error recovery)."""
        self.gui.recover_frame()

    def close(self) -> None:
        self.gui.close()

    def rect(self, name: str) -> None:
        """Record the last widget's rectangle as ``name`` when it is wholly
        shown (one scrolled out of the panel's sections, or under the footer,
        is not: it cannot be clicked)."""
        a, b = imgui.get_item_rect_min(), imgui.get_item_rect_max()
        p, s = imgui.get_window_pos(), imgui.get_window_size()
        slack = EDITOR_GUI_LAYOUT_SLACK_PX
        if not imgui.is_item_visible() or a.y < p.y - slack or b.y > p.y + s.y + slack:
            self.rects.pop(name, None)
            return
        self.rects[name] = Box(int(a.x), int(a.y), int(b.x - a.x), int(b.y - a.y))

    # --------------------------------------------------------------- panel
    def _place_panel(self, w: int, h: int) -> tuple[float, float]:
        """Top-left below the menu bar, or top-right when that would cover the gizmo."""
        ed = self.ed
        m = PANEL_MARGIN
        top = self.menu_height + m
        pw, ph = self._panel_size
        avoid = ed.gizmo.avoid_box(w, h) if ed.session is not None else None
        left = Box(m, int(top), int(pw), int(ph))
        if left.overlaps(avoid):
            right = Box(int(w - pw - m), int(top), int(pw), int(ph))
            if not right.overlaps(avoid):
                return right.x, right.y
        return left.x, left.y

    def _panel(self, w: int, h: int) -> None:
        """The side panel: its sections in a scrolling part sized to what is
        left of the window, and below it a footer that always shows (the
        status line, the last frame's time, the keys' hint)."""
        ed = self.ed
        x, y = self._place_panel(w, h)
        imgui.set_next_window_pos(imgui.ImVec2(x, y), imgui.Cond_.always)
        imgui.set_next_window_size_constraints(imgui.ImVec2(EDITOR_GUI_PANEL_WIDTH, 0),
                                               imgui.ImVec2(EDITOR_GUI_PANEL_WIDTH, max(h - y - PANEL_MARGIN, 60)))
        flags = imgui.WindowFlags_.always_auto_resize.value | imgui.WindowFlags_.no_move.value
        title = f"{ed.cloud_name}###panel"
        expanded, _ = imgui.begin(title, None, flags)
        if expanded:
            style = imgui.get_style()
            inner_w = EDITOR_GUI_PANEL_WIDTH - 2 * style.window_padding.x
            # what the window leaves for the scrolling part: below the title, above the footer
            room = (h - PANEL_MARGIN - imgui.get_cursor_screen_pos().y - self._footer_h
                    - style.window_padding.y - style.item_spacing.y)
            child_h = max(min(self._sections_h, room), 40.0)
            self.panel_scrolls = self._sections_h > child_h + EDITOR_GUI_LAYOUT_SLACK_PX
            imgui.begin_child("##sections", imgui.ImVec2(inner_w, child_h))
            if ed.session is None:
                imgui.text(f"opening {ed.path}")
            else:
                self._sections()
            sections_h = imgui.get_cursor_pos().y + style.window_padding.y
            imgui.end_child()
            top = imgui.get_cursor_screen_pos()
            self._footer()
            footer_h = imgui.get_cursor_screen_pos().y - top.y
            if max(abs(sections_h - self._sections_h), abs(footer_h - self._footer_h)) > EDITOR_GUI_LAYOUT_SLACK_PX:
                self._frames_wanted = max(self._frames_wanted, 1)    # laid out with last frame's sizes
            self._sections_h, self._footer_h = sections_h, footer_h
            self.rects["panel_footer"] = Box(int(top.x), int(top.y), int(inner_w), int(self._footer_h))
        pos, size = imgui.get_window_pos(), imgui.get_window_size()
        self._panel_size = (size.x, size.y)
        self.panel_box = Box(int(pos.x), int(pos.y), int(size.x), int(size.y))
        self.windows.append(self.panel_box)
        imgui.end()

    def _footer(self) -> None:
        """The panel's pinned lines: the status message, the frame time, the hint."""
        ed = self.ed
        imgui.push_text_wrap_pos(0.0)
        # the status line keeps EDITOR_GUI_FOOTER_MESSAGE_LINES lines even when shorter or gone, so the
        # sections above do not jump each time a message comes and goes
        line = imgui.get_text_line_height_with_spacing()
        y0 = imgui.get_cursor_pos().y
        if ed.message and time.perf_counter() - ed.message_time < MESSAGE_SECONDS:
            imgui.text_colored(YELLOW, ed.message)
        used = imgui.get_cursor_pos().y - y0
        if used < EDITOR_GUI_FOOTER_MESSAGE_LINES * line:
            imgui.dummy(imgui.ImVec2(1.0, EDITOR_GUI_FOOTER_MESSAGE_LINES * line - used - imgui.get_style().item_spacing.y))
        info = ed.viewport.last_info
        if ed.session is not None and info is not None and not isinstance(info, dict):
            what = (f"{info.splats:,} {'Gaussians' if getattr(info, 'gaussians', False) else 'splats'}"
                    + (" LOD" if info.lod else "") + (f" 1/{info.div}" if info.div > 1 else ""))
            imgui.text_disabled(f"frame {info.ms:.0f} ms ({what}), total {ed.frame_ms:.0f} ms")
        imgui.text_disabled("F1: help   P: hide panels")
        imgui.pop_text_wrap_pos()

    def _sections(self) -> None:
        s = self.ed.session
        st = s.stats()
        imgui.push_text_wrap_pos(0.0)
        imgui.text(f"{model_summary(s.cloud)}   edits {len(s.edits)}" + ("   unsaved" if s.dirty else ""))
        if getattr(self.ed, "ooc", None) is not None:
            imgui.text_disabled(self.ed.ooc.summary(s))
        imgui.pop_text_wrap_pos()
        self.rect("panel_summary")
        if s.manip is not None:               # the live readout of a running move
            imgui.text_colored(YELLOW, s.manip.readout())
            imgui.push_text_wrap_pos(0.0)
            imgui.text_disabled(s.manip.describe())
            imgui.pop_text_wrap_pos()
        open_ = imgui.TreeNodeFlags_.default_open.value
        if imgui.collapsing_header("Tools", open_):
            self._palette()
        if imgui.collapsing_header("Selection and solver", open_):
            self._stats(st)
        if imgui.collapsing_header("Deformation", open_):
            self._deformation()
        if imgui.collapsing_header("Transform", open_):
            self.transform.draw(self.rect)
        # History before Display: at 1280x720 the History section was always
        # below the fold (issue 19 item 8); the display options are set once
        if imgui.collapsing_header("History", open_):
            self._history()
        if imgui.collapsing_header("Display", open_):
            self._display()

    def _slider(self, label: str, name: str, value: float, lo: float, hi: float, fmt: str):
        """A logarithmic slider with its value and ``label`` written beside
        it, not in it: ImGui centres a slider's value text in its frame, where
        the moving grab box covers it (a tester found "24 px" under the
        brush radius's grab).  Rects ``<name>_slider`` and ``<name>_value``;
        returns ImGui's (changed, value)."""
        imgui.set_next_item_width(EDITOR_GUI_SLIDER_WIDTH)
        changed, v = imgui.slider_float(f"##{name}", value, lo, hi, "", imgui.SliderFlags_.logarithmic.value)
        self.rect(f"{name}_slider")
        imgui.same_line()
        imgui.text(f"{fmt % v}  {label}")
        self.rect(f"{name}_value")
        return changed, v

    def _tool_button(self, label: str, name: str, action: Action, on: bool) -> None:
        if on:
            imgui.push_style_color(imgui.Col_.button.value, ACTIVE_BUTTON)
        if imgui.button(label):
            self.ed.run_action(action)
        if on:
            imgui.pop_style_color()
        self.rect(name)

    def _palette(self) -> None:
        s = self.ed.session
        b = self.ed.brush
        manip = s.manip.mode if s.manip is not None else None
        self._tool_button("Support", "tool_support", Action.BRUSH_SUPPORT, s.brush_target == SUPPORT)
        imgui.same_line()
        self._tool_button("Handle", "tool_handle", Action.BRUSH_HANDLE, s.brush_target != SUPPORT)
        imgui.same_line()
        self._tool_button("Erase", "tool_erase", Action.ERASE_TOGGLE, b.erase_toggle)
        imgui.same_line()
        self._tool_button("Curve", "tool_curve", Action.CURVE_TOOL, s.curve_mode)
        self._tool_button("Grab", "tool_grab", Action.GRAB, manip == "grab")
        imgui.same_line()
        self._tool_button("Rotate", "tool_rotate", Action.ROTATE, manip == "rotate")
        imgui.same_line()
        self._tool_button("Scale", "tool_scale", Action.SCALE, manip == "scale")
        imgui.same_line()
        self._tool_button("3D" if b.mode == seltools.BRUSH_3D else "Visible", "tool_brush_mode",
                          Action.BRUSH_MODE, False)
        changed, r = self._slider("brush radius", "brush_radius", float(b.radius), 2.0, 300.0, "%.0f px")
        if changed:
            b.set_radius(r)
        # state lines wrap at the panel's edge (an armed box select's line was cut there)
        imgui.push_text_wrap_pos(0.0)
        note = b.mode_note()
        if note:
            imgui.text_colored(YELLOW, note)
            self.rect("brush_note")
        for tool in self.ed.tools:      # the protocol tools' state lines
            line = tool.status()
            if line:
                imgui.text_colored(YELLOW, line)
                self.rect(f"tool_status_{getattr(tool, 'name', type(tool).__name__)}")
        imgui.pop_text_wrap_pos()

    def _stats(self, st) -> None:
        s = self.ed.session
        imgui.text(f"support {st.support:,}   handle {st.handle:,}")
        if st.handles > 1 or st.curve_points:
            sizes = " ".join(f"[{n:,}]" if k == st.active_handle else f"{n:,}"
                             for k, n in enumerate(st.handle_sizes))
            imgui.text(f"handles {st.handles}: {sizes}")
            imgui.text(f"curve {st.curve_points} pts   columns {st.columns}/16")
        fit, prog = st.fit, st.progress
        if st.commit is not None:             # a commit in the background (issue 10)
            c = st.commit
            imgui.progress_bar(c.fraction, imgui.ImVec2(-1, 0), f"{c.stage} {c.fraction * 100:.0f}% "
                               f"({c.elapsed:.1f} s)")
        elif prog is not None:
            imgui.progress_bar(prog.fraction, imgui.ImVec2(-1, 0), f"{prog.stage} {prog.fraction * 100:.0f}%")
        elif fit is not None:
            imgui.text(f"{fit.method}: {fit.centers} centers / {fit.constraints} constraints")
            imgui.text(f"residual {fit.residual:.1e}   {fit.fit_seconds:.2f} s + {fit.basis_seconds:.2f} s")
        elif st.error:
            imgui.push_text_wrap_pos(0.0)
            imgui.text_colored(RED, f"solver: {st.error}")
            imgui.pop_text_wrap_pos()
        else:
            imgui.text_disabled("paint a support, then a handle")
        d = s.distortion()
        if d is not None:
            imgui.text_colored(RED if d.exceeds_warn else imgui.ImVec4(0.92, 0.92, 0.92, 1.0),
                               f"stretch max {d.max_stretch:.1f}x, {d.n_above_warn:,} > {d.warn:g}x")
            source = ov.distortion_source(s)
            if source:
                imgui.push_text_wrap_pos(0.0)
                imgui.text_disabled(source)
                imgui.pop_text_wrap_pos()
                self.rect("distortion_source")

    def _deformation(self) -> None:
        ed, s = self.ed, self.ed.session
        detail_ok = s.detail_available
        for m in DeformationMode:
            if m is DeformationMode.DETAIL and not detail_ok:
                imgui.begin_disabled()
            if imgui.radio_button(m.value, s.deformation is m) and s.deformation is not m:
                s.set_deformation(m)
                ed.say(f"deformation: {m.value}")
            self.rect(f"mode_{m.value}")
            if m is DeformationMode.DETAIL and not detail_ok:
                imgui.end_disabled()
            imgui.same_line()
        imgui.new_line()
        if not detail_ok:       # a Gaussian scene: say why detail is greyed out
            imgui.push_text_wrap_pos(0.0)
            imgui.text_disabled("detail: not available for Gaussian scenes")
            imgui.pop_text_wrap_pos()
        if s.pose_pending and s.manip is None and not s.committing:
            imgui.text_colored(YELLOW, "pending moves")
            if imgui.button("Apply (Enter)"):
                ed.run_action(Action.COMMIT_POSE)
            imgui.same_line()
            if imgui.button("Discard (Esc)"):
                ed.run_action(Action.CANCEL)

    def _display(self) -> None:
        ed, vp = self.ed, self.ed.viewport
        modes = (("file colours", not vp.grey and not vp.distortion_map),
                 ("grey", vp.grey and not vp.distortion_map), ("heat map", vp.distortion_map))
        for k, (name, on) in enumerate(modes):
            if imgui.radio_button(name, on) and not on:
                if vp.distortion_map != (k == 2):
                    ed.run_action(Action.DISTORTION_MAP)
                if k < 2 and vp.grey != (k == 1):
                    ed.run_action(Action.COLOUR_MODE)
            self.rect(f"display_{name.split()[0]}")
            if k < 2:
                imgui.same_line()
        if getattr(vp, "gaussians", None) is None:      # eye-dome lighting: a splat pass
            if imgui.checkbox("eye-dome lighting (Shift+E)", bool(vp.edl))[0]:
                ed.run_action(Action.EDL)
            self.rect("display_edl")
        ch, v = self._slider("splat size", "splat_size", float(vp.splat_scale), EDITOR_SPLAT_SCALE_MIN,
                             EDITOR_SPLAT_SCALE_MAX, "%.2fx")
        if ch:
            vp.splat_scale = float(v)
        imgui.set_next_item_width(150)
        ch, c = imgui.color_edit3("background", list(vp.background[:3]))
        if ch:
            vp.background = tuple(float(x) for x in c)
        imgui.text_disabled(f"up axis {ed.camera.up.label} ({ed.camera.up.source.value}), U to change")

    def _history(self) -> None:
        ed, s = self.ed, self.ed.session
        hist = s.history
        if imgui.button("Undo"):
            ed.run_action(Action.UNDO)
        imgui.same_line()
        if imgui.button("Redo"):
            ed.run_action(Action.REDO)
        labels = hist.labels
        rows = min(len(labels), 8)
        lh = imgui.get_text_line_height_with_spacing()
        height = rows * lh + 8
        if self._history_at != (hist.position, len(labels)):
            # a new step, an undo, a redo or a jump: the list scrolls to the current entry (for two
            # frames: ImGui applies a scroll request in the next frame, clamped to this frame's
            # content); otherwise the user's own scrolling is left alone
            self._history_at = (hist.position, len(labels))
            self._history_follow = 2
        if imgui.begin_child("history", imgui.ImVec2(-1, height), imgui.ChildFlags_.borders.value):
            for k, text in enumerate(labels):
                here = k == hist.position
                saved = " (saved)" if k == hist.saved_pos else ""
                name = (text or "state")[:1].upper() + (text or "state")[1:]
                if imgui.selectable(f"{k}. {name}{saved}##h{k}", here)[0] and not here:
                    self.jump(k)
                if here and self._history_follow > 0:
                    imgui.set_scroll_here_y(0.5)
                    self._history_follow -= 1
                    self._frames_wanted = max(self._frames_wanted, 1)   # the frame that applies it
                if imgui.is_item_visible():
                    self.rect(f"history_{k}")
        imgui.end_child()           # always (ImGui's rule for begin_child)

    def jump(self, k: int) -> None:
        """Go to history entry ``k`` (repeated undo / redo)."""
        s = self.ed.session
        while s.history.position > k and s.undo():
            pass
        while s.history.position < k and s.redo():
            pass
        self.ed.say(f"history: at {k}. {s.history.labels[s.history.position] or 'state'}")
        self.ed.motion()

    # ---------------------------------------------------------------- help
    def _help_area(self, w: int, h: int):
        return gui_help.help_area(self, w, h)

    def _help(self, w: int, h: int) -> None:
        gui_help.draw_help(self, w, h)

    # --------------------------------------------------- progress, questions
    def _progress(self, w: int, h: int) -> None:
        ed, s = self.ed, self.ed.session
        bars = [(j.stage, j.fraction) for j in ed.jobs.values()]
        if s is not None and s.fit_job is not None and ed.panel_box is None:
            bars.append((s.fit_job.stage, s.fit_job.fraction))
        c = None if s is None else s.committer.progress()
        if c is not None:       # a commit: always shown (editing waits for it)
            bars.append((c.stage, c.fraction))
        if not bars:
            return
        imgui.set_next_window_pos(imgui.ImVec2(w / 2, self.menu_height + PANEL_MARGIN), imgui.Cond_.always,
                                  imgui.ImVec2(0.5, 0.0))
        imgui.set_next_window_size(imgui.ImVec2(380, 0), imgui.Cond_.always)
        imgui.begin("##progress", None, imgui.WindowFlags_.no_decoration.value | imgui.WindowFlags_.no_inputs.value)
        for stage, frac in bars:
            imgui.progress_bar(float(frac), imgui.ImVec2(-1, 0), f"{stage} {frac * 100:3.0f}%")
        imgui.end()

    def _question(self, w: int, h: int) -> None:
        gui_questions.draw_question(self, w, h)
