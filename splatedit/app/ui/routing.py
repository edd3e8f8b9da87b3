"""The editor's event routing: each window event (from
:meth:`splatedit.render.vk.window.Window.poll`) goes to the GUI first, then
to the modal question, the file browser, the help or the tools.

An owned part of :class:`~splatedit.app.editor.Editor` (``editor.routing``,
an :class:`EventRouter`; the editor's state it reads and sets -- the drag in
progress, the pointer, the modal questions -- stays the editor's).  Mouse
presses go to the tools in press order (every tool's ``press_modal``
first, then ``press``); the tool that takes a press gets the drag's moves
and its release.  Keys are looked up in the one keymap
(:func:`splatedit.app.ui.keymap.lookup`) in the contexts the editor is in
(save-as prompt, quit / open question, browser, error box, help, a running
G/R/S move, idle) and run the bound action.
"""

from __future__ import annotations

from pathlib import Path

from splatedit.app.document import files
from splatedit.app.ui.keymap import Action, Context, lookup
from splatedit.app.tools.base import DragMode

#: wheel notch -> help lines scrolled
HELP_WHEEL_LINES = 3

#: what stays available while an edit is applied in the background: the view,
#: the display, the panel and help, the brush's size and quitting (quitting
#: asks first: the running edit counts as unsaved).  Every other action
#: changes the document, the rig or the file and is refused with a message.
WHILE_COMMITTING = frozenset({
    Action.FRAME_ALL, Action.FRAME_SELECTION, Action.VIEW_FRONT, Action.VIEW_RIGHT, Action.VIEW_TOP,
    Action.VIEW_BACK, Action.VIEW_LEFT, Action.VIEW_BOTTOM, Action.CYCLE_UP_AXIS,
    Action.DISTORTION_MAP, Action.COLOUR_MODE, Action.SPLATS_SMALLER, Action.SPLATS_LARGER, Action.EDL, Action.TWO_SIDED,
    Action.PANEL, Action.HELP, Action.HELP_DOWN, Action.HELP_UP, Action.HELP_CLOSE,
    Action.BRUSH_SMALLER, Action.BRUSH_LARGER, Action.DISMISS_ERROR, Action.QUIT})


