"""The editor loop while an edit is applied in the background (no window):
document keys and brush presses are refused with a message, the camera
keeps its drags and keys, and how the commit ended is shown once (a message,
or the error box with the document unchanged)."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.app.document.session import GRAB, Session
from splatedit.app.tools.base import DragMode
from tests.app.sessions import view
from tests.app.document.test_commit_job import _bunny, _posed
from tests.app.test_editor_review_fixes import _plane_with_tiny_corner_splats, paint
from tests.app.ui.test_editor_routing import StubEditor, key, press

glfw = pytest.importorskip("glfw")


def test_only_the_view_answers_while_a_commit_runs():
    s = _posed(_bunny(120_000), sync_ms=0.0)
    ed = StubEditor(s)
    try:
        cloud, support = s.cloud, s.selection.support.copy()
        assert s.commit() and s.committing
        key(ed, glfw.KEY_Z, glfw.MOD_CONTROL)                 # undo: refused
        key(ed, glfw.KEY_ENTER)                               # commit again: refused
        press(ed, glfw.MOUSE_BUTTON_LEFT, x=320, y=240)       # the brush: refused
        assert ed.drag is DragMode.NONE
        assert sum("still being applied" in m for m in ed.messages) == 3, ed.messages
        yaw = ed.cam.yaw
        key(ed, glfw.KEY_KP_3)                                # a view key: works
        assert ed.cam.yaw != yaw
        press(ed, glfw.MOUSE_BUTTON_MIDDLE)                   # an orbit drag: works
        assert ed.drag is DragMode.ORBIT and s.committing
        assert s.cloud is cloud and np.array_equal(s.selection.support, support) and s.edits == ()
        assert s.wait_commit()
        ed.gizmo.report_commit()
        assert len(s.edits) == 1 and ed.error_box is None and "edit 1 applied" in ed.messages[-1]
        n = len(ed.messages)
        ed.gizmo.report_commit()                              # shown once
        assert len(ed.messages) == n
    finally:
        s.close()


def test_a_failed_background_commit_shows_the_error_box():
    c = _plane_with_tiny_corner_splats(4e-9)
    s = Session(c, fit_sync=True)
    ed = StubEditor(s)
    try:
        paint(s)
        assert s.wait_fit()
        assert s.begin(GRAB, view(), (100, 100))
        s.manip.set_axis(2)
        s.manip.type_char("3")
        s.commit_sync_ms = 0.0
        ed.finish_manip()                                     # Enter: a single handle commits
        assert s.committing
        assert s.wait_commit()
        ed.gizmo.report_commit()
        assert ed.error_box is not None and "degenerate splat axis" in ed.error_box
        assert s.cloud is c and s.edits == () and not s.dirty
    finally:
        s.close()
