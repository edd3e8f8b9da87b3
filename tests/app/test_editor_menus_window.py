"""The menu bar in the real window (Xvfb + xdotool): a menu closed with Esc
hands the next stroke to the brush (the first stroke paints)."""

from __future__ import annotations

import pytest

from tests.app.window_harness import EditorProcess, _foreground_centre

pytestmark = [pytest.mark.window, pytest.mark.gpu, pytest.mark.slow]
pytest.importorskip("imgui_bundle")


def _stroke(ed, cx, cy):
    ed.xdo("mousemove", cx - 30, cy, "mousedown", "1", "mousemove", cx - 10, cy, "mousemove", cx + 10, cy,
           "mousemove", cx + 30, cy, "sleep", "0.1", "mouseup", "1")


def test_the_first_stroke_after_a_menu_closed_with_esc_paints(xvfb, tmp_path):
    ed = EditorProcess(xvfb, tmp_path)
    try:
        s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0 and "menu_file" in s["gui_rects"],
                    "model loaded", 90)
        cx, cy = _foreground_centre(ed.screenshot(), s["panel_box"])
        for menu in ("menu_file", "menu_edit"):
            x, y, w, h = s["gui_rects"][menu]
            ed.xdo("mousemove", x + w // 2, y + h // 2, "click", "1")
            s = ed.idle(lambda s: s["gui_menu_open"], f"{menu} opened")
            before = s["support"]
            ed.xdo("key", "Escape")
            s = ed.idle(lambda s: not s["gui_menu_open"], "Esc closes the menu")
            _stroke(ed, cx, cy)
            s = ed.idle(lambda s: s["support"] > before, "the first stroke paints", 20)
            cy += 25
        assert s["validation_messages"] == 0
    finally:
        ed.close()
