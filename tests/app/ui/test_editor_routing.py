"""The thin editor loop without a window: mouse presses go to the tools in
order (the camera takes middle / Alt drags, the gizmo a click on a handle,
the brush the rest) and keys through the keymap to the tools' actions, in
the context the editor is in (help, manipulation, idle)."""

from __future__ import annotations

import math
import types

import numpy as np
import pytest

from splatedit.app.view.camera_control import OrbitCamera
from splatedit.app.editor import Editor
from splatedit.app.document.session import Session
from splatedit.app.tools.base import DragMode
from splatedit.select.selection import HANDLE, SUPPORT
from tests.app.sessions import plane_cloud

glfw = pytest.importorskip("glfw")
W, H = 640, 480


class StubEditor(Editor):
    size = (W, H)

    def __init__(self, session):
        self.path, self.window = None, None
        self._init_state(OrbitCamera(np.zeros(3), 4.0, yaw=0.6, pitch=0.5, scene_radius=1.5), glfw)
        self.session = session
        self.viewport = types.SimpleNamespace(grey=False, splat_scale=1.0, distortion_map=False, dc=None)
        self.messages = []

    def say(self, text):
        self.messages.append(text)


@pytest.fixture
def ed():
    s = Session(plane_cloud(), fit_sync=True)
    yield StubEditor(s)
    s.close()


def key(ed, k, mods=0):
    ed.routing.on_key(types.SimpleNamespace(key=k, mods=mods, action=glfw.PRESS))


def press(ed, button, mods=0, x=100.0, y=100.0, action=None):
    ed.routing.on_button(types.SimpleNamespace(x=x, y=y, button=button, mods=mods,
                                       action=glfw.PRESS if action is None else action))


@pytest.mark.parametrize("button,mods,mode", [
    (glfw.MOUSE_BUTTON_MIDDLE, 0, DragMode.ORBIT),
    (glfw.MOUSE_BUTTON_MIDDLE, glfw.MOD_SHIFT, DragMode.PAN),
    (glfw.MOUSE_BUTTON_MIDDLE, glfw.MOD_CONTROL, DragMode.DOLLY),
    (glfw.MOUSE_BUTTON_LEFT, glfw.MOD_ALT, DragMode.ORBIT),
    (glfw.MOUSE_BUTTON_LEFT, glfw.MOD_ALT | glfw.MOD_SHIFT, DragMode.PAN),
])
def test_camera_tool_takes_middle_and_alt_drags(ed, button, mods, mode):
    yaw, target = ed.cam.yaw, np.array(ed.cam.target, float)
    press(ed, button, mods)
    assert ed.drag is mode and ed.drag_tool is ed.camera
    ed.routing.on_move(types.SimpleNamespace(x=140.0, y=120.0))
    moved = ed.cam.yaw != yaw or not np.allclose(ed.cam.target, target) or ed.cam.distance != 4.0
    assert moved
    press(ed, button, mods, action=glfw.RELEASE)
    assert ed.drag is DragMode.NONE and ed.drag_tool is None


def test_keys_reach_the_tools_through_the_keymap(ed):
    s = ed.session
    key(ed, glfw.KEY_2)
    assert s.brush_target == HANDLE
    key(ed, glfw.KEY_1)
    assert s.brush_target == SUPPORT
    r = ed.brush.radius
    key(ed, glfw.KEY_RIGHT_BRACKET)
    assert ed.brush.radius > r
    key(ed, glfw.KEY_RIGHT_BRACKET, glfw.MOD_SHIFT)           # Shift+]: the splats, not the brush
    assert math.isclose(ed.viewport.splat_scale, 1.25)
    key(ed, glfw.KEY_M)
    assert ed.viewport.grey
    key(ed, glfw.KEY_K)
    assert s.curve_mode
    key(ed, glfw.KEY_ESCAPE)                                  # Esc with nothing pending: curve tool off
    assert not s.curve_mode and ed.running
    key(ed, glfw.KEY_G)                                       # nothing to move yet: says why
    assert s.manip is None and "support" in ed.messages[-1]
    key(ed, glfw.KEY_KP_1, glfw.MOD_CONTROL)
    assert math.isclose(ed.cam.yaw, math.pi) and ed.cam.pitch == 0.0
    key(ed, glfw.KEY_7, glfw.MOD_SHIFT)                       # without a numpad: Shift + top-row digit
    assert ed.cam.pitch > 1.5
    key(ed, glfw.KEY_3, glfw.MOD_SHIFT | glfw.MOD_CONTROL)    # Ctrl+Shift+3: left
    assert math.isclose(abs(ed.cam.yaw), math.pi / 2) and ed.cam.pitch == 0.0
    key(ed, glfw.KEY_1)                                       # the plain digit is still the support brush
    assert ed.session.brush_target == SUPPORT
    key(ed, glfw.KEY_U)
    assert ed.camera.up.label == "+Z" and np.allclose(ed.cam.up_axis, [0, 0, 1])


def test_help_context_comes_first_and_esc_closes_it(ed):
    key(ed, glfw.KEY_F1)
    assert ed.help.shown
    ed.help.rows = 10                                         # as a 10-line window would lay it out
    key(ed, glfw.KEY_PAGE_DOWN)
    assert ed.help.top == 8                                   # a page minus the overlap
    key(ed, glfw.KEY_1)                                       # other keys still work under the help
    assert ed.session.brush_target == SUPPORT
    key(ed, glfw.KEY_ESCAPE)
    assert not ed.help.shown and ed.running
    key(ed, glfw.KEY_P)
    assert not ed.panel_visible


def test_a_click_on_a_fitted_handle_grabs_it_and_typed_keys_go_to_the_move(ed):
    s = ed.session
    r = np.linalg.norm(s.cloud.positions[:, :2], axis=1)
    s.brush_target = SUPPORT
    s.end_stroke(s.paint(np.flatnonzero(r < 0.8)))
    s.brush_target = HANDLE
    s.end_stroke(s.paint(np.flatnonzero(r < 0.2)))
    assert s.wait_fit() and s.active_fitted()
    ed.mouse = (300.0, 200.0)
    key(ed, glfw.KEY_G)
    assert s.manip is not None
    for k in (glfw.KEY_Z, glfw.KEY_KP_0, glfw.KEY_PERIOD, glfw.KEY_2):    # in a move: axis and digits
        key(ed, k)
    assert s.manip.axis == 2 and s.manip.typed == "0.2"
    assert ed.gizmo.readout_text().startswith("distance Z 0.2")
    key(ed, glfw.KEY_F1)                                      # the help open: Esc still cancels the move
    key(ed, glfw.KEY_ESCAPE)
    assert s.manip is None and ed.help.shown
    key(ed, glfw.KEY_F1)
    key(ed, glfw.KEY_G)
    for k in (glfw.KEY_Z, glfw.KEY_KP_0, glfw.KEY_PERIOD, glfw.KEY_2):
        key(ed, k)
    key(ed, glfw.KEY_ENTER)
    assert s.manip is None and len(s.edits) == 1
    assert np.allclose(s.cloud.positions[r < 0.2, 2], 0.2)
