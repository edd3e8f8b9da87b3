"""A long commit in the real editor window (Xvfb + xdotool, issue 10 "long
work shows progress; the window stays responsive").

A 50k-Gaussian scene (the bunny resampled, SH degree 3): a dab of support
at the bottom inverted (Ctrl+I: all but the bottom, ~75k Gaussians), a
handle on the top, G Z 0.05 Enter.  The commit's CPU work (covariances, SH
rotation: about 1-2 s on this machine) runs in the background: while the
status file says "committing" with a progress fraction the window keeps
presenting frames, a camera key (numpad 3) turns the view, a document key
(Ctrl+Z) is refused, and the commit then lands as one edit.  The saved file
equals what ``splatedit deform`` replaying the exported script (the
synchronous commit) writes.  A second editor quits (Q, Y) in the middle of a
commit: it exits 0 at once and writes no file.
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from tests.app.window_harness import EditorProcess

pytestmark = [pytest.mark.window, pytest.mark.gpu, pytest.mark.slow]

#: Gaussians of the test scene: a commit of > 0.5 s here (~25 us per support
#: Gaussian), frames of a few hundred ms in the small window below
N_GAUSSIANS = 50_000
#: a small window: the Gaussian renderer's cost is mostly fragments
SIZE = (560, 360)


@pytest.fixture(scope="module")
def scene_path(tmp_path_factory):
    from splatedit.bench.editor import bunny_surface_cloud
    from splatedit.bench.gs_scenes import gaussians_from_splats
    from splatedit.io import write_gaussians
    path = tmp_path_factory.mktemp("commit-scene") / "bunny80k-gs.ply"
    write_gaussians(path, gaussians_from_splats(bunny_surface_cloud(N_GAUSSIANS)))
    return path


def _rig_and_move(ed) -> dict:
    """Support: all but a dab at the bottom; handle: the top; then G Z 0.05
    typed (Enter not yet pressed).  Returns the status."""
    s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0, "scene loaded", 120)
    ed.xdo("mousemove", 5, SIZE[1] - 5, "key", "p")           # hide the panel
    s = ed.idle(lambda s: not s["panel_visible"], "panel hidden")
    img = ed.screenshot()[:SIZE[1], :SIZE[0], :3].astype(int)
    fg = img.min(axis=2) < 230
    menu = s.get("gui_rects", {}).get("menu_file")
    if menu is not None:
        fg[:menu[1] + menu[3] + 2] = False
    from scipy import ndimage
    lab, _ = ndimage.label(fg)                                  # the model, not the brush circle
    fg = lab == np.argmax(np.bincount(lab.ravel())[1:]) + 1
    ys, xs = np.nonzero(fg)
    top, bottom = int(ys.min()), int(ys.max())
    by = bottom - (bottom - top) // 10
    bx = int(np.median(np.flatnonzero(fg[by])))
    tx = int(np.median(np.flatnonzero(fg[top + 10])))
    ed.xdo("mousemove", bx, by, "click", "1")
    s = ed.idle(lambda s: s["support"] > 0 and s["history"] == 2, "support dab")
    ed.xdo("key", "ctrl+i")
    s = ed.idle(lambda s: s["support"] > s["n"] // 2, "support inverted")
    ed.xdo("key", "2", "mousemove", tx, top + 10, "click", "1")
    s = ed.idle(lambda s: s["handle"] > 0 and s["state"] == "ready", "handle painted and fitted", 120)
    ed.xdo("mousemove", tx, top + 40, "key", "g", "z", "0", "period", "0", "5")
    return ed.wait(lambda s: s["manip"] == "grab" and "0.05" in s["readout"], "moving 0.05 (typed)")


def test_long_commit_keeps_the_window_live(xvfb, tmp_path, scene_path):
    out = tmp_path / "edited.ply"
    ed = EditorProcess(xvfb, tmp_path, str(scene_path), "--save-as", str(out), "--size", "%dx%d" % SIZE)
    try:
        s = _rig_and_move(ed)
        ed.xdo("key", "Return")
        s = ed.wait(lambda s: s["state"] == "committing", "the commit running in the background", 30)
        f0, yaw0 = s["frames_presented"], s["camera"]["yaw"]
        ed.xdo("key", "KP_3")                           # camera input: the right view
        s = ed.wait(lambda s: s["camera"]["yaw"] != yaw0 and s["frames_presented"] > f0 + 1,
                    "the view turned and presented during the commit", 30)
        assert s["state"] == "committing", ("the commit landed before the view turned: make the scene "
                                            f"bigger (last commit {s['last_commit_ms']} ms)")
        assert s["commit"] is not None and 0.0 <= s["commit"]["fraction"] <= 1.0, s["commit"]
        assert s["edits"] == 0 and s["dirty"]           # not landed yet; quitting would ask first
        ed.xdo("key", "ctrl+z")                         # a document change: refused while committing
        s = ed.idle(lambda s: s["edits"] == 1 and s["state"] == "ready", "the commit landed", 120)
        assert s["history"] == 5 and s["undo_position"] == 4, s    # open, dab, invert, handle, edit
        assert s["last_commit_ms"] > 500, s["last_commit_ms"]
        assert s["error_box"] is None
        ed.xdo("key", "ctrl+s")
        s = ed.idle(lambda s: s["saved"] and not s["dirty"], "saved", 120)
        script = s["script"]
        assert s["validation_messages"] == 0
    finally:
        ed.close()
    assert "still being applied" in ed.stderr_path.read_text()      # Ctrl+Z's refusal
    # the background commit's file is the synchronous commit's (splatedit deform replaying the script)
    from splatedit.io import read_gaussians
    replay = tmp_path / "replay.ply"
    r = subprocess.run([sys.executable, "-m", "splatedit.cli", "-q", "deform", str(scene_path), "--edit", script,
                        "-o", str(replay)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    again, saved, src = read_gaussians(replay), read_gaussians(out), read_gaussians(scene_path)
    assert np.abs(again.positions - saved.positions).max() < 1e-6
    assert np.abs(again.covariances() - saved.covariances()).max() < 1e-6
    assert np.abs(again.sh - saved.sh).max() < 1e-5
    assert np.abs(saved.positions - src.positions).max() > 0.01        # the edit moved the top


def test_quit_during_a_commit_writes_nothing(xvfb, tmp_path, scene_path):
    out = tmp_path / "edited.ply"
    ed = EditorProcess(xvfb, tmp_path, str(scene_path), "--save-as", str(out), "--size", "%dx%d" % SIZE)
    try:
        _rig_and_move(ed)
        ed.xdo("key", "Return")
        ed.wait(lambda s: s["state"] == "committing", "the commit running in the background", 30)
        ed.xdo("key", "q")
        ed.wait(lambda s: s["confirm_quit"], "quit asks first (the running edit is unsaved)", 30)
        t0 = time.time()
        ed.xdo("key", "y")
        assert ed.proc.wait(30) == 0
        assert time.time() - t0 < 10
    finally:
        ed.close()
    written = {p.name for p in Path(tmp_path).iterdir()} - {"status.json", "editor.stderr", "config"}
    assert not out.exists() and not written, written
