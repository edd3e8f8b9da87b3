"""The 3D brush in the real window (Xvfb + xdotool): one stroke along the
bunny's tall ear, seen from the front, selects the ear's whole thickness
(front and back); the handle on the tip is grabbed (G), moved and applied;
the saved file has no tear, almost no stretched splat and no fragment.

Measures (against the input, h = median nearest-neighbour spacing):
tears = input neighbours within 2 h that end up more than 8 h apart (must
be 0); stretch = moved splats whose axis grows or shrinks beyond 4x (under
0.1 % of the moved splats); fragments = connected pieces of the neighbour
graph (the same as the input's).
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
import pytest

from tests.app.window_harness import EditorProcess, assert_replay_reproduces

pytestmark = [pytest.mark.window, pytest.mark.gpu, pytest.mark.slow]


def _camera(status: dict):
    from splatedit.app.view.camera_control import OrbitCamera
    c = status["camera"]
    return OrbitCamera(np.array(c["target"], float), c["distance"], c["yaw"], c["pitch"])


def _ear(cloud, graph) -> np.ndarray:
    """(n,) bool: the tall ear, the splats connected to the highest one above y = 0.3."""
    p = cloud.positions
    tip = int(np.argmax(p[:, 1]))
    return graph.connected([tip], p[:, 1] > 0.3)


def _components(graph, min_size: int = 5) -> list[int]:
    n, labels = graph.components(np.arange(graph.n))
    sizes = np.bincount(labels, minlength=n)
    return sorted(int(s) for s in sizes if s >= min_size)


def test_3d_brush_paints_the_ear_through_and_the_grab_does_not_tear(xvfb, tmp_path):
    from splatedit.data import default_model_path
    from splatedit.deform.distortion import count_tears
    from splatedit.io import read
    from splatedit.select.graph import NeighbourGraph

    src = read(default_model_path())
    graph = NeighbourGraph.build(src.positions)
    ear = _ear(src, graph)
    out = tmp_path / "ear.ply"
    ed = EditorProcess(xvfb, tmp_path, "--save-as", str(out))
    try:
        s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0, "model loaded", 90)
        assert s["brush_mode"] == "3d"
        ed.xdo("key", "KP_1")                      # front view
        s = ed.idle(lambda s: abs(s["camera"]["yaw"]) < 1e-9 and abs(s["camera"]["pitch"]) < 1e-9,
                    "front view")
        w, h = s["window"]
        cam = _camera(s)
        px, depth = cam.project(src.positions, w, h)
        # the ear on screen: from its base (lowest tenth) to the tip; the brush as wide as the
        # ear (closure adds only inside what the stroke covered on screen: its reach)
        ep, ey = px[ear], src.positions[ear, 1]
        base = ep[ey < np.quantile(ey, 0.1)].mean(axis=0)
        tip = ep[ey > np.quantile(ey, 0.97)].mean(axis=0)
        axis = (tip - base) / np.linalg.norm(tip - base)
        across = np.abs((ep - base) @ np.array([-axis[1], axis[0]]))
        want = float(np.quantile(across, 0.99))
        presses = max(0, round(math.log(want / 24.0) / math.log(1.2)))
        key = "bracketright" if want > 24 else "bracketleft"
        presses = abs(presses)
        if presses:
            ed.xdo("key", *[key] * presses)
        # --- one stroke along the ear, from the front only
        pts = [base + (tip - base) * t for t in np.linspace(-0.05, 1.0, 12)]
        moves = [v for q in pts[1:] for v in ("mousemove", int(round(q[0])), int(round(q[1])))]
        ed.xdo("mousemove", int(round(pts[0][0])), int(round(pts[0][1])), "mousedown", "1", *moves,
               "sleep", "0.1", "mouseup", "1")
        s = ed.idle(lambda s: s["support"] > 0 and s["history"] == 2, "ear painted")
        shot = ed.screenshot()[:h, :w]
        from PIL import Image
        Image.fromarray(shot[..., :3]).save(tmp_path / "painted.png")
        painted = s["support"]
        # --- the tools: V toggles the mode, grow / shrink by a ring and undo are one step each
        ed.xdo("key", "v")
        ed.wait(lambda s: s["brush_mode"] == "visible", "visible-only brush")
        ed.xdo("key", "v")
        ed.wait(lambda s: s["brush_mode"] == "3d", "3D brush again")
        ed.xdo("key", "ctrl+equal")
        s = ed.idle(lambda s: s["history"] == 3, "grown")
        grown = s["support"]
        ed.xdo("key", "ctrl+minus")
        s = ed.idle(lambda s: s["history"] == 4, "shrunk")
        assert grown > painted and s["support"] < grown
        ed.xdo("key", "ctrl+z", "ctrl+z")
        s = ed.idle(lambda s: s["undo_position"] == 1, "tools undone")
        assert s["support"] == painted
        # --- the handle: the ear's tip (handle brush, a small radius)
        ed.xdo("key", "2", *["bracketleft"] * (presses + 3 if key == "bracketright" else 3))
        tip_px = tip + (base - tip) * 0.04
        ed.xdo("mousemove", int(round(tip_px[0])), int(round(tip_px[1])), "click", "1")
        s = ed.idle(lambda s: s["handle"] > 0 and s["state"] == "ready", "handle painted and fitted", 120)
        support_n, handle_n = s["support"], s["handle"]
        # --- grab it with G, move to the right and up, Enter
        x0, y0 = int(round(tip_px[0])), int(round(tip_px[1]))
        ed.xdo("key", "g")
        ed.wait(lambda s: s["manip"] == "grab", "grab started")
        ed.xdo("mousemove", x0 + 30, y0 - 10, "mousemove", x0 + 70, y0 - 25, "sleep", "0.2", "key", "Return")
        s = ed.idle(lambda s: s["edits"] == 1 and s["state"] == "ready", "edit applied", 120)
        ed.xdo("mousemove", 1270, 790)
        ed.idle(lambda s: True, "idle after the edit")
        Image.fromarray(ed.screenshot()[:h, :w, :3]).save(tmp_path / "moved.png")
        ed.xdo("key", "ctrl+s")
        s = ed.idle(lambda s: s["saved"] and not s["dirty"], "saved")
        script_path = Path(s["script"])
        assert s["validation_messages"] == 0
    finally:
        ed.close()
    log = ed.stderr_path.read_text()
    assert "Traceback" not in log, log

    # --- the selection: the ear's whole thickness, front- and back-facing splats alike
    doc = json.loads(script_path.read_text())
    e = doc["edits"][0]
    assert e["support"].get("fill_holes") is False       # the closed selection is recorded as is
    support = np.zeros(src.n, bool)
    support[np.asarray(e["support"]["indices"])] = True
    assert support.sum() == support_n
    facing = src.normals[:, 2] > 0                          # the front view looks along -z
    core = ear & (src.positions[:, 1] > 0.33)               # away from the stroke's start
    front_sel = (support & core & facing).sum() / (core & facing).sum()
    back_sel = (support & core & ~facing).sum() / (core & ~facing).sum()
    assert front_sel > 0.97 and back_sel > 0.97, (front_sel, back_sel)
    handle = np.zeros(src.n, bool)
    handle[np.asarray(e["handle"]["indices"])] = True
    assert handle.sum() == handle_n
    assert (handle & ~facing).sum() > 0.3 * handle.sum()   # closure took the back of the tip

    # --- the saved file against the input: no tear, no stretch, no fragment
    saved = read(out)
    hsp = graph.spacing
    tears = count_tears(src.positions, saved.positions, hsp)
    disp = np.linalg.norm(saved.positions - src.positions, axis=1)
    moved = disp > 1e-3 * hsp
    assert disp[handle].min() > 20 * hsp                    # the tip really moved
    ratio = np.stack([np.linalg.norm(saved.u, axis=1) / np.linalg.norm(src.u, axis=1),
                      np.linalg.norm(saved.v, axis=1) / np.linalg.norm(src.v, axis=1)], axis=1)
    stretched = int((((ratio > 4) | (ratio < 0.25)).any(axis=1) & moved).sum())
    frag_in = _components(graph)
    frag_out = _components(NeighbourGraph.build(saved.positions))
    report = (f"tears {tears}, stretched {stretched} of {int(moved.sum())} moved, support {support_n} "
              f"(ear front {front_sel:.3f}, back {back_sel:.3f}), handle {handle_n}, "
              f"pieces in {len(frag_in)} out {len(frag_out)}")
    if os.environ.get("SPLATEDIT_TEST_REPORT"):
        print(report)
    assert tears == 0, report
    assert stretched < 0.001 * moved.sum(), report
    assert len(frag_out) == len(frag_in) and frag_out[-1] >= frag_in[-1], report
    # --- `splatedit deform` with the exported script replays the saved file exactly
    assert_replay_reproduces(script_path, out, tmp_path)


def test_an_erase_stroke_in_a_support_stays_erased_and_says_so(xvfb, tmp_path):
    """Ctrl+drag across the middle of a painted support: the support ends up
    smaller than before the stroke (the tester saw 9158 -> 9209, and a
    small hole refilled by closure), and the status line counts the erased
    splats."""
    from tests.app.window_harness import _foreground_centre
    ed = EditorProcess(xvfb, tmp_path)
    try:
        s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0, "model loaded", 90)
        cx, cy = _foreground_centre(ed.screenshot(), s["panel_box"])
        ed.xdo("mousemove", cx, cy, "key", "bracketright", "bracketright", "bracketright", "bracketright")
        ed.xdo("mousemove", cx - 60, cy - 30, "mousedown", "1", "mousemove", cx + 60, cy - 30,
               "mousemove", cx + 60, cy, "mousemove", cx - 60, cy, "mousemove", cx - 60, cy + 30,
               "mousemove", cx + 60, cy + 30, "sleep", "0.1", "mouseup", "1")
        s = ed.idle(lambda s: s["support"] > 1000 and s["history"] == 2, "support painted")
        before = s["support"]
        ed.xdo("key", "bracketleft", "bracketleft", "bracketleft", "bracketleft", "bracketleft", "bracketleft")
        ed.xdo("mousemove", cx - 15, cy, "keydown", "ctrl", "mousedown", "1", "mousemove", cx, cy,
               "mousemove", cx + 15, cy, "sleep", "0.1", "mouseup", "1", "keyup", "ctrl")
        s = ed.idle(lambda s: s["history"] == 3, "erase stroke")
        assert s["support"] < before
        msg = s["message"]
        assert msg == f"erased {before - s['support']:,} splats from the support", msg
        assert s["validation_messages"] == 0
    finally:
        ed.close()
