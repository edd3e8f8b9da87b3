"""Harness of the real-window editor tests (Xvfb + xdotool): the editor
process driven through its status file, and the replay check of a saved
edit (``splatedit deform`` with the exported script reproduces the file)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from tests.app.xwd import read_xwd

WINDOW = (960, 600)


class EditorProcess:
    def __init__(self, xvfb, tmp: Path, *args):
        import splatedit
        # the editor process imports the splatedit these tests import (it runs in ``tmp``,
        # where ``python -m`` would otherwise find whichever checkout is installed)
        root = str(Path(splatedit.__file__).resolve().parents[1])
        path = os.pathsep.join([root] + ([os.environ["PYTHONPATH"]] if os.environ.get("PYTHONPATH") else []))
        self.env = dict(os.environ, DISPLAY=xvfb["display"], SPLATEDIT_VALIDATION="1", PYTHONPATH=path)
        self.screen = xvfb["screen"]
        self.status_path = tmp / "status.json"
        self.stderr_path = tmp / "editor.stderr"
        self.stderr = open(self.stderr_path, "w")
        cmd = [sys.executable, "-m", "splatedit.app.editor", "--status-file", str(self.status_path),
               "--size", f"{WINDOW[0]}x{WINDOW[1]}", *args]
        self.proc = subprocess.Popen(cmd, env=self.env, stdout=self.stderr, stderr=subprocess.STDOUT,
                                     cwd=tmp)

    def status(self) -> dict:
        try:
            return json.loads(self.status_path.read_text())
        except (FileNotFoundError, json.JSONDecodeError):
            return {}

    def wait(self, cond, what: str, timeout: float = 60.0) -> dict:
        t0 = time.time()
        while time.time() - t0 < timeout:
            s = self.status()
            if s:
                try:
                    if cond(s):
                        return s
                except KeyError:
                    pass
            if self.proc.poll() is not None and not (s and cond(s)):
                break
            time.sleep(0.05)
        raise AssertionError(f"timed out waiting for: {what}; last status {self.status()}; "
                             f"stderr:\n{self.stderr_path.read_text()[-3000:]}")

    def idle(self, cond=lambda s: True, what="idle", timeout=60.0) -> dict:
        return self.wait(lambda s: s.get("idle") and cond(s), what, timeout)

    def xdo(self, *args) -> None:
        subprocess.run(["xdotool", *map(str, args)], env=self.env, check=True, timeout=30)

    def screenshot(self) -> np.ndarray:
        return read_xwd(self.screen)

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(10)
        self.stderr.close()


def paint_support_stroke(ed: "EditorProcess", cx: int, cy: int) -> None:
    """A user's first support stroke: the brush made bigger (] three times), then
    one drag around the model's centre (cx, cy) in window pixels."""
    ed.xdo("mousemove", cx, cy, "key", "bracketright", "bracketright", "bracketright")
    ed.xdo("mousemove", cx - 40, cy - 10, "mousedown", "1", "mousemove", cx, cy - 10,
           "mousemove", cx + 40, cy - 10, "mousemove", cx + 40, cy + 15, "mousemove", cx - 40, cy + 15,
           "sleep", "0.1", "mouseup", "1")


def _foreground_centre(img: np.ndarray, panel) -> tuple[int, int]:
    w, h = WINDOW
    a = img[:h, :w].astype(int)
    fg = a.min(axis=2) < 230
    x, y, pw, ph = panel
    fg[: y + ph + 4, : x + pw + 4] = False
    ys, xs = np.nonzero(fg)
    assert len(xs) > 1000, "the model is not visible in the window"
    return int(np.median(xs)), int(np.median(ys))


def assert_replay_reproduces(script_path: Path, saved_path: Path, tmp_path: Path) -> None:
    """``splatedit deform`` on the bundled model with the edit script at
    ``script_path`` reproduces the saved file ``saved_path``."""
    from splatedit.data import default_model_path
    from splatedit.io import read

    replay = tmp_path / f"replay-{Path(saved_path).stem}.ply"
    r = subprocess.run([sys.executable, "-m", "splatedit.cli", "-q", "deform", str(default_model_path()),
                        "--edit", str(script_path), "-o", str(replay)], capture_output=True, text=True,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    again, saved = read(replay), read(saved_path)
    assert np.allclose(again.positions, saved.positions, rtol=0, atol=1e-6)
    assert np.allclose(again.u, saved.u, rtol=1e-5, atol=1e-9)
    assert np.allclose(again.v, saved.v, rtol=1e-5, atol=1e-9)
