"""The editor's Dear ImGui panels in the real window (Xvfb + xdotool): palette
buttons start the same actions as the keys, a number typed into a transform
field moves the handle (and deforms the model), display options switch the
renderer, the history list jumps, and a click on a panel never reaches the
brush.  Widgets are found through the rectangles the status file reports."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from splatedit.app.ui.panel import PANEL_MARGIN
from tests.app.window_harness import EditorProcess, _foreground_centre, paint_support_stroke

pytestmark = [pytest.mark.window, pytest.mark.gpu, pytest.mark.slow]
pytest.importorskip("imgui_bundle")


def _click(ed, name: str, dx: int | None = None) -> None:
    """Click the widget ``name``, scrolling the panel down (wheel) until it shows."""
    for _ in range(12):
        s = ed.idle(lambda s: True, "idle")
        if name in s["gui_rects"]:
            break
        px, py, pw, ph = s["panel_box"]
        ed.xdo("mousemove", px + pw // 2, py + ph // 2, "click", "5", "click", "5")
        time.sleep(0.2)
    rect = None
    for _ in range(40):                 # the layout settles (fit results, messages, scrolling)
        s = ed.wait(lambda s: name in s.get("gui_rects", {}), f"widget {name} shown")
        if s["gui_rects"][name] == rect and s["idle"]:
            break
        rect = s["gui_rects"][name]
        time.sleep(0.25)
    x, y, w, h = rect
    ed.xdo("mousemove", x + (w // 2 if dx is None else dx), y + h // 2, "sleep", "0.15", "click", "1")


def _paint_support_and_handle(ed, cx: int, cy: int) -> dict:
    paint_support_stroke(ed, cx, cy)
    ed.idle(lambda s: s["support"] > 200, "support painted")
    _click(ed, "tool_handle")                           # the palette instead of the 2 key
    ed.idle(lambda s: s["brush"] == "handle", "handle brush from the palette")
    ed.xdo("key", "bracketleft", "bracketleft", "bracketleft", "bracketleft", "bracketleft",
           "mousemove", cx, cy, "click", "1")
    return ed.idle(lambda s: s["handle"] > 0 and s["state"] == "ready", "handle painted and fitted")


def test_palette_transform_fields_display_and_history(xvfb, tmp_path):
    ed = EditorProcess(xvfb, tmp_path)
    try:
        s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0, "model loaded", 90)
        assert s["gui"] and s["panel_visible"] and s["brush"] == "support"
        x, y, pw, ph = s["panel_box"]
        assert x == PANEL_MARGIN and y > PANEL_MARGIN          # left, below the menu bar
        cx, cy = _foreground_centre(ed.screenshot(), s["panel_box"])
        # --- a click on the panel is ImGui's: it paints nothing
        ed.xdo("mousemove", x + pw // 2, y + ph - 12, "click", "1")
        s = ed.idle(lambda s: True, "click on the panel")
        assert s["support"] == 0 and s["history"] == 1
        s = _paint_support_and_handle(ed, cx, cy)
        hist, support = s["history"], s["support"]
        handle_px = s["handle_px"][0]
        # --- the Grab button starts the same move as G; Esc cancels it
        _click(ed, "tool_grab")
        s = ed.wait(lambda s: s["manip"] == "grab", "grab started from the palette")
        ed.xdo("key", "Escape")
        s = ed.idle(lambda s: s["manip"] is None, "grab cancelled")
        assert s["edits"] == 0 and s["running"]
        # --- type 0.051 into the X field of "move", Enter: a committed edit that moves the handle
        before = s["handle_px"][0]
        _click(ed, "field_translate", dx=20)
        ed.wait(lambda s: s["gui_wants_keyboard"], "the field takes the keyboard")
        ed.xdo("key", "ctrl+a", "0", "period", "0", "5", "1", "Return")      # 0.051 ("1" is also a key)
        s = ed.idle(lambda s: s["edits"] == 1 and s["state"] == "ready", "typed translation applied")
        assert s["support"] == support and s["history"] == hist + 1
        moved = s["handle_px"][0]
        # +0.051 model units along X on a ~1-unit bunny seen from the front: tens of pixels to the right
        assert moved[0] - before[0] > 10 and abs(moved[1] - before[1]) < 0.25 * (moved[0] - before[0]), \
            (before, moved, handle_px)
        # the typed keys went to the field, not to the keymap (1 would select the support brush)
        assert s["manip"] is None and s["brush"] == "handle"
        # --- display options: grey, heat map, file colours
        _click(ed, "display_grey")
        s = ed.idle(lambda s: s["grey"], "grey shading")
        _click(ed, "display_heat")
        s = ed.idle(lambda s: s["distortion_map"], "heat map")
        _click(ed, "display_file")
        s = ed.idle(lambda s: not s["grey"] and not s["distortion_map"], "file colours")
        # --- the history list: a click on the first entry jumps back (repeated undo)
        _click(ed, "history_0")
        s = ed.idle(lambda s: s["undo_position"] == 0, "jumped to the start of the history")
        assert s["edits"] == 0 and s["support"] == 0 and not s["dirty"]
        _click(ed, f"history_{hist}")
        s = ed.idle(lambda s: s["undo_position"] == hist and s["edits"] == 1, "jumped to the end")
        assert s["validation_messages"] == 0
    finally:
        ed.close()


def test_gui_screenshot_shows_panel_and_gizmo_apart(xvfb, tmp_path):
    """The panel moves to the right when the gizmo is on the left; a frame's
    pixels show the panel where the status says it is."""
    ed = EditorProcess(xvfb, tmp_path)
    try:
        s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0, "model loaded", 90)
        cx, cy = _foreground_centre(ed.screenshot(), s["panel_box"])
        s = _paint_support_and_handle(ed, cx, cy)
        # pan the view so the handle goes to the left edge, under the panel's place
        gb = s["gizmo_box"]
        assert gb is not None
        ed.xdo("mousemove", cx, cy, "keydown", "shift", "mousedown", "2", "mousemove", cx - 200, cy,
               "mousemove", cx - 330, cy, "mouseup", "2", "keyup", "shift")
        s = ed.idle(lambda s: s["gizmo_box"] is not None and s["gizmo_box"][0] < 300, "gizmo on the left")
        x, y, pw, ph = s["panel_box"]
        gx0, gy0, gx1, gy1 = (int(round(v)) for v in s["gizmo_box"])
        assert x > PANEL_MARGIN, "the panel stays on the left over the gizmo"
        assert not (x < gx1 and gx0 < x + pw and y < gy1 and gy0 < y + ph)
        time.sleep(0.3)
        img = ed.screenshot()[:, :, :3].astype(int)
        body = np.median(img[y + 30:y + ph - 4, x + 2], axis=0)   # the panel's left padding column
        assert body.max() < 90, body                        # the panel's dark body is drawn there
        scene = img[max(gy0, 0):max(gy1, 1), max(gx0, 0):max(gx1, 1)]
        assert scene.min() < 200 and not math.isnan(float(np.mean(scene)))   # the gizmo area is not covered
    finally:
        ed.close()


def test_cpu_overlay_fallback_still_presents(xvfb, tmp_path, monkeypatch):
    """SPLATEDIT_GUI=0: frames read back, the text panel blended on the CPU."""
    monkeypatch.setenv("SPLATEDIT_GUI", "0")
    ed = EditorProcess(xvfb, tmp_path)
    try:
        s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0, "model loaded", 90)
        assert not s["gui"] and s["panel_visible"]
        x, y, pw, ph = s["panel_box"]
        assert (x, y) == (PANEL_MARGIN, PANEL_MARGIN)       # the CPU panel: no menu bar above it
        time.sleep(0.3)
        px = ed.screenshot()[y + 4, x + 4, :3].astype(int)
        assert px.max() < 90, px
        ed.xdo("key", "p")
        ed.idle(lambda s: not s["panel_visible"], "P hides the CPU panel")
        assert ed.status()["validation_messages"] == 0
    finally:
        ed.close()
