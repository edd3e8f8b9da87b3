"""A COPC scan opened out of core in the real editor window (Xvfb + xdotool,
issue 23 item 3).

A 150k-point terrain COPC with small nodes (a 3-level octree) is opened with
``--out-of-core on`` and small point budgets (``SPLATEDIT_OOC_BUDGET``:
2,000 points first, 40,000 after refinement), so that it behaves like a scan
far beyond the budget: the first frame shows the octree's root, the top view
(numpad 7) refines the shown nodes in a background job while frames keep
being presented; a support stroke loads the support's region at full
resolution; a handle, G Z 2 Enter commits; Ctrl+S writes a COPC through
``rewrite_copc``.  The saved file: the nodes away from the edit are
byte-identical to the source's, and its points equal what ``splatedit
deform`` replaying the saved edit script on the whole file (in memory) writes,
to one LAS grid step (the file stores integers of 0.001; the replay's floats are
rounded to the same grid to compare), and to what the same replay writes out of
core, to one grid step (``-o Y.copc.laz``: the nodes around the points the
script's whole-file index lists name).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.app.copc_scans import terrain_copc
from tests.app.window_harness import EditorProcess, paint_support_stroke

pytestmark = [pytest.mark.window, pytest.mark.gpu, pytest.mark.slow]
pytest.importorskip("lazrs", reason="COPC point data is LAZ-compressed (lazrs)")

N_POINTS = 150_000


def _model_centre(ed, s) -> tuple[int, int]:
    """The middle of the drawn model right of the panel (window pixels)."""
    w, h = s["window"]
    img = ed.screenshot()[:h, :w].astype(int)
    fg = img.min(axis=2) < 230
    x, y, pw, ph = s["panel_box"]
    fg[:, : x + pw + 4] = False
    fg[:30] = False                                   # the menu bar
    ys, xs = np.nonzero(fg)
    assert len(xs) > 2000, "the scan is not visible in the window"
    return int(np.median(xs)), int(np.median(ys))


def _sorted_rows(xyz: np.ndarray) -> np.ndarray:
    q = np.round(xyz, 3)
    return q[np.lexsort(q.T[::-1])]


def test_out_of_core_scan_refines_edits_a_region_and_saves_streaming(xvfb, tmp_path, monkeypatch):
    from splatedit.io import read
    from splatedit.io.copc import CopcFile
    src = terrain_copc(tmp_path / "terrain.copc.laz", N_POINTS)
    out = tmp_path / "edited.copc.laz"
    monkeypatch.setenv("SPLATEDIT_OOC_BUDGET", "2000,40000")
    ed = EditorProcess(xvfb, tmp_path, str(src), "--out-of-core", "on", "--save-as", str(out))
    try:
        s = ed.wait(lambda s: s["loaded"] and s["frames_presented"] > 0 and s["out_of_core"], "first frame", 90)
        first = s["out_of_core"]
        assert first["points"] == N_POINTS and first["nodes_shown"] == 1 and s["n"] < 2000
        # top view: the view refines in the background, frames keep coming meanwhile
        ed.xdo("mousemove", 700, 300, "key", "KP_7")
        s = ed.wait(lambda s: s["out_of_core"]["refined"] and s["out_of_core"]["nodes_shown"] > 1
                    and "nodes" not in s["jobs"], "refined top view", 90)
        oc = s["out_of_core"]
        assert 2000 < oc["shown"] <= 40_000 < N_POINTS and oc["max_depth_shown"] >= 1
        assert oc["loading_seconds"] > 0 and oc["loading_frames"] >= 1
        s = ed.idle(what="top view drawn", timeout=90)
        n_before = s["n"]
        cx, cy = _model_centre(ed, s)
        paint_support_stroke(ed, cx, cy)
        s = ed.wait(lambda s: s["support"] > 0 and s["n"] > n_before and s["out_of_core"]["waiting"] is None
                    and "region" not in s["jobs"], "the support's region at full resolution", 90)
        assert s["history_label"] == "full resolution"
        ed.xdo("key", "2", "mousemove", cx, cy, "click", "1")
        s = ed.idle(lambda s: s["handle"] > 0 and s["state"] == "ready", "handle painted and fitted", 120)
        ed.xdo("mousemove", cx + 30, cy, "key", "g", "z", "2", "Return")
        s = ed.idle(lambda s: s["edits"] == 1, "edit committed", 120)
        ed.xdo("key", "ctrl+s")
        s = ed.idle(lambda s: s["saved"] == str(out) and not s["dirty"], "saved", 120)
        assert s["validation_messages"] == 0 and s["internal_errors"] == 0
    finally:
        ed.close()
    a, b = CopcFile.open(src), CopcFile.open(out)
    assert b.point_count == N_POINTS
    before = a.read(list(a.nodes)).xyz
    after = b.read(list(b.nodes)).xyz
    rb = _sorted_rows(after)
    # the nodes whose cube is away from the moved points are the source's bytes
    old = {tuple(p) for p in np.round(before, 3)}
    new = np.round(after, 3)
    arrived = np.array([tuple(p) not in old for p in new])
    assert 100 < arrived.sum() < N_POINTS // 4
    lo, hi = new[arrived].min(0) - 1.0, new[arrived].max(0) + 1.0
    far = [k for k, nd in a.nodes.items() if (nd.bounds[0] > hi).any() or (nd.bounds[1] < lo).any()]
    assert far and all(a.read_compressed(k) == b.read_compressed(k) for k in far if k in b.nodes)
    # equal to the edit script replayed on the whole file in memory
    script = out.with_name("edited.copc.edits.json")
    replay = tmp_path / "replay.ply"
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2]))     # this checkout's splatedit
    r = subprocess.run([sys.executable, "-m", "splatedit.cli", "-q", "deform", str(src), "--edit", str(script),
                        "-o", str(replay)], capture_output=True, text=True, timeout=120, cwd=tmp_path, env=env)
    assert r.returncode == 0, r.stderr
    again = read(replay).world_positions()
    # both rounded to the 0.001 grid: a point half a step off may round one step apart
    np.testing.assert_allclose(_sorted_rows(again), rb, rtol=0, atol=1e-3 + 1e-9)
    # and out of core (a COPC out: only the nodes around the indexed points are read)
    replay_copc = tmp_path / "replay.copc.laz"
    r = subprocess.run([sys.executable, "-m", "splatedit.cli", "-q", "deform", str(src), "--edit", str(script),
                        "-o", str(replay_copc)], capture_output=True, text=True, timeout=120, cwd=tmp_path, env=env)
    assert r.returncode == 0, r.stderr
    c = CopcFile.open(replay_copc)
    # the same grid: at most one step apart where the editor's float path (file coordinates minus
    # the origin) and deform's (integer differences) round a moved point differently (2 of 150k once)
    np.testing.assert_allclose(_sorted_rows(c.read(list(c.nodes)).xyz), rb, rtol=0, atol=1e-3 + 1e-9)
