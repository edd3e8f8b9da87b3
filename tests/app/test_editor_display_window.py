"""Display and feedback in the real window (Xvfb + xdotool, screenshots):
eye-dome lighting toggled by its key darkens depth edges, the status line
of an edge-on view, and a long selection operation (mirror) runs as a job
while frames keep coming."""

from __future__ import annotations

import numpy as np
import pytest

from tests.app.window_harness import WINDOW, EditorProcess

pytestmark = [pytest.mark.window, pytest.mark.gpu, pytest.mark.slow]
pytest.importorskip("imgui_bundle")


def _model_area(s: dict) -> np.ndarray:
    """(h, w) bool: the window's pixels right of the side panel and below the menu bar."""
    w, h = WINDOW
    m = np.zeros((h, w), bool)
    x, y, pw, ph = s["panel_box"]
    m[30:h - 4, x + pw + 8: w - 4] = True
    return m


def _eroded(mask: np.ndarray, r: int) -> np.ndarray:
    out = mask.copy()
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            out &= np.roll(np.roll(mask, dy, 0), dx, 1)
    return out


def test_shift_e_toggles_eye_dome_lighting_which_darkens_only_depth_edges(xvfb, tmp_path):
    """Shift+E: the frame changes; every changed pixel of the model got
    darker (EDL only darkens), a visible share of them clearly (the far side
    of the ear and body outlines), in thin lines (an erosion by 2 pixels
    leaves few of them: edges, not a darker model); Shift+E again gives the
    first frame back."""
    ed = EditorProcess(xvfb, tmp_path)
    try:
        s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0 and s["full_quality"]
                    and "menu_view" in s.get("gui_rects", {}), "model loaded", 90)
        assert not s["edl"]
        off = ed.screenshot()[:WINDOW[1], :WINDOW[0]].astype(int)
        n0 = s["frames_presented"]
        ed.xdo("key", "shift+e")
        s = ed.idle(lambda s: s["edl"] and s["full_quality"] and s["frames_presented"] > n0, "EDL on")
        assert s["message"].startswith("eye-dome lighting on")
        on = ed.screenshot()[:WINDOW[1], :WINDOW[0]].astype(int)
        area = _model_area(s)
        model = area & (off.min(axis=2) < 230)
        assert model.sum() > 5000, "the model is not visible"
        lum_off, lum_on = off.mean(axis=2), on.mean(axis=2)
        brighter = area & (lum_on > lum_off + 3)
        assert brighter.sum() <= 0.002 * model.sum(), f"{brighter.sum()} pixels got brighter"
        # measured on the bunny's front view: 2.9 % of the model's pixels darkened by more than 20 levels
        dark = model & (lum_on < lum_off - 20)
        assert dark.sum() >= 0.01 * model.sum(), f"only {dark.sum()} of {model.sum()} model pixels darkened"
        assert dark.sum() <= 0.5 * model.sum(), "the whole model got darker, not its edges"
        assert _eroded(dark, 2).sum() <= 0.25 * dark.sum(), "the darkened pixels are not thin edges"
        ed.xdo("key", "shift+e")
        s = ed.idle(lambda s: not s["edl"] and s["full_quality"] and s["message"] == "eye-dome lighting off",
                    "EDL off")
        again = ed.screenshot()[:WINDOW[1], :WINDOW[0]].astype(int)
        assert np.abs(again - off)[area].max() <= 3
        # the View menu's entry toggles it too
        x, y, w, h = s["gui_rects"]["menu_view"]
        ed.xdo("mousemove", x + w // 2, y + h // 2, "click", "1")
        s = ed.wait(lambda s: "view_edl" in s["gui_rects"] and s["gui_menu_open"], "View menu open")
        x, y, w, h = s["gui_rects"]["view_edl"]
        ed.xdo("mousemove", x + w // 2, y + h // 2, "sleep", "0.2", "click", "1")
        s = ed.idle(lambda s: s["edl"], "EDL on from the View menu")
        assert s["validation_messages"] == 0
    finally:
        ed.close()


def test_a_view_that_draws_almost_nothing_says_why_on_the_status_line(xvfb, tmp_path):
    """A scanned post (normals horizontal and outward, no cap) from the top
    (Shift+7): the window draws (almost) no pixel of it, and the status line
    names the view and says that its splats are seen edge-on or from behind,
    with the keys of other views and T; T (two-sided splats) draws the splats
    seen from behind: the ring of the post's wall shows; from the front
    (Shift+1) the post covers a good part of the view and no hint is given."""
    from splatedit.io import write
    from tests.app.view.test_view_coverage import post_cloud
    path = tmp_path / "post.ply"
    write(str(path), post_cloud())
    ed = EditorProcess(xvfb, tmp_path, str(path))
    try:
        s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0 and s["full_quality"], "post loaded", 90)
        ed.xdo("key", "shift+7")
        s = ed.idle(lambda s: s["full_quality"] and s["message"].startswith("view: top")
                    and "edge-on" in s["message"], "top view with the hint")
        assert "Shift+1" in s["message"] and "T: draw the splats seen from behind" in s["message"]
        top = ed.screenshot()[:WINDOW[1], :WINDOW[0]].astype(int)
        area = _model_area(s)
        drawn_top = (area & (top.min(axis=2) < 230)).sum() / area.sum()
        ed.xdo("key", "t")
        s = ed.idle(lambda s: s["two_sided"] and s["full_quality"] and s["view_hint_checked"], "two-sided")
        assert "edge-on" not in s["message"], s["message"]
        ring = ed.screenshot()[:WINDOW[1], :WINDOW[0]].astype(int)
        drawn_ring = (area & (ring.min(axis=2) < 230)).sum() / area.sum()
        assert drawn_ring > max(0.005, 5 * drawn_top), (drawn_top, drawn_ring)
        ed.xdo("key", "t")
        s = ed.idle(lambda s: not s["two_sided"] and s["full_quality"], "one-sided again")
        ed.xdo("key", "shift+1")
        s = ed.idle(lambda s: s["full_quality"] and s["message"].startswith("view: front")
                    and s["view_hint_checked"], "front view, its coverage estimated")
        assert "edge-on" not in s["message"], s["message"]
        front = ed.screenshot()[:WINDOW[1], :WINDOW[0]].astype(int)
        drawn_front = (area & (front.min(axis=2) < 230)).sum() / area.sum()
        # the brush circle and its label are drawn over the view in both
        assert drawn_top < 0.005 and drawn_front > 0.05, (drawn_top, drawn_front)
        assert s["validation_messages"] == 0
    finally:
        ed.close()


def test_panel_lines_and_sliders_stay_readable(xvfb, tmp_path):
    """An armed box select's state line wraps inside the panel (it was cut
    at the panel's edge), and the brush radius and splat size sliders show
    their value beside the slider: no text inside the slider's frame, where
    the grab box would cover it (screenshot: no text-white pixel there)."""
    ed = EditorProcess(xvfb, tmp_path)
    try:
        s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0 and "brush_radius_slider" in s["gui_rects"],
                    "model loaded", 90)
        ed.xdo("key", "ctrl+b")
        s = ed.idle(lambda s: s["region_armed"] and "tool_status_region" in s["gui_rects"], "box select armed")
        n = s["frames_presented"]
        s = ed.wait(lambda s: s["frames_presented"] >= n + 2, "laid out")
        px, py, pw, ph = s["panel_box"]
        x, y, w, h = s["gui_rects"]["tool_status_region"]
        assert px <= x and x + w <= px + pw - 8, (s["gui_rects"]["tool_status_region"], s["panel_box"])
        assert h >= 2 * 13, "the line is not wrapped"
        img = ed.screenshot()[:WINDOW[1], :WINDOW[0]].astype(int)
        ed.xdo("key", "Escape")
        for name in ("brush_radius", "splat_size"):
            if f"{name}_slider" not in s["gui_rects"]:          # the Display section below the fold
                continue
            x, y, w, h = s["gui_rects"][f"{name}_slider"]
            frame = img[y + 1:y + h - 1, x + 1:x + w - 1]
            assert (frame.min(axis=2) > 200).sum() == 0, f"text inside the {name} slider"
            vx, vy, vw, vh = s["gui_rects"][f"{name}_value"]
            assert vx >= x + w and vx + vw <= px + pw, f"the {name} value is not beside its slider"
            value = img[vy:vy + vh, vx:vx + vw]
            assert (value.min(axis=2) > 200).sum() > 20, f"no {name} value text"
        assert s["validation_messages"] == 0
    finally:
        ed.close()


