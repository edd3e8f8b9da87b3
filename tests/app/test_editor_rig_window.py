"""The real editor window (Xvfb + xdotool): two simultaneous handles and a
control curve, each committed as one edit (the first in the detail mode, B),
saved, and reproduced by replaying the exported edit script with
``splatedit deform``."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.app.window_harness import EditorProcess, _foreground_centre, assert_replay_reproduces

pytestmark = [pytest.mark.window, pytest.mark.gpu, pytest.mark.slow]


def test_two_handles_and_a_curve(xvfb, tmp_path):
    from splatedit.data import default_model_path
    from splatedit.io import read

    out = tmp_path / "rig.ply"
    ed = EditorProcess(xvfb, tmp_path, "--save-as", str(out))
    try:
        s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0, "model loaded", 90)
        cx, cy = _foreground_centre(ed.screenshot(), s["panel_box"])
        # --- support: a bigger brush, a stroke around the centre
        ed.xdo("mousemove", cx, cy, "key", "bracketright", "bracketright", "bracketright")
        ed.xdo("mousemove", cx - 45, cy - 12, "mousedown", "1", "mousemove", cx, cy - 12,
               "mousemove", cx + 45, cy - 12, "mousemove", cx + 45, cy + 15, "mousemove", cx - 45, cy + 15,
               "sleep", "0.1", "mouseup", "1")
        s = ed.idle(lambda s: s["support"] > 200 and s["history"] == 2, "support painted")
        # --- handle 1 (left), then N and handle 2 (right)
        ed.xdo("key", "2", "bracketleft", "bracketleft", "bracketleft", "bracketleft", "bracketleft",
               "mousemove", cx - 28, cy, "click", "1")
        s = ed.idle(lambda s: s["handles"] == 1 and s["handle"] > 0 and s["state"] == "ready", "handle 1")
        ed.xdo("key", "n")
        ed.idle(lambda s: s["handles"] == 2 and s["active_handle"] == 1, "new handle")
        ed.xdo("mousemove", cx + 28, cy, "click", "1")
        s = ed.idle(lambda s: min(s["handle_sizes"]) > 0 and s["state"] == "ready"
                    and s["basis_columns"] == 8, "handle 2 painted, both fitted")
        # --- B: the detail mode (a refit of the detail basis); this edit is replayed in it
        assert s["deformation"] == "rotation" and s["basis_kind"] == "DeformationBasis"
        ed.xdo("key", "b")
        s = ed.idle(lambda s: s["deformation"] == "detail" and s["state"] == "ready"
                    and s["basis_kind"] == "DetailBasis", "detail mode fitted", 90)
        # --- move handle 2 (active) up, then drag handle 1 (becomes active) down: kept as a pose
        ed.xdo("mousemove", cx + 28, cy, "mousedown", "1", "mousemove", cx + 30, cy - 8,
               "mousemove", cx + 32, cy - 18, "sleep", "0.2", "mouseup", "1")
        s = ed.idle(lambda s: s["pose_pending"] and s["edits"] == 0, "handle 2 moved")
        ed.xdo("mousemove", cx - 28, cy, "mousedown", "1", "mousemove", cx - 30, cy + 6,
               "mousemove", cx - 34, cy + 14, "sleep", "0.2", "mouseup", "1")
        s = ed.idle(lambda s: s["active_handle"] == 0 and s["history"] == 7, "handle 1 moved")
        assert s["edits"] == 0 and s["pose_pending"]
        ed.xdo("key", "Return")
        s = ed.idle(lambda s: s["edits"] == 1 and not s["pose_pending"] and s["state"] == "ready",
                    "two-handle edit committed")
        # --- remove both handles, then a curve: K, three clicks on the support
        ed.xdo("key", "shift+n", "shift+n")
        ed.idle(lambda s: s["handles"] == 1 and s["handle"] == 0, "handles removed")
        ed.xdo("key", "k")
        ed.wait(lambda s: s["curve_mode"], "curve tool")
        for dx, dy in ((-40, 8), (0, 2), (40, 8)):
            ed.xdo("mousemove", cx + dx, cy + dy, "click", "1")
        s = ed.idle(lambda s: s["curve_points"] == 3 and s["state"] == "ready" and s["basis_columns"] == 3,
                    "curve drawn and fitted")
        # --- bend it: drag the middle dot up, then along X only
        x, y = (int(round(v)) for v in s["curve_dots"][1])
        ed.xdo("mousemove", x, y, "mousedown", "1", "mousemove", x + 2, y - 10,
               "mousemove", x + 3, y - 22, "sleep", "0.2", "mouseup", "1")
        s = ed.idle(lambda s: s["pose_pending"], "curve bent")
        assert s["curve_dots"][1][1] < y - 10
        ed.xdo("key", "Return")
        s = ed.idle(lambda s: s["edits"] == 2 and s["curve_points"] == 0, "curve edit committed")
        ed.xdo("key", "ctrl+s")
        s = ed.idle(lambda s: s["saved"] and not s["dirty"], "saved")
        script_path = tmp_path / "rig.edits.json"
        ed.xdo("key", "q")
        assert ed.proc.wait(30) == 0
        assert ed.status()["validation_messages"] == 0
        log = ed.stderr_path.read_text()
        assert "Traceback" not in log and "validation" not in log.lower(), log
    finally:
        ed.close()

    doc = json.loads(script_path.read_text())
    e1, e2 = doc["edits"]
    assert len(e1["handles"]) == 2 and len(e1["transforms"]) == 2 and e1["deformation"] == "detail"
    assert "curves" in e2 and len(e2["curves"][0]["points"]) == 3 and "handle" not in e2
    assert np.abs(np.asarray(e2["curves"][0]["move"][1])).max() > 0
    src, saved = read(default_model_path()), read(out)
    assert np.abs(saved.positions - src.positions).max() > 1e-3
    assert_replay_reproduces(script_path, out, tmp_path)
