"""glfw input events -> Dear ImGui io calls, and the routing question "does ImGui want it?".

The window (:class:`splatedit.render.vk.window.Window`) turns glfw callbacks
into :class:`~splatedit.render.vk.window.InputEvent` records with positions
in framebuffer pixels; :func:`feed_event` hands one record to ImGui's io
(``add_mouse_pos_event``, ``add_mouse_button_event``, ``add_mouse_wheel_event``,
``add_key_event`` with the modifier keys, ``add_input_character``,
``add_focus_event``).  ImGui is fed *every* event (so it sees releases that
end a drag it did not start); :func:`wants_event` then says whether the
editor must leave the event alone: mouse events while ``io.want_capture_mouse``
(the pointer is over a GUI window or ImGui is dragging), keys and characters
while ``io.want_capture_keyboard`` (a text field or a focused window has the
keyboard).  ImGui updates both flags in ``new_frame``, from the events fed
before it, as in ImGui's own platform backends.
"""

from __future__ import annotations

from imgui_bundle import imgui

#: events whose routing follows io.want_capture_mouse / want_capture_keyboard
MOUSE_KINDS = frozenset({"button", "move", "scroll"})
KEYBOARD_KINDS = frozenset({"key", "char"})

_FLT_MAX = 3.4028234663852886e38
_MOD_SHIFT, _MOD_CONTROL, _MOD_ALT, _MOD_SUPER = 0x1, 0x2, 0x4, 0x8   # GLFW_MOD_*
_PRESS, _RELEASE = 1, 0                                            # GLFW_PRESS / RELEASE (2 = REPEAT)


def _key_table() -> dict[int, int]:
    """glfw key code -> ImGuiKey (values of GLFW_KEY_* from glfw3.h, stable since glfw 3.0)."""
    K = imgui.Key
    t = {32: K.space, 39: K.apostrophe, 44: K.comma, 45: K.minus, 46: K.period, 47: K.slash,
         59: K.semicolon, 61: K.equal, 91: K.left_bracket, 92: K.backslash, 93: K.right_bracket,
         96: K.grave_accent, 256: K.escape, 257: K.enter, 258: K.tab, 259: K.backspace,
         260: K.insert, 261: K.delete, 262: K.right_arrow, 263: K.left_arrow, 264: K.down_arrow,
         265: K.up_arrow, 266: K.page_up, 267: K.page_down, 268: K.home, 269: K.end,
         280: K.caps_lock, 281: K.scroll_lock, 282: K.num_lock, 283: K.print_screen, 284: K.pause,
         330: K.keypad_decimal, 331: K.keypad_divide, 332: K.keypad_multiply,
         333: K.keypad_subtract, 334: K.keypad_add, 335: K.keypad_enter, 336: K.keypad_equal,
         340: K.left_shift, 341: K.left_ctrl, 342: K.left_alt, 343: K.left_super,
         344: K.right_shift, 345: K.right_ctrl, 346: K.right_alt, 347: K.right_super, 348: K.menu}
    for i in range(10):
        t[48 + i] = getattr(K, f"_{i}")              # GLFW_KEY_0..9
        t[320 + i] = getattr(K, f"keypad{i}")        # GLFW_KEY_KP_0..9
    for i in range(26):
        t[65 + i] = getattr(K, chr(ord("a") + i))     # GLFW_KEY_A..Z
    for i in range(12):
        t[290 + i] = getattr(K, f"f{i + 1}")          # GLFW_KEY_F1..F12
    return t


_KEYS: dict[int, int] | None = None


def imgui_key(glfw_key: int):
    """The ImGuiKey of a glfw key code (``imgui.Key.none`` when ImGui has no such key)."""
    global _KEYS
    if _KEYS is None:
        _KEYS = _key_table()
    return _KEYS.get(int(glfw_key), imgui.Key.none)


def _feed_mods(io, mods: int) -> None:
    io.add_key_event(imgui.Key.mod_ctrl, bool(mods & _MOD_CONTROL))
    io.add_key_event(imgui.Key.mod_shift, bool(mods & _MOD_SHIFT))
    io.add_key_event(imgui.Key.mod_alt, bool(mods & _MOD_ALT))
    io.add_key_event(imgui.Key.mod_super, bool(mods & _MOD_SUPER))


def feed_event(io, ev) -> None:
    """Pass one :class:`~splatedit.render.vk.window.InputEvent` to ImGui's ``io``
    (of the current context).  Kinds ImGui has no use for ("resize", "close",
    "iconify") are ignored; the display size is set per frame instead."""
    kind = ev.kind
    if kind == "move":
        io.add_mouse_pos_event(float(ev.x), float(ev.y))
    elif kind == "button":
        io.add_mouse_pos_event(float(ev.x), float(ev.y))
        _feed_mods(io, ev.mods)
        if 0 <= ev.button < 5:       # glfw 0/1/2 = left/right/middle, as ImGui's 0/1/2
            io.add_mouse_button_event(int(ev.button), ev.action == _PRESS)
    elif kind == "scroll":
        io.add_mouse_wheel_event(float(ev.dx), float(ev.dy))
    elif kind == "key":
        # glfw reports the modifier state *before* a modifier key's own event
        _feed_mods(io, _mods_after(ev))
        key = imgui_key(ev.key)
        if key != imgui.Key.none:
            io.add_key_event(key, ev.action != _RELEASE)
    elif kind == "char":
        for ch in ev.char:
            io.add_input_character(ord(ch))
    elif kind == "enter":
        if not ev.action:            # the pointer left the window: no hover anywhere
            io.add_mouse_pos_event(-_FLT_MAX, -_FLT_MAX)
    elif kind == "focus":
        io.add_focus_event(bool(ev.action))


def _mods_after(ev) -> int:
    bit = {340: _MOD_SHIFT, 344: _MOD_SHIFT, 341: _MOD_CONTROL, 345: _MOD_CONTROL,
           342: _MOD_ALT, 346: _MOD_ALT, 343: _MOD_SUPER, 347: _MOD_SUPER}.get(int(ev.key), 0)
    if not bit:
        return ev.mods
    return ev.mods | bit if ev.action != _RELEASE else ev.mods & ~bit


def wants_event(io, ev) -> bool:
    """True when ImGui claims ``ev``: the editor must not act on it."""
    if ev.kind in MOUSE_KINDS:
        return bool(io.want_capture_mouse)
    if ev.kind in KEYBOARD_KINDS:
        return bool(io.want_capture_keyboard)
    return False
