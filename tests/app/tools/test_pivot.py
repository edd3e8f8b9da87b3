"""Pivot and axes without a window: "." picks the support's rim (or the 3D
cursor, or the view centre) as the centre of R / S and of the gizmo, ","
picks the gizmo's and X / Y / Z's axes (global / local / view), Shift +
right click places the 3D cursor on the surface; an edit rotated about a
pivot keeps the pivot fixed."""

from __future__ import annotations

import math
import types

import numpy as np
import pytest

from splatedit.app.tools.pick_brush import BrushPicker
from splatedit.app.document.manipulation import GRAB, SCALE, Manipulation
from splatedit.app.tools.pivot import (CURSOR, LOCAL, SUPPORT_RIM, VIEW, VIEW_CENTRE, principal_frame,
                                       rim_centroid)
from splatedit.select.graph import NeighbourGraph
from splatedit.app.view.camera_control import OrbitCamera
from splatedit.app.document.session import Session
from splatedit.select.selection import HANDLE, SUPPORT
from tests.app.sessions import plane_cloud, view
from tests.app.ui.test_editor_routing import H, W, StubEditor

glfw = pytest.importorskip("glfw")


@pytest.fixture
def editor():
    """A fitted handle (r < 0.15 about (0.5, 0.1)) in a support disc (r < 0.6 about (0.2, 0.1)),
    seen obliquely (all three rings show)."""
    s = Session(plane_cloud(), fit_sync=True)
    r = np.linalg.norm(s.cloud.positions[:, :2] - [0.2, 0.1], axis=1)
    s.brush_target = SUPPORT
    s.end_stroke(s.paint(np.flatnonzero(r < 0.6)))
    s.brush_target = HANDLE                 # off the support's centre: the rim's centroid is elsewhere
    s.end_stroke(s.paint(np.flatnonzero(np.linalg.norm(s.cloud.positions[:, :2] - [0.5, 0.1], axis=1) < 0.15)))
    assert s.wait_fit() and s.active_fitted()
    ed = StubEditor(s)
    ed.cam = OrbitCamera(np.zeros(3), 4.0, yaw=0.6, pitch=0.5, scene_radius=1.5)
    yield ed
    s.close()


def key(ed, k, mods=0):
    ed.routing.on_key(types.SimpleNamespace(key=k, mods=mods, action=glfw.PRESS))


def test_rim_centroid_is_where_the_support_meets_the_fixed_part():
    c = plane_cloud(40)
    g = NeighbourGraph.build(c.positions)
    p = c.positions
    half = p[:, 0] > 0.3                                   # a limb: the right part of the plane
    rim = rim_centroid(p, half, g)
    step = 2.0 / 39
    assert 0.3 < rim[0] < 0.3 + 2 * step and abs(rim[1]) < 0.25 * step     # k-NN ties: not exact
    disc = np.linalg.norm(p[:, :2], axis=1) < 0.5
    assert np.allclose(rim_centroid(p, disc, g), 0.0, atol=0.02)
    assert rim_centroid(p, np.ones(c.n, bool), g) is None


def test_principal_frame_puts_x_along_the_longest_spread_right_handed():
    rng = np.random.default_rng(1)
    pts = rng.normal(size=(500, 3)) * [3.0, 1.0, 0.2]
    a = math.radians(30)
    rot = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
    f = principal_frame(pts @ rot.T)
    assert abs(f[:, 0] @ rot[:, 0]) > 0.99 and abs(f[:, 2] @ [0, 0, 1]) > 0.99
    assert np.allclose(f.T @ f, np.eye(3), atol=1e-12) and np.linalg.det(f) > 0


def test_a_framed_manipulation_grabs_and_scales_along_the_frames_axis():
    a = math.radians(40)
    f = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
    m = Manipulation(GRAB, np.zeros(3), view(), (0, 0), frame=f, frame_name="local")
    m.set_axis(0)
    m.type_char("2")
    assert np.allclose(m.matrix()[:3, 3], 2 * f[:, 0])
    assert m.label() == "Grab 2 along local X"
    s = Manipulation(SCALE, np.array([1.0, 0, 0]), view(), (0, 0), frame=f)
    s.set_axis(1)
    s.type_char("3")
    mat = s.matrix()
    assert np.allclose(mat[:3, :3] @ f[:, 1], 3 * f[:, 1]) and np.allclose(mat[:3, :3] @ f[:, 0], f[:, 0])
    assert np.allclose(mat[:3, :3] @ [1.0, 0, 0] + mat[:3, 3], [1.0, 0, 0])      # the pivot stays


