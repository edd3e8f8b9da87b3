"""The editor's overlays in the real window (Xvfb + xdotool): the F1 help
pages through every line without covering the panel, P hides and shows the
panel, G / R / S show their live distance / angle / factor next to the
cursor, U sets the up axis the numpad views turn about, M and Shift+[ ]
switch the colours and the splat size."""

from __future__ import annotations

import math
import time

import pytest

from tests.app.window_harness import WINDOW, EditorProcess, _foreground_centre

pytestmark = [pytest.mark.window, pytest.mark.gpu, pytest.mark.slow]


def _inside(box, w, h):
    x, y, bw, bh = box
    return x >= 0 and y >= 0 and x + bw <= w and y + bh <= h


def _overlap(a, b):
    return a[0] < b[0] + b[2] and b[0] < a[0] + a[2] and a[1] < b[1] + b[3] and b[1] < a[1] + a[3]


def test_help_rows_paged_are_all_visible_above_the_horizontal_scroll_bar(xvfb, tmp_path):
    """A window narrower than the help's lines: the horizontal scroll bar gets
    its own room, so every row the help pages by (its last line at the end
    included) is wholly visible, not half under the bar."""
    ed = EditorProcess(xvfb, tmp_path, "--size", "720x480")
    try:
        ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0, "model loaded", 90)
        ed.xdo("mousemove", 600, 300, "key", "F1")
        s = ed.wait(lambda s: s["help"] and s["help_box"] and s["help_visible_rows"] > 0, "help shown")
        assert s["help_box"][2] < 720 and s["help_rows"] < s["help_total"]
        assert s["help_visible_rows"] >= s["help_rows"], s
        for _ in range(12):                             # to the last page
            if s["help_top"] + s["help_rows"] >= s["help_total"]:
                break
            top = s["help_top"]
            ed.xdo("key", "Next")
            s = ed.wait(lambda s, t=top: s["help_top"] != t, "help paged")
        assert s["help_top"] + s["help_rows"] == s["help_total"]
        s = ed.idle(lambda s: s["help"], "last page drawn")
        assert s["help_visible_rows"] >= s["help_rows"] and s["validation_messages"] == 0
    finally:
        ed.close()


