"""The GUI demo (python -m splatedit.render.gui.demo --demo) in a real window under
Xvfb: ImGui drawn on the GPU into the swapchain image, clicked with xdotool."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import numpy as np
import pytest

from splatedit import tolerances as tol
from tests.app.xwd import read_xwd

pytestmark = [pytest.mark.window, pytest.mark.gpu]
pytest.importorskip("imgui_bundle")


def _status(path):
    try:
        return json.loads(path.read_text())
    except (FileNotFoundError, json.JSONDecodeError):
        return {}


def _wait(path, cond, what, proc, timeout=60.0):
    t0 = time.time()
    while time.time() - t0 < timeout:
        s = _status(path)
        if s and cond(s):
            return s
        if proc.poll() is not None:
            break
        time.sleep(0.05)
    raise AssertionError(f"timed out waiting for {what}; last status {_status(path)}")


def test_demo_button_click_and_gpu_drawn_panel(xvfb, tmp_path):
    from splatedit.render.gui.demo import DEMO_BACKGROUND
    status = tmp_path / "status.json"
    env = dict(os.environ, DISPLAY=xvfb["display"], SPLATEDIT_VALIDATION="1")
    log = open(tmp_path / "demo.log", "w")
    proc = subprocess.Popen([sys.executable, "-m", "splatedit.render.gui.demo", "--demo", "--size", "640x400",
                             "--status-file", str(status)], env=env, stdout=log, stderr=subprocess.STDOUT,
                            cwd=tmp_path)
    xdo = lambda *a: subprocess.run(["xdotool", *map(str, a)], env=env, check=True, timeout=30)  # noqa: E731
    try:
        s = _wait(status, lambda s: s["frame"] >= 3, "the first frames", proc)
        assert s["clicks"] == 0
        x0, y0, x1, y1 = s["button"]
        cx, cy = int((x0 + x1) / 2), int((y0 + y1) / 2)
        # a click outside the panel is not ImGui's and changes nothing
        xdo("mousemove", 600, 380, "click", "1")
        s = _wait(status, lambda s: not s["wants_mouse"] and s["frame"] >= 6, "pointer outside", proc)
        assert s["clicks"] == 0
        xdo("mousemove", cx, cy, "sleep", "0.3", "click", "1")
        s = _wait(status, lambda s: s["clicks"] == 1, "one click counted", proc)
        assert s["wants_mouse"]
        xdo("click", "1")
        s = _wait(status, lambda s: s["clicks"] == 2, "a second click", proc)
        f0 = s["frame"]
        _wait(status, lambda s: s["frame"] >= f0 + 3, "frames after the clicks", proc)
        time.sleep(0.2)
        shot = read_xwd(xvfb["screen"])[:400, :640].astype(int)
        # the cleared background around the panel, the panel's window colour inside it
        bg8 = np.array([int(v * 255 + 0.5) for v in DEMO_BACKGROUND[:3]])
        px, py, pw, ph = (int(v) for v in s["panel"])
        outside = np.ones(shot.shape[:2], bool)
        outside[py:py + ph, px:px + pw] = False
        assert np.abs(shot[outside] - bg8).max() <= tol.GUI_COLOUR_TOL
        from imgui_bundle import imgui
        ctx = imgui.create_context()
        try:
            wb = imgui.get_style().color_(imgui.Col_.window_bg)
        finally:
            imgui.destroy_context(ctx)
        win_bg = np.array([int(v * 255 + 0.5) for v in (wb.x, wb.y, wb.z)])
        inside = shot[py + ph - 12: py + ph - 4, px + 4: px + pw - 30]       # bottom strip of the panel
        assert np.abs(inside - win_bg).max() <= tol.GUI_COLOUR_TOL
        # the hovered button is drawn where the demo says it is (brighter than the window)
        assert shot[int(y0) + 2: int(y1) - 2, int(x0) + 1: int(x0) + 3].mean() > win_bg.mean() + tol.GUI_TEXT_CONTRAST
        xdo("key", "q")
        assert proc.wait(30) == 0
        final = _status(status)
        assert final["validation_messages"] == 0
        text = (tmp_path / "demo.log").read_text()
        assert "validation" not in text.lower() and "Traceback" not in text, text
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
        log.close()