def test_rotate_about_the_support_rim_keeps_the_rim_fixed_and_the_gizmo_sits_on_it(editor):
    ed, s = editor, editor.session
    key(ed, glfw.KEY_PERIOD)
    assert ed.pivot.mode == SUPPORT_RIM
    rim = ed.pivot.point()
    g = ed.selection_tools.graph(s.cloud)
    assert np.allclose(rim, rim_centroid(s.cloud.positions, s.selection.support, g))
    assert np.linalg.norm(rim - s.handle_centroid()) > 0.2
    px, _ = ed.cam.project(rim, W, H)
    assert np.allclose(ed.gizmo.scale_circle(W, H)[0], px[0])         # the gizmo is drawn on the pivot
    key(ed, glfw.KEY_R)
    assert np.allclose(s.manip.pivot, rim)
    key(ed, glfw.KEY_Z)
    for k in (glfw.KEY_3, glfw.KEY_0):
        ed.gizmo.type_key(k)
    m = s.manip.matrix()
    assert np.allclose(m[:3, :3] @ rim + m[:3, 3], rim) and not np.allclose(m, np.eye(4))
    key(ed, glfw.KEY_ENTER)
    assert len(s.edits) == 1 and s.history.labels[-1].startswith("Rotate 30 deg about Z")


def test_view_axes_put_the_gizmos_x_arrow_along_the_screen(editor):
    ed = editor
    key(ed, glfw.KEY_COMMA)
    assert ed.pivot.orientation == LOCAL
    key(ed, glfw.KEY_COMMA)
    assert ed.pivot.orientation == VIEW
    arrows = {k: p1 - p0 for k, p0, p1 in ed.gizmo.axes(W, H)}
    assert abs(arrows[0][1]) < 1e-6 * abs(arrows[0][0]) and arrows[0][0] > 0     # right on screen
    assert abs(arrows[1][0]) < 1e-6 * abs(arrows[1][1]) and arrows[1][1] < 0     # up on screen
    key(ed, glfw.KEY_G)
    key(ed, glfw.KEY_X)
    assert np.allclose(ed.session.manip.axis_vector(), ed.cam.basis()[0])
    assert ed.session.manip.axis_name() == "view X"


def test_shift_right_click_places_the_cursor_on_the_surface_and_it_can_be_the_pivot(editor):
    ed, s = editor, editor.session
    x, y = 300.0, 260.0
    o, d = ed.cam.pixel_ray(x, y, W, H)
    hit = o + d * (-o[2] / d[2])                             # the plane z = 0 under the pixel
    _, depth = ed.cam.project(hit, W, H)
    pick = np.zeros((H, W), np.int64)
    ed.pivot.ctx.visible = lambda: BrushPicker(pick, pick_depth=np.full((H, W), float(depth[0])))
    ed.routing.on_button(types.SimpleNamespace(x=x, y=y, action=glfw.PRESS, button=glfw.MOUSE_BUTTON_RIGHT,
                                       mods=glfw.MOD_SHIFT))
    assert ed.drag_tool is None
    assert np.allclose(ed.pivot.cursor, hit, atol=1e-9)
    (ring, *_), = [ed.pivot.shapes(W, H)]
    assert ring.closed and np.allclose(ring.points.mean(axis=0), (x, y), atol=1e-6)
    for _ in range(2):
        key(ed, glfw.KEY_PERIOD)
    assert ed.pivot.mode == CURSOR and np.allclose(ed.pivot.point(), hit)
    key(ed, glfw.KEY_S)
    assert np.allclose(s.manip.pivot, hit)
    key(ed, glfw.KEY_ESCAPE)
    key(ed, glfw.KEY_PERIOD)
    assert ed.pivot.mode == VIEW_CENTRE and np.allclose(ed.pivot.point(), ed.cam.target)