def test_help_panel_toggle_and_view_keys(xvfb, tmp_path):
    ed = EditorProcess(xvfb, tmp_path)
    w, h = WINDOW
    try:
        s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0, "model loaded", 90)
        assert s["panel_visible"] and s["up_axis"] == "+Y"
        # --- F1: the help, paged with PageDown to its last line, never over the panel
        ed.xdo("mousemove", w // 2, h // 2, "key", "F1")
        s = ed.wait(lambda s: s["help"] and s["help_box"], "help shown")
        assert s["help_rows"] < s["help_total"]            # 600 px: it takes more than one page
        assert _inside(s["help_box"], w, h) and not _overlap(s["help_box"], s["panel_box"])
        tops = [s["help_top"]]
        for _ in range(10):
            ed.xdo("key", "Next")
            s = ed.wait(lambda s, t=tops[-1]: s["help_top"] != t or s["help_top"] + s["help_rows"] >= s["help_total"],
                        "paged")
            if s["help_top"] == tops[-1]:
                break
            tops.append(s["help_top"])
        assert len(tops) >= 2 and s["help_top"] + s["help_rows"] == s["help_total"]
        x, y, bw, bh = s["help_box"]
        ed.xdo("mousemove", x + bw // 2, y + bh // 2, "click", "4", "click", "4")     # wheel up scrolls back
        s = ed.wait(lambda s: s["help_top"] < tops[-1], "help scrolled by the wheel")
        ed.xdo("key", "Escape")
        s = ed.wait(lambda s: not s["help"], "Esc closes the help")
        assert s["running"]
        # --- P hides the panel (its corner shows the background) and shows it again
        ed.xdo("mousemove", w - 5, h - 5)
        s = ed.idle(lambda s: True, "idle")
        # a point of the panel's body (its top rows are the ImGui title bar, blue)
        px, py = s["panel_box"][0] + 4, s["panel_box"][1] + s["panel_box"][3] // 2
        dark = ed.screenshot()[py, px, :3].astype(int)
        ed.xdo("key", "p")
        s = ed.idle(lambda s: not s["panel_visible"], "panel hidden")
        time.sleep(0.3)
        light = ed.screenshot()[py, px, :3].astype(int)
        assert dark.max() < 90 and light.min() > 200, (dark, light)
        ed.xdo("key", "p")
        ed.idle(lambda s: s["panel_visible"], "panel shown again")
        # --- U: the up axis; the numpad views turn about it
        ed.xdo("key", "u")
        s = ed.idle(lambda s: s["up_axis"] == "+Z", "up axis +Z")
        assert s["up_source"] == "set by the user" and s["camera"]["up"] == [0.0, 0.0, 1.0]
        ed.xdo("key", "KP_1")
        s = ed.idle(lambda s: abs(s["camera"]["yaw"]) < 1e-9 and abs(s["camera"]["pitch"]) < 1e-9, "front")
        ed.xdo("key", "ctrl+KP_1")
        s = ed.idle(lambda s: math.isclose(abs(s["camera"]["yaw"]), math.pi, abs_tol=1e-6), "back")
        # --- M: grey shading; Shift+] larger splats (display only)
        ed.xdo("key", "m", "shift+bracketright")
        s = ed.idle(lambda s: s["grey"] and math.isclose(s["splat_scale"], 1.25), "display options")
        assert not s["dirty"] and s["validation_messages"] == 0
    finally:
        ed.close()


def test_live_readout_while_moving_with_g_r_s(xvfb, tmp_path):
    ed = EditorProcess(xvfb, tmp_path)
    try:
        s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0, "model loaded", 90)
        cx, cy = _foreground_centre(ed.screenshot(), s["panel_box"])
        ed.xdo("mousemove", cx, cy, "key", "bracketright", "bracketright", "bracketright")
        ed.xdo("mousemove", cx - 30, cy, "mousedown", "1", "mousemove", cx + 30, cy, "sleep", "0.1", "mouseup", "1")
        ed.idle(lambda s: s["support"] > 100, "support painted")
        ed.xdo("key", "2", "bracketleft", "bracketleft", "bracketleft", "mousemove", cx, cy, "click", "1")
        s = ed.idle(lambda s: s["handle"] > 0 and s["state"] == "ready", "handle fitted")
        g = s["gizmo_box"]                                  # the panel never covers the gizmo
        assert g and not _overlap(s["panel_box"], (g[0], g[1], g[2] - g[0], g[3] - g[1]))
        ed.xdo("mousemove", cx + 5, cy + 5, "key", "g", "mousemove", cx + 45, cy + 5)
        s = ed.wait(lambda s: s["manip"] == "grab" and (s["readout"] or "").startswith("distance")
                    and float(s["readout"].split()[1]) > 0, "grab readout")
        time.sleep(0.4)
        shot = ed.screenshot()[:WINDOW[1], :WINDOW[0], :3].astype(int)
        near = shot[cy + 5:cy + 60, cx + 45:cx + 400]
        yellow = (near[..., 0] > 200) & (near[..., 1] > 180) & (near[..., 2] < 160)
        assert yellow.sum() > 30, "the readout is not drawn next to the cursor"
        ed.xdo("key", "r")
        s = ed.wait(lambda s: (s["readout"] or "").startswith("angle"), "rotate readout")
        ed.xdo("key", "s")
        s = ed.wait(lambda s: (s["readout"] or "").startswith("factor"), "scale readout")
        ed.xdo("key", "2")
        s = ed.wait(lambda s: s["readout"] == "factor 2.000x  (typed)", "typed factor")
        ed.xdo("key", "Escape")
        s = ed.idle(lambda s: s["manip"] is None and s["readout"] is None, "cancelled")
        assert s["edits"] == 0 and s["validation_messages"] == 0
    finally:
        ed.close()
