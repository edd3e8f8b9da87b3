"""Opening another model in the real window (Xvfb + xdotool): Ctrl+O shows
the file browser, a model picked by typing its name and Enter asks first
while there are unsaved changes (N keeps the edit, Y opens), the new model
is shown, the recent files come first in the next browser (and are offered
when the editor starts without a file), and a file that cannot be read shows
an error box in the window (Esc closes it) while the open model stays.  A
file dropped on the window opens too: xdotool cannot drop, so
:mod:`tests.app.xdnd` plays the XDND source (the drop reaches glfw's drop
callback through the X server, as a file manager's would)."""

from __future__ import annotations

import subprocess
import time

import numpy as np
import pytest

from tests.app.sessions import plane_cloud
from tests.app.window_harness import EditorProcess, WINDOW, _foreground_centre, paint_support_stroke
from tests.app.xdnd import drop_files

pytestmark = [pytest.mark.window, pytest.mark.gpu, pytest.mark.slow]


def _edit_bunny(ed, s):
    """Paint a support and a handle around the model's centre and drag the handle (one edit)."""
    cx, cy = _foreground_centre(ed.screenshot(), s["panel_box"])
    paint_support_stroke(ed, cx, cy)
    ed.idle(lambda s: s["support"] > 200, "support painted")
    ed.xdo("key", "2", "bracketleft", "bracketleft", "bracketleft", "bracketleft", "bracketleft",
           "mousemove", cx, cy, "click", "1")
    ed.idle(lambda s: s["handle"] > 0 and s["state"] == "ready", "handle painted and fitted")
    ed.xdo("mousemove", cx, cy, "mousedown", "1", "mousemove", cx + 10, cy - 8,
           "mousemove", cx + 25, cy - 20, "sleep", "0.3", "mouseup", "1")
    return ed.idle(lambda s: s["edits"] == 1 and s["dirty"], "edit committed")


def _pick(ed, *names):
    """In the open browser: type each name and press Enter (folders, then the file)."""
    for name in names:
        ed.xdo("type", "--delay", "30", name)
        ed.wait(lambda s, n=name: s["browser"] and s["browser"]["typed"] == n, f"typed {name}")
        ed.xdo("key", "Return")


def _fg_fraction(img) -> float:
    w, h = WINDOW
    return float((img[:h, :w, :3].min(axis=2) < 230).mean())


def test_open_another_model_through_the_browser(xvfb, tmp_path):
    from splatedit.io import write
    scans = tmp_path / "scans"
    scans.mkdir()
    write(str(scans / "plane.ply"), plane_cloud(40))
    (scans / "broken.ply").write_bytes(b"ply\nformat binary_little_endian 1.0\nelement vertex 9\n"
                                       b"property float x\nend_header\n\x00\x00")
    ed = EditorProcess(xvfb, tmp_path)           # the bundled bunny, in tmp_path
    w, h = WINDOW
    try:
        s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0, "model loaded", 90)
        bunny_n = s["n"]
        s = _edit_bunny(ed, s)
        bunny_fg = _fg_fraction(ed.screenshot())
        # --- Ctrl+O: the browser in the current folder (the bundled model has none of its own)
        ed.xdo("mousemove", w // 2, h // 2, "key", "ctrl+o")
        s = ed.wait(lambda s: s["browser"] is not None, "browser shown")
        assert s["browser"]["folder"] == str(tmp_path)
        assert ["folder", "scans"] in s["browser"]["entries"]
        _pick(ed, "scans", "pla")
        # --- unsaved changes: the question, N keeps the edit
        s = ed.wait(lambda s: s["confirm_open"] == str(scans / "plane.ply"), "asks about unsaved changes")
        assert s["browser"] is None and s["n"] == bunny_n
        ed.xdo("key", "n")
        s = ed.idle(lambda s: s["confirm_open"] is None, "stays")
        assert s["n"] == bunny_n and s["dirty"] and s["edits"] == 1
        # --- again, Y opens the plane without saving
        ed.xdo("key", "ctrl+o")
        ed.wait(lambda s: s["browser"] is not None, "browser shown again")
        _pick(ed, "scans", "pla")
        ed.wait(lambda s: s["confirm_open"] is not None, "asks again")
        frames = s["frames_presented"]
        ed.xdo("key", "y")
        s = ed.idle(lambda s: s["n"] == 1600 and s["path"] == str(scans / "plane.ply"), "plane opened", 60)
        assert not s["dirty"] and s["edits"] == 0 and s["frames_presented"] > frames
        assert s["cloud_name"] == "plane.ply"
        time.sleep(0.3)
        plane_fg = _fg_fraction(ed.screenshot())
        assert abs(plane_fg - bunny_fg) > 0.02, (plane_fg, bunny_fg)   # the window shows another model
        # --- the browser opens in the model's folder with the recent file on top
        ed.xdo("key", "ctrl+o")
        s = ed.wait(lambda s: s["browser"] is not None, "browser in the model's folder")
        b = s["browser"]
        assert b["folder"] == str(scans) and b["entries"][0] == ["recent", "plane.ply"]
        assert b["entries"][1:] == [["parent", ".."], ["file", "broken.ply"], ["file", "plane.ply"]]
        # --- an unreadable file: an error box in the window, the plane stays
        _pick(ed, "bro")
        s = ed.idle(lambda s: s["error_box"] is not None and s["error_rect"], "error box shown")
        assert "broken.ply" in s["error_box"] and s["n"] == 1600 and s["path"] == str(scans / "plane.ply")
        assert "splatedit: error: not opened" in ed.stderr_path.read_text()
        time.sleep(0.3)
        x, y, bw, bh = s["error_rect"]
        box = ed.screenshot()[y + 4:y + bh - 4, x + 4:x + bw - 4, :3].astype(int)
        assert np.median(box[..., 0]) > np.median(box[..., 1]) + 30          # a red box is drawn
        ed.xdo("key", "Escape")
        s = ed.idle(lambda s: s["error_box"] is None, "Esc closes the error box")
        assert s["running"] and s["n"] == 1600 and s["validation_messages"] == 0
    finally:
        ed.close()
    # --- `splatedit edit` without a file offers the recent files over the bunny
    (tmp_path / "status.json").unlink()
    ed = EditorProcess(xvfb, tmp_path)
    try:
        s = ed.wait(lambda s: s["browser"] is not None and s["loaded"], "recent files offered", 90)
        assert s["browser"]["entries"][0] == ["recent", "plane.ply"] and s["browser"]["index"] == 0
        ed.xdo("key", "Return")
        s = ed.idle(lambda s: s["n"] == 1600 and s["browser"] is None, "recent file opened", 60)
        assert s["path"] == str(scans / "plane.ply")
        # --- a file dropped on the window (a real XDND drop) opens like Ctrl+O
        write(str(tmp_path / "dropped.ply"), plane_cloud(30))
        win = subprocess.run(["xdotool", "search", "--onlyvisible", "--name", "^splatedit"], env=ed.env,
                             capture_output=True, text=True, timeout=30).stdout.split()
        assert win, "the editor's window is not found"
        drop_files(ed.env["DISPLAY"], int(win[0]), [tmp_path / "dropped.ply"], w // 2, h // 2)
        s = ed.idle(lambda s: s["n"] == 900, "dropped file opened", 60)
        assert s["path"] == str(tmp_path / "dropped.ply") and s["validation_messages"] == 0
    finally:
        ed.close()