def test_the_grab_readout_keeps_a_margin_from_the_window_edge(xvfb, tmp_path):
    """G with the cursor at the window's right edge and a long typed value:
    the readout's box ends EDITOR_READOUT_MARGIN_PX inside the window (it
    touched the edge), and the screenshot shows its dark box there and
    background beyond it."""
    from splatedit.tolerances import EDITOR_READOUT_MARGIN_PX
    from tests.app.window_harness import _foreground_centre, paint_support_stroke
    ed = EditorProcess(xvfb, tmp_path)
    try:
        s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0 and s["full_quality"], "model loaded", 90)
        cx, cy = _foreground_centre(ed.screenshot(), s["panel_box"])
        paint_support_stroke(ed, cx, cy)
        ed.idle(lambda s: s["support"] > 200, "support painted")
        ed.xdo("key", "2", "bracketleft", "bracketleft", "bracketleft", "bracketleft", "bracketleft",
               "mousemove", cx, cy, "click", "1")
        ed.idle(lambda s: s["handle"] > 0 and s["state"] == "ready", "handle painted and fitted")
        ed.xdo("mousemove", cx, cy, "key", "g")
        ed.wait(lambda s: s["manip"] == "grab", "grab started")
        ed.xdo("mousemove", WINDOW[0] - 3, WINDOW[1] // 2, "key", "x", "1", "2", "3", "period", "4")
        s = ed.wait(lambda s: s["readout"] and "typed" in s["readout"] and "readout" in s.get("gui_rects", {}),
                    "typed readout shown")
        n = s["frames_presented"]
        s = ed.wait(lambda s: s["frames_presented"] >= n + 1, "drawn")
        x, y, w, h = s["gui_rects"]["readout"]
        assert x + w <= WINDOW[0] - EDITOR_READOUT_MARGIN_PX and x >= EDITOR_READOUT_MARGIN_PX
        assert y + h <= WINDOW[1] - EDITOR_READOUT_MARGIN_PX
        img = ed.screenshot()[:WINDOW[1], :WINDOW[0]].astype(int)
        row = img[y + h // 2]
        assert row[x + 2:x + w - 2].min() < 120                 # the readout's dark box
        assert row[WINDOW[0] - EDITOR_READOUT_MARGIN_PX + 1:].min() > 200   # background in the margin
        ed.xdo("key", "Escape")
        s = ed.idle(lambda s: s["manip"] is None, "grab cancelled")
        assert s["validation_messages"] == 0
    finally:
        ed.close()


def test_mirror_runs_as_a_job_while_the_window_keeps_drawing(xvfb, tmp_path, monkeypatch):
    """Ctrl+M on a painted support: the mirror runs as a background job
    (held open by the jobs' test hook until the test lets it finish, so the
    window can be watched meanwhile): the status file lists it, frames keep
    being presented, a view key turns the view and the progress bar is on
    screen; when it lands the support has grown by its mirror image as one
    undo step."""
    from tests.app.window_harness import _foreground_centre, paint_support_stroke
    hold = tmp_path / "hold-mirror"
    hold.write_text("")
    monkeypatch.setenv("SPLATEDIT_TEST_HOLD_JOB", "mirroring")
    monkeypatch.setenv("SPLATEDIT_TEST_HOLD_FILE", str(hold))
    ed = EditorProcess(xvfb, tmp_path)
    try:
        s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0 and s["full_quality"], "model loaded", 90)
        cx, cy = _foreground_centre(ed.screenshot(), s["panel_box"])
        paint_support_stroke(ed, cx + 60, cy)
        s = ed.idle(lambda s: s["support"] > 200, "support painted")
        support, history = s["support"], s["history"]
        ed.xdo("key", "ctrl+m")
        s = ed.wait(lambda s: "mirror" in s["jobs"], "mirror job running")
        n0, yaw0 = s["frames_presented"], s["camera"]["yaw"]
        ed.xdo("key", "shift+3")
        s = ed.wait(lambda s: s["camera"]["yaw"] != yaw0 and s["frames_presented"] >= n0 + 3
                    and s["full_quality"], "frames drawn while the mirror runs")
        assert "mirror" in s["jobs"] and s["support"] == support
        img = ed.screenshot()[:WINDOW[1], :WINDOW[0]].astype(int)
        bar = img[30:60, WINDOW[0] // 2 - 150: WINDOW[0] // 2 + 150]     # the progress window, top centre
        assert (bar.max(axis=2) < 90).mean() > 0.3, "no progress bar on screen"
        hold.unlink()
        s = ed.idle(lambda s: "mirror" not in s["jobs"] and s["support"] > support, "mirror landed")
        assert s["history"] == history + 1 and s["history_label"] == "mirror support"
        assert s["message"].startswith("mirror support across X")
        assert s["validation_messages"] == 0
    finally:
        ed.close()