class EventRouter:
    """The Editor's ``on_<kind>`` event handlers and action dispatch
    (``ed``: the :class:`~splatedit.app.editor.Editor` it routes for)."""

    def __init__(self, ed):
        self.ed = ed

    def handle_events(self, events) -> None:
        """Each event to its handler, under the editor's guard (a
        SplatEditError is a message; any other exception an internal error
        shown in the error box, :mod:`splatedit.app.crash_guard`); the
        events after it are still handled."""
        for e in events:
            with self.ed.crash_guard.guarded(f"handling a {e.kind} event"):
                if self.ed.gui is not None and self.ed.gui.takes(e):
                    continue
                getattr(self, f"on_{e.kind}")(e)

    def on_resize(self, e) -> None:
        self.ed.frames.invalidate()
        self.ed.motion()

    def on_enter(self, e) -> None:
        self.ed.cursor_inside = bool(e.action)

    def on_iconify(self, e) -> None:
        self.ed.frames.invalidate()

    def on_close(self, e) -> None:
        self.ed.file_actions.request_quit()

    def on_drop(self, e) -> None:
        if self.refuse_while_committing():
            return
        files.on_drop(self.ed, [Path(p) for p in e.paths])

    def refuse_while_committing(self) -> bool:
        """True (and a message) while an edit is applied in the background."""
        s = self.ed.session
        if s is None or not s.committing:
            return False
        p = s.committer.progress()
        pct = f" ({p.fraction * 100:.0f}%)" if p is not None else ""
        self.ed.say(f"the edit is still being applied{pct}: wait until it lands (the view stays live)")
        return True

    def on_char(self, e) -> None:
        if self.ed.browser.shown and self.ed.prompt is None and self.ed.confirm_open is None:
            self.ed.browser.type_char(e.char)
            return
        if self.ed.prompt is not None:
            self.ed.file_actions.prompt_char(e.char)

    def on_scroll(self, e) -> None:
        if self.ed.browser.shown:
            self.ed.browser.scroll(-int(round(e.dy * HELP_WHEEL_LINES)))
            return
        b = self.ed.help.box
        if self.ed.help.shown and b is not None and b.x <= e.x < b.right and b.y <= e.y < b.bottom:
            self.ed.help.scroll(-int(round(e.dy * HELP_WHEEL_LINES)))
            return
        if self.ed.session is None:
            return
        if e.mods & self.ed.g.MOD_CONTROL:
            self.ed.brush.scroll(e)
        else:
            self.ed.camera.scroll(e)

    def on_move(self, e) -> None:
        x, y = e.x, e.y
        last = self.ed.drag_last
        self.ed.mouse = (x, y)
        self.ed.cursor_inside = True
        s = self.ed.session
        if self.ed.drag_tool is not None and s is not None:
            self.ed.drag_tool.drag(self.ed.drag, x, y, x - last[0], y - last[1], last)
        if s is not None and s.manip is not None:
            s.manip.mouse = (x, y)
            self.ed.motion()
        self.ed.drag_last = (x, y)

    def on_button(self, e) -> None:
        g, s = self.ed.g, self.ed.session
        self.ed.mouse = (e.x, e.y)
        if e.action == g.RELEASE:
            tool, mode = self.ed.drag_tool, self.ed.drag
            self.ed.drag, self.ed.drag_tool = DragMode.NONE, None
            if tool is not None and s is not None:
                tool.release(mode)
            return
        if e.action != g.PRESS:
            return
        if self.ed.browser.shown and self.ed.confirm_open is None:
            if e.button == g.MOUSE_BUTTON_LEFT:
                self.ed.browser.click(e.x, e.y)
            return
        r = self.ed.error_rect
        if r is not None and r[0] <= e.x < r[0] + r[2] and r[1] <= e.y < r[1] + r[3]:
            self.ed.dismiss_error()
            return
        if s is None or self.ed.modal():
            return
        self.ed.drag_last = (e.x, e.y)
        # while an edit is applied in the background only the camera takes presses
        tools = (self.ed.camera,) if s.committing else self.ed.tools
        for tool in tools:
            mode = tool.press_modal(e)
            if mode is not None:
                break
        else:
            for tool in tools:
                mode = tool.press(e)
                if mode is not None:
                    break
            else:
                if s.committing and e.button == g.MOUSE_BUTTON_LEFT:
                    self.refuse_while_committing()
                return
        self.ed.drag = mode
        self.ed.drag_tool = tool if mode is not DragMode.NONE else None

    def on_key(self, e) -> None:
        g = self.ed.g
        if e.action not in (g.PRESS, g.REPEAT):
            return
        k = e.key
        ctrl, shift = bool(e.mods & g.MOD_CONTROL), bool(e.mods & g.MOD_SHIFT)
        if self.ed.prompt is not None:
            self.ed.file_actions.prompt_key(k, e.mods)
            return
        if self.ed.crash_guard.confirm_restore is not None:   # Y restores, N discards, Esc: next time
            if k in (g.KEY_Y, g.KEY_N, g.KEY_ESCAPE):
                self.ed.crash_guard.answer_restore(None if k == g.KEY_ESCAPE else k == g.KEY_Y)
            return
        if self.ed.confirm_quit:              # N, Esc or anything else: stay
            self.ed.file_actions.answer_quit(k in (g.KEY_Y, g.KEY_Q))
            return
        if self.ed.confirm_open is not None:
            self.ed.file_actions.answer_open(k == g.KEY_Y)
            return
        if self.ed.browser.shown:
            action = lookup(k, ctrl, shift, [Context.BROWSER])
            if action is not None:
                self.ed.actions[action]()
            return
        s = self.ed.session
        manip = s is not None and s.manip is not None
        # a running move keeps its keys (Esc cancels it, digits type) even under the help
        helping = [Context.HELP] if self.ed.help.shown else []
        if self.ed.error_box is not None:
            helping.insert(0, Context.ERROR)
        if s is None:
            contexts = helping + [Context.ANY]
        elif manip:
            contexts = [Context.MANIP] + helping + [Context.ANY]
        else:
            contexts = helping + [Context.IDLE, Context.ANY]
        action = lookup(k, ctrl, shift, contexts)
        if action is None:
            if s is not None:
                self.ed.motion()
            return
        if action is Action.TYPE_VALUE:
            self.ed.gizmo.type_key(k)
            self.ed.motion()
        else:
            self.run_action(action)

    def run_action(self, action: Action) -> None:
        """Run the handler bound to ``action`` (keys and GUI buttons share it):
        during a G/R/S move its own handler when it has one."""
        s = self.ed.session
        if s is not None and s.committing and action not in WHILE_COMMITTING:
            self.refuse_while_committing()
            return
        manip = s is not None and s.manip is not None
        table = self.ed.manip_actions if manip and action in self.ed.manip_actions else self.ed.actions
        # guarded here too: a GUI button runs its action while the frame is laid out, and
        # an error there must neither abandon the frame nor take the window down
        with self.ed.crash_guard.guarded(f"running '{action.value}'"):
            if not any(tool.intercept(action) for tool in self.ed.tools):
                table[action]()
        if s is not None:
            self.ed.motion()
