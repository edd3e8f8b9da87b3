"""``python -m splatedit.render.gui.demo --demo``: a window with a Dear ImGui panel
drawn on the GPU into the swapchain image (no readback, no CPU blending).

The panel has a click counter button, a slider, a checkbox and a text field;
Q quits (unless a text field has the keyboard), Esc does not, nor does
anything else ImGui claims.  With ``--status-file`` the demo writes its state
as JSON after every frame (frame number, click count, the button's rectangle in
window pixels, the slider value, ImGui's capture flags): the window test drives
it with xdotool through that file.
"""

from __future__ import annotations

import json
import os
import sys
import time
from dataclasses import asdict, dataclass, field

from imgui_bundle import imgui

from splatedit.render.gui.gui import Gui

#: background the panel is drawn over (RGBA floats; the window test checks it)
DEMO_BACKGROUND = (0.10, 0.14, 0.20, 1.0)
#: redraw period while idle (s): ImGui animates hover/press feedback
IDLE_PERIOD_S = 1.0 / 30.0
_KEY_Q = 81          # GLFW_KEY_Q
_PRESS = 1


@dataclass
class DemoState:
    """What the ImGui demo panel shows and reports (frame count, clicks, widget values, button and panel
    rectangles in pixels): written as JSON for the window tests."""
    frame: int = 0
    clicks: int = 0
    value: float = 0.5
    checked: bool = False
    text: str = ""
    button: list = field(default_factory=lambda: [0.0, 0.0, 0.0, 0.0])   # x0, y0, x1, y1 (pixels)
    panel: list = field(default_factory=lambda: [0.0, 0.0, 0.0, 0.0])    # x, y, w, h (pixels)
    wants_mouse: bool = False
    wants_keyboard: bool = False
    draws: int = 0
    gui_ms: float = 0.0
    validation_messages: int = 0


def draw_panel(state: DemoState) -> None:
    """The demo's widgets (call between Gui.new_frame and Gui.render)."""
    imgui.set_next_window_pos((20, 20), imgui.Cond_.first_use_ever)
    imgui.set_next_window_size((300, 190), imgui.Cond_.first_use_ever)
    imgui.begin("splatedit GUI demo")
    imgui.text(f"clicks: {state.clicks}")
    if imgui.button("Click me"):
        state.clicks += 1
    mn, mx = imgui.get_item_rect_min(), imgui.get_item_rect_max()
    state.button = [mn.x, mn.y, mx.x, mx.y]
    _, state.value = imgui.slider_float("splat size", state.value, 0.0, 1.0)
    _, state.checked = imgui.checkbox("file colours", state.checked)
    _, state.text = imgui.input_text("note", state.text)
    imgui.text(f"{state.gui_ms:.1f} ms per GUI frame, {state.draws} draws")
    pos, size = imgui.get_window_pos(), imgui.get_window_size()
    state.panel = [pos.x, pos.y, size.x, size.y]
    imgui.end()


def _report_validation() -> int:
    """Print the Vulkan validation messages collected so far to stderr; their number."""
    from splatedit.render.vk import drain_validation_messages
    msgs = drain_validation_messages()
    for m in msgs:
        print(f"splatedit: vulkan validation: {m}", file=sys.stderr)
    return len(msgs)


def _write_status(path: str, state: DemoState) -> None:
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(asdict(state), f)
    os.replace(tmp, path)


def run_demo(size=(800, 500), *, status_file: str | None = None, frames: int = 0) -> int:
    """Open the demo window and run until it is closed (or ``frames`` frames were shown)."""
    from splatedit.render.vk.swapchain import SwapchainPresenter
    from splatedit.render.vk.window import Window
    win = Window("splatedit GUI demo", *size)
    pres = gui = None
    try:
        pres = SwapchainPresenter(win.handle)
        gui = Gui(pres.dev)
        state = DemoState()
        last = time.perf_counter()
        running = True
        while running:
            for ev in win.poll(IDLE_PERIOD_S):
                if gui.feed(ev):
                    continue
                if ev.kind == "close" or (ev.kind == "key" and ev.key == _KEY_Q and ev.action == _PRESS):
                    running = False
            now = time.perf_counter()
            fw, fh = win.framebuffer_size()
            gui.new_frame(fw, fh, now - last)
            last = now
            draw_panel(state)
            t0 = time.perf_counter()

            def record(cmd, target):
                stats = gui.render_into(cmd, target, clear=DEMO_BACKGROUND, final="present")
                state.draws = stats.draws
            if not pres.render_frame(record):
                gui.discard_frame()
                continue
            state.gui_ms = 1e3 * (time.perf_counter() - t0)
            state.frame += 1
            state.wants_mouse, state.wants_keyboard = gui.wants_mouse, gui.wants_keyboard
            state.validation_messages += _report_validation()
            if status_file:
                _write_status(status_file, state)
            if frames and state.frame >= frames:
                running = False
    finally:
        if pres is not None and pres.dev is not None:
            pres.dev.wait_idle()
        if gui is not None:
            gui.close()
        if pres is not None:
            pres.close()
        win.close()
        _report_validation()
    return 0


def main(argv=None) -> int:
    """``python -m splatedit.render.gui.demo``: Dear ImGui on our Vulkan swapchain, for tests and a quick look."""
    import argparse
    p = argparse.ArgumentParser(prog="python -m splatedit.render.gui.demo",
                                description="Dear ImGui on splatedit's Vulkan renderer")
    p.add_argument("--demo", action="store_true", help="open a window with a demo panel")
    p.add_argument("--size", default="800x500", help="window size WxH (default 800x500)")
    p.add_argument("--status-file", help="write the demo's state as JSON after every frame (tests)")
    p.add_argument("--frames", type=int, default=0, help="quit after this many frames (0: run until closed)")
    args = p.parse_args(argv)
    if not args.demo:
        p.print_help()
        return 0
    from splatedit.errors import SplatEditError
    try:
        w, h = (int(v) for v in args.size.lower().split("x"))
    except ValueError:
        print(f"splatedit: error: --size: expected WxH, got {args.size!r}", file=sys.stderr)
        return 2
    try:
        return run_demo((w, h), status_file=args.status_file, frames=args.frames)
    except SplatEditError as exc:
        print(f"splatedit: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
