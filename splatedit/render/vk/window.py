"""A glfw window for Vulkan presentation (``GLFW_CLIENT_API = GLFW_NO_API``) whose
input callbacks are turned into plain :class:`InputEvent` records.

The editor polls :meth:`Window.poll` once per frame and gets a list of
events; no application logic runs inside glfw callbacks.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

from splatedit.render.vk.swapchain import PresentError


#: the message of a failed glfw initialisation without any display
NO_DISPLAY_MESSAGE = ("cannot open a window: no display (set DISPLAY, or use the headless "
                      "commands: splatedit demo/render/deform)")


def _init_glfw(glfw) -> None:
    """``glfwInit`` without glfw's own error reporting (pyGLFW turns every GLFW
    error into a python warning on stderr); a failure becomes one
    :class:`PresentError` (a SplatEditError: ``splatedit: error: ...``)."""
    saved = glfw.ERROR_REPORTING
    glfw.ERROR_REPORTING = "ignore"
    try:
        ok = glfw.init()
        detail = ""
        if not ok:
            try:
                code, desc = glfw.get_error()
                if desc:
                    detail = desc.decode("utf-8", "replace") if isinstance(desc, bytes) else str(desc)
            except Exception:  # noqa: BLE001 - the message is only a detail
                detail = ""
    finally:
        glfw.ERROR_REPORTING = saved
    if ok:
        return
    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        raise PresentError(NO_DISPLAY_MESSAGE)
    display = os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
    raise PresentError(f"cannot open a window: cannot connect to the display {display!r}"
                       + (f" ({detail})" if detail else ""))


@dataclass
class InputEvent:
    """One input event.

    kind: "key" (key, action, mods), "char" (char), "button" (button, action,
    mods, x, y), "move" (x, y), "scroll" (dx, dy, x, y, mods), "resize"
    (w, h: framebuffer size), "close", "iconify" (action 1 = minimized),
    "enter" (action 1 = the cursor entered the window, 0 = left it), "drop"
    (paths: the files / folders dropped on the window, in the order given).
    Coordinates are framebuffer pixels, origin top-left.
    """
    kind: str
    key: int = 0
    action: int = 0
    mods: int = 0
    button: int = 0
    x: float = 0.0
    y: float = 0.0
    dx: float = 0.0
    dy: float = 0.0
    char: str = ""
    w: int = 0
    h: int = 0
    paths: tuple[str, ...] = ()


class Window:
    """A resizable glfw window without a client API."""

    def __init__(self, title: str, width: int = 1280, height: int = 720):
        import glfw
        self.glfw = glfw
        _init_glfw(glfw)
        if not glfw.vulkan_supported():
            glfw.terminate()
            raise PresentError("glfw finds no Vulkan loader")
        glfw.default_window_hints()
        glfw.window_hint(glfw.CLIENT_API, glfw.NO_API)
        glfw.window_hint(glfw.RESIZABLE, glfw.TRUE)
        self.handle = glfw.create_window(int(width), int(height), title, None, None)
        if not self.handle:
            glfw.terminate()
            raise PresentError("cannot create a window")
        self.events: list[InputEvent] = []
        self._mods = 0
        self._scale = (1.0, 1.0)
        self._update_scale()
        # Button and scroll events carry the position of the last motion event
        # *in event order*: glfwGetCursorPos on X11 queries the pointer's
        # current position, which is already ahead when events are queued.
        self._last_pos = self.cursor()
        # the framebuffer size and the iconified state, kept from their callbacks:
        # asking glfw is an X round trip (~1 ms each on the loaded machine, several
        # per editor frame: issue 19 item 9); ``queries`` counts the real queries
        self.queries = 0
        self._fb_size = self._query_framebuffer_size()
        self._iconified = bool(glfw.get_window_attrib(self.handle, glfw.ICONIFIED))
        glfw.set_key_callback(self.handle, self._on_key)
        glfw.set_char_callback(self.handle, self._on_char)
        glfw.set_mouse_button_callback(self.handle, self._on_button)
        glfw.set_cursor_pos_callback(self.handle, self._on_move)
        glfw.set_scroll_callback(self.handle, self._on_scroll)
        glfw.set_framebuffer_size_callback(self.handle, self._on_resize)
        glfw.set_window_close_callback(self.handle, self._on_close)
        glfw.set_window_iconify_callback(self.handle, self._on_iconify)
        glfw.set_cursor_enter_callback(self.handle, self._on_enter)
        glfw.set_drop_callback(self.handle, self._on_drop)

    # ----------------------------------------------------------- callbacks
    def _update_scale(self) -> None:
        ww, wh = self.glfw.get_window_size(self.handle)
        fw, fh = self.glfw.get_framebuffer_size(self.handle)
        self._scale = (fw / ww if ww else 1.0, fh / wh if wh else 1.0)

    def _on_key(self, win, key, scancode, action, mods):
        self._mods = mods
        self.events.append(InputEvent("key", key=key, action=action, mods=mods))

    def _on_char(self, win, codepoint):
        self.events.append(InputEvent("char", char=chr(codepoint)))

    def _on_button(self, win, button, action, mods):
        x, y = self._last_pos
        self._mods = mods
        self.events.append(InputEvent("button", button=button, action=action, mods=mods, x=x, y=y))

    def _on_move(self, win, x, y):
        self._last_pos = (x * self._scale[0], y * self._scale[1])
        self.events.append(InputEvent("move", x=self._last_pos[0], y=self._last_pos[1]))

    def _on_scroll(self, win, dx, dy):
        x, y = self._last_pos
        self.events.append(InputEvent("scroll", dx=dx, dy=dy, x=x, y=y, mods=self.mods()))

    def _on_resize(self, win, w, h):
        self._fb_size = (int(w), int(h))
        self._update_scale()
        self.events.append(InputEvent("resize", w=w, h=h))

    def _on_close(self, win):
        self.glfw.set_window_should_close(self.handle, False)  # the editor decides
        self.events.append(InputEvent("close"))

    def _on_enter(self, win, entered):
        self.events.append(InputEvent("enter", action=int(entered)))

    def _on_drop(self, win, paths):
        x, y = self._last_pos
        names = tuple(p.decode("utf-8", "surrogateescape") if isinstance(p, bytes) else str(p) for p in paths)
        self.events.append(InputEvent("drop", paths=names, x=x, y=y))

    def _on_iconify(self, win, iconified):
        self._iconified = bool(iconified)
        self.events.append(InputEvent("iconify", action=int(iconified)))

    # ----------------------------------------------------------------- API
    def mods(self) -> int:
        """Current modifier bits (GLFW_MOD_*), from the key states."""
        g = self.glfw
        m = 0
        pressed = lambda *ks: any(g.get_key(self.handle, k) == g.PRESS for k in ks)  # noqa: E731
        if pressed(g.KEY_LEFT_SHIFT, g.KEY_RIGHT_SHIFT):
            m |= g.MOD_SHIFT
        if pressed(g.KEY_LEFT_CONTROL, g.KEY_RIGHT_CONTROL):
            m |= g.MOD_CONTROL
        if pressed(g.KEY_LEFT_ALT, g.KEY_RIGHT_ALT):
            m |= g.MOD_ALT
        return m

    def cursor(self) -> tuple[float, float]:
        x, y = self.glfw.get_cursor_pos(self.handle)
        return x * self._scale[0], y * self._scale[1]

    def poll(self, timeout: float | None = None) -> list[InputEvent]:
        """Process window-system events (waiting up to ``timeout`` s when
        given and nothing is pending) and return the events since the last call."""
        if timeout is not None and not self.events:
            self.glfw.wait_events_timeout(max(0.0, timeout))
        else:
            self.glfw.poll_events()
        out, self.events = self.events, []
        return out

    def _query_framebuffer_size(self) -> tuple[int, int]:
        self.queries += 1
        w, h = self.glfw.get_framebuffer_size(self.handle)
        return int(w), int(h)

    def framebuffer_size(self) -> tuple[int, int]:
        """(w, h) pixels of the framebuffer as of the last :meth:`poll` (kept
        from the resize callback; no window-system round trip)."""
        return self._fb_size

    def iconified(self) -> bool:
        """Minimized, as of the last :meth:`poll` (kept from the iconify callback)."""
        return self._iconified

    def set_title(self, title: str) -> None:
        self.glfw.set_window_title(self.handle, title)

    def set_size(self, w: int, h: int) -> None:
        self.glfw.set_window_size(self.handle, int(w), int(h))

    def iconify(self) -> None:
        self.glfw.iconify_window(self.handle)

    def restore(self) -> None:
        self.glfw.restore_window(self.handle)

    def post_empty_event(self) -> None:
        """Wake a :meth:`poll` waiting in another thread (thread-safe)."""
        self.glfw.post_empty_event()

    def close(self) -> None:
        if self.handle is not None:
            self.glfw.destroy_window(self.handle)
            self.handle = None
            self.glfw.terminate()
