"""Box selection and the Select menu in the real window (Xvfb + xdotool):
Ctrl+B then a left drag over the bunny seen from the front draws the box
(its white outline is on the screen while dragging) and adds every splat
whose centre projects inside (3D mode: through, front and back) to the
support as one undo step; Select > Invert inverts it; two undos clear it.
Shift + right click places the 3D cursor (drawn there) and "." makes it
the pivot.  Then a lasso (visible splats only, V) and Delete remove splats; the saved
file is what ``splatedit deform`` makes of the bundled model with the
saved edit script."""

from __future__ import annotations

import os

import numpy as np
import pytest

from tests.app.window_harness import EditorProcess, assert_replay_reproduces

pytestmark = [pytest.mark.window, pytest.mark.gpu, pytest.mark.slow]
pytest.importorskip("imgui_bundle")


def _camera(status: dict):
    from splatedit.app.view.camera_control import OrbitCamera
    c = status["camera"]
    return OrbitCamera(np.array(c["target"], float), c["distance"], c["yaw"], c["pitch"])


def test_box_select_through_and_select_menu_invert(xvfb, tmp_path):
    from splatedit.app.tools.region import box_polygon, polygon_mask, splats_through
    from splatedit.data import default_model_path
    from splatedit.io import read

    src = read(default_model_path())
    out = tmp_path / "deleted.ply"
    ed = EditorProcess(xvfb, tmp_path, "--save-as", str(out))
    try:
        ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0 and "menu_select" in s["gui_rects"],
                "model loaded", 90)
        ed.xdo("key", "KP_1")
        s = ed.idle(lambda s: abs(s["camera"]["yaw"]) < 1e-9 and abs(s["camera"]["pitch"]) < 1e-9, "front view")
        w, h = s["window"]
        px, depth = _camera(s).project(src.positions, w, h)
        on = depth > 0
        cx, cy = np.median(px[on], axis=0).astype(int)
        # --- the 3D cursor: Shift + right click on the model, drawn there; "." twice makes it the pivot
        before = ed.screenshot()[:h, :w].astype(int)
        ed.xdo("mousemove", cx, cy, "keydown", "shift", "click", "3", "keyup", "shift")
        s = ed.idle(lambda s: s["cursor"] is not None, "3D cursor placed")
        cpx, cdepth = _camera(s).project(np.array(s["cursor"]), w, h)
        assert cdepth[0] > 0 and np.hypot(*(cpx[0] - (cx, cy))) < 1.5
        ed.xdo("key", "period", "key", "period")
        s = ed.idle(lambda s: s["pivot"] == "3D cursor", "pivot: 3D cursor")
        shown = s["frames_presented"]
        ed.wait(lambda s: s["frames_presented"] > shown, "a frame with the cursor")
        img = ed.screenshot()[:h, :w].astype(int)
        ring = np.s_[cy - 12:cy + 13, cx - 12:cx + 13]
        red = (img[ring][..., 0] > 150) & (img[ring][..., 1] < 120) & (np.abs(img[ring] - before[ring]).max(axis=2) > 40)
        if os.environ.get("SPLATEDIT_KEEP_SHOTS"):
            np.save(tmp_path / "cursor.npy", img[cy - 40:cy + 40, cx - 40:cx + 40])
        assert red.sum() > 20, "the 3D cursor is not drawn (red ring and cross)"
        x0, y0, x1, y1 = cx - 60, cy - 40, cx + 50, cy + 30
        want = splats_through(polygon_mask(box_polygon((x0, y0), (x1, y1)), w, h), px, depth)
        assert len(want) > 500
        ed.xdo("mousemove", x0, y0, "key", "ctrl+b")
        before = ed.screenshot()[:h, :w].astype(int)
        ed.idle(lambda s: s["region_armed"] == "box", "box armed")
        ed.xdo("mousedown", "1", "mousemove", (x0 + x1) // 2, (y0 + y1) // 2, "mousemove", x1, y1)
        s = ed.wait(lambda s: s["region_points"] == 2, "box drawn")
        shown = s["frames_presented"]
        ed.wait(lambda s: s["frames_presented"] > shown + 1, "a frame with the box")
        img = ed.screenshot()[:h, :w].astype(int)
        # the outline (white on a dark halo) changed the pixels along each side
        for band in (np.s_[y0 - 2:y0 + 3, x0 + 10:x1 - 10], np.s_[y1 - 2:y1 + 3, x0 + 10:x1 - 10]):
            changed = np.abs(img[band] - before[band]).max(axis=2) > 40
            assert changed.any(axis=0).mean() > 0.9, "the box outline is not drawn"
        band = np.s_[y0 + 10:y1 - 10, x0 - 2:x0 + 3]
        assert (np.abs(img[band] - before[band]).max(axis=2) > 40).any(axis=1).mean() > 0.9
        ed.xdo("mouseup", "1")
        s = ed.idle(lambda s: s["support"] > 0 and s["region_armed"] is None, "box selected", 30)
        assert s["history_label"] == "box select support"
        assert s["support"] >= len(want)                      # every centre inside (closure only adds)
        assert s["support"] <= 1.25 * len(want)
        first = s["support"]
        x, y, bw, bh = s["gui_rects"]["menu_select"]
        ed.xdo("mousemove", x + bw // 2, y + bh // 2, "click", "1")
        s = ed.wait(lambda s: "select_invert" in s["gui_rects"], "Select menu open")
        x, y, bw, bh = s["gui_rects"]["select_invert"]
        ed.xdo("mousemove", x + bw // 2, y + bh // 2, "sleep", "0.2", "click", "1")
        s = ed.idle(lambda s: s["history_label"] == "invert support", "inverted")
        assert s["support"] == s["n"] - first
        ed.xdo("key", "ctrl+z", "key", "ctrl+z")
        s = ed.idle(lambda s: s["support"] == 0, "two undos clear it")
        # --- visible only (V): a lasso over the same area takes fewer splats (no back side)
        ed.xdo("key", "v", "key", "ctrl+shift+b")
        ed.idle(lambda s: s["region_armed"] == "lasso" and s["brush_mode"] == "visible", "lasso armed")
        ed.xdo("mousemove", x0, y0, "mousedown", "1", "mousemove", x1, y0, "mousemove", x1, y1,
               "mousemove", x0, y1, "mousemove", x0, y0 + 3, "sleep", "0.1", "mouseup", "1")
        s = ed.idle(lambda s: s["history_label"] == "lasso select support", "lasso selected", 30)
        assert 0.2 * first < s["support"] < 0.9 * first
        lasso = s["support"]
        ed.xdo("key", "Delete")
        s = ed.idle(lambda s: s["history_label"] == "delete", "deleted")
        assert s["n"] == src.n - lasso and s["support"] == 0 and s["edits"] == 1
        if os.environ.get("SPLATEDIT_KEEP_SHOTS"):          # for looking at: the hole the delete left
            shown = s["frames_presented"]
            ed.wait(lambda s: s["frames_presented"] > shown, "a frame after the delete")
            np.save(tmp_path / "deleted.npy", ed.screenshot()[:h, :w])
        ed.xdo("key", "ctrl+s")
        s = ed.idle(lambda s: s["saved"] and not s["dirty"], "saved", 60)
        assert s["validation_messages"] == 0 and s["internal_errors"] == 0
    finally:
        ed.close()
    assert_replay_reproduces(tmp_path / "deleted.edits.json", out, tmp_path)
