"""The panel's transform fields act on what is active (real window under
Xvfb): disabled with a reason before anything is painted; with the curve
tool on and a curve picked, a number typed into the "position" field moves
the active curve point there (one undo step)."""

from __future__ import annotations

import pytest

from tests.app.test_editor_gui_window import _click
from tests.app.window_harness import EditorProcess, _foreground_centre, paint_support_stroke

pytestmark = [pytest.mark.window, pytest.mark.gpu, pytest.mark.slow]
pytest.importorskip("imgui_bundle")

#: model units: the status file rounds positions to 1e-9; the field parses
#: the typed text as a 32-bit float (ImGui InputFloat3): ~1e-7 relative
TYPED_TOL = 1e-6

_KEYS = {".": "period", "-": "minus"}


def _type_number(ed, text: str) -> None:
    ed.xdo("key", "ctrl+a", *(_KEYS.get(c, c) for c in text), "Return")


def test_position_field_moves_the_active_curve_point(xvfb, tmp_path):
    ed = EditorProcess(xvfb, tmp_path)
    try:
        s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0, "model loaded", 90)
        assert s["fields"]["kind"] == "none" and "paint a support" in s["fields"]["problem"]
        cx, cy = _foreground_centre(ed.screenshot(), s["panel_box"])
        # --- support: a bigger brush, a stroke around the model's centre
        paint_support_stroke(ed, cx, cy)
        ed.idle(lambda s: s["support"] > 200, "support painted")
        # --- curve tool, three points on the support
        ed.xdo("key", "k")
        ed.wait(lambda s: s["curve_mode"], "curve tool")
        for dx in (-30, 0, 30):
            ed.xdo("mousemove", cx + dx, cy, "sleep", "0.1", "click", "1")
        s = ed.idle(lambda s: s["curve_points"] == 3 and s["state"] == "ready", "curve picked and fitted")
        f = s["fields"]
        assert f["kind"] == "curve" and f["index"] == 2 and f["problem"] is None
        before = s["curve_positions"]
        assert f["position"] == before[2]
        hist = s["history"]
        # --- type a new x into the position field: the point moves there, the others stay
        x_new = before[2][0] + 0.02
        _click(ed, "field_position", dx=20)
        ed.wait(lambda s: s["gui_wants_keyboard"], "the field takes the keyboard")
        _type_number(ed, f"{x_new:.6f}")
        s = ed.idle(lambda s: s["pose_pending"], "curve point moved")
        after = s["curve_positions"]
        assert abs(after[2][0] - x_new) < TYPED_TOL
        assert after[2][1:] == pytest.approx(before[2][1:], abs=TYPED_TOL)
        assert after[:2] == before[:2]
        assert s["fields"]["position"] == after[2] and s["history"] == hist + 1
        assert s["edits"] == 0 and s["curve_points"] == 3
        # --- one undo puts it back
        ed.xdo("mousemove", cx, cy + 60, "key", "ctrl+z")
        s = ed.idle(lambda s: not s["pose_pending"], "undo")
        assert s["curve_positions"] == before
        ed.xdo("key", "Escape", "Escape", "q")
        ed.proc.wait(30)
        assert "Traceback" not in ed.stderr_path.read_text()
        assert ed.status()["validation_messages"] == 0
    finally:
        ed.close()
