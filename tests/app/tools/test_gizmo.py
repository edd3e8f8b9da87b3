"""The gizmo without a window: arrows, rotate rings and the scale grip are
picked in that order, and a drag on a ring / on the grip gives a rotation
about that world axis / a uniform scale, both about the handle centroid,
applied on release like the arrow drag (single handle: an edit at once)."""

from __future__ import annotations

import math
import types

import numpy as np
import pytest

from splatedit.select.selection import HANDLE, SUPPORT
from splatedit.app.view.camera_control import OrbitCamera
from splatedit.app.editor import Editor
from splatedit.app.tools.base import DragMode
from splatedit.app.document.session import GRAB, ROTATE, SCALE, Session
from splatedit.tolerances import EDITOR_GIZMO_HIT_PX, EDITOR_GIZMO_SCALE_PX
from tests.app.sessions import plane_cloud

W, H = 640, 480
G = types.SimpleNamespace(RELEASE=0, PRESS=1, MOUSE_BUTTON_LEFT=0, MOUSE_BUTTON_RIGHT=1,
                          MOUSE_BUTTON_MIDDLE=2, MOD_SHIFT=1, MOD_CONTROL=2, MOD_ALT=4)


class StubEditor(Editor):
    size = (W, H)

    def __init__(self, session, cam):            # no window, no GPU
        self.path, self.window = None, None
        self._init_state(cam, G)
        self.session = session
        self.messages = []

    def motion(self):
        pass

    def say(self, text):
        self.messages.append(text)


def button(ed, x, y, action):
    ed.routing.on_button(types.SimpleNamespace(x=x, y=y, action=action, button=G.MOUSE_BUTTON_LEFT, mods=0))


def drag(ed, points):
    """Left press at points[0], moves through the rest, release at the last."""
    button(ed, *points[0], G.PRESS)
    for x, y in points[1:]:
        ed.routing.on_move(types.SimpleNamespace(x=x, y=y))
    m = None if ed.session.manip is None else ed.session.manip.matrix()
    button(ed, *points[-1], G.RELEASE)
    return m


@pytest.fixture
def editor():
    s = Session(plane_cloud(), fit_sync=True)
    r = np.linalg.norm(s.cloud.positions[:, :2] - [0.2, 0.1], axis=1)
    s.brush_target = SUPPORT
    s.end_stroke(s.paint(np.flatnonzero(r < 0.8)))
    s.brush_target = HANDLE
    s.end_stroke(s.paint(np.flatnonzero(r < 0.2)))
    assert s.wait_fit() and s.active_fitted()
    # an oblique view: all three rings are visible
    cam = OrbitCamera(np.zeros(3), 4.0, yaw=0.6, pitch=0.5, scene_radius=1.5)
    yield StubEditor(s, cam)
    s.close()


def around(c, p, degrees, steps=6):
    """Points from ``p`` turning by ``degrees`` about pixel ``c`` (same radius)."""
    v = np.subtract(p, c)
    out = []
    for t in np.linspace(0.0, math.radians(degrees), steps + 1):
        cs, sn = math.cos(t), math.sin(t)
        out.append((c[0] + cs * v[0] - sn * v[1], c[1] + sn * v[0] + cs * v[1]))
    return out


def rotation_axis_angle(m):
    r = m[:3, :3]
    ang = math.degrees(math.acos(np.clip((np.trace(r) - 1) / 2, -1, 1)))
    w, v = np.linalg.eig(r)
    axis = np.real(v[:, np.argmin(np.abs(w - 1))])
    return axis / np.linalg.norm(axis), ang


def test_all_parts_are_shown_and_picked_in_priority_order(editor):
    ed = editor
    rings = dict(ed.gizmo.rings(W, H))
    assert sorted(rings) == [0, 1, 2] and len(ed.gizmo.axes(W, H)) == 3
    c, rad = ed.gizmo.scale_circle(W, H)
    centre_px = ed.cam.project(ed.gizmo.handle_centre(), W, H)[0][0]
    assert np.allclose(c, centre_px) and rad == EDITOR_GIZMO_SCALE_PX
    # every ring point lies on the projected world circle around the centroid
    for k, px in rings.items():
        assert np.isfinite(px).all() and np.allclose(px[0], px[-1])
        assert ed.gizmo.pick(*ed.gizmo.ring_grab_point(k, W, H)) == (ROTATE, k)
    # an arrow wins over a ring where they cross
    n_crossings = 0
    for k, p0, p1 in ed.gizmo.axes(W, H):
        tip = p0 + 0.95 * (p1 - p0)
        assert ed.gizmo.pick(*tip) == (GRAB, k)
        crossing = [q for q in rings[(k + 1) % 3]
                    if abs(float(np.linalg.det(np.c_[p1 - p0, q - p0]))) / np.linalg.norm(p1 - p0) < 1.0
                    and 0.3 < (q - p0) @ (p1 - p0) / ((p1 - p0) @ (p1 - p0)) < 1.0]
        for q in crossing:
            assert ed.gizmo.pick(*q) == (GRAB, k)
        n_crossings += len(crossing)
    # the scale grip: on its circle (away from the rest), not inside nor outside it
    for ang in np.linspace(0, 2 * math.pi, 12, endpoint=False):
        d = np.array([math.cos(ang), math.sin(ang)])
        assert ed.gizmo.pick(*(c + d * rad)) == (SCALE, None)
        assert ed.gizmo.pick(*(c + d * (rad + EDITOR_GIZMO_HIT_PX + 2))) is None
    assert n_crossings > 0
    assert ed.gizmo.pick(5, 5) is None
    # the overlay draws grip, rings and arrows (shapes: one list for both painters)
    from splatedit.app.tools.shapes import Circle, Dot, Polyline, to_patches
    shapes = ed.gizmo.shapes(W, H)
    kinds = [type(s) for s in shapes]
    assert kinds.count(Circle) == 1 and kinds.count(Polyline) >= 3 + 3 and kinds.count(Dot) == 3
    assert len(to_patches(shapes, (W, H))) == len(shapes)


def test_edge_on_rings_are_hidden_and_nothing_shows_while_moving(editor):
    ed = editor
    ed.cam.yaw, ed.cam.pitch = 0.0, 0.0          # looking down -z: X and Y rings seen edge-on
    assert [k for k, _ in ed.gizmo.rings(W, H)] == [2]
    c, rad = ed.gizmo.scale_circle(W, H)
    ed.session.curve_mode = True
    assert ed.gizmo.rings(W, H) == [] and ed.gizmo.scale_circle(W, H) is None
    assert ed.gizmo.pick(c[0] + rad, c[1]) is None


@pytest.mark.parametrize("k", [0, 1, 2])
def test_ring_drag_rotates_about_that_axis_through_the_centroid(editor, k):
    ed, s = editor, editor.session
    piv = ed.gizmo.handle_centre().copy()
    hnd = s.selection.handle.copy()
    before = s.cloud.positions[hnd].copy()
    c = ed.gizmo.scale_circle(W, H)[0]
    g = ed.gizmo.ring_grab_point(k, W, H)
    m = drag(ed, around(c, g, 25.0))
    axis, ang = rotation_axis_angle(m)
    assert abs(abs(axis[k]) - 1) < 1e-9 and ang == pytest.approx(25.0, abs=1e-6)
    assert np.allclose(m[:3, :3] @ piv + m[:3, 3], piv)          # the centroid stays put
    # the mouse sweeps counter-clockwise on screen: a positive turn about the axis
    # when it points at the viewer (right-handed), negative when it points away
    back = ed.cam.basis()[2]
    signed = math.degrees(math.atan2(m[:3, :3][(k + 2) % 3, (k + 1) % 3], m[:3, :3][(k + 1) % 3, (k + 1) % 3]))
    assert np.sign(signed) == -np.sign(back[k])      # y down: the listed sweep is clockwise on screen
    # released: one handle, no curve -> applied at once, the handle moved rigidly
    assert ed.drag is DragMode.NONE and s.manip is None and len(s.edits) == 1 and not s.pose_pending
    assert np.allclose(s.cloud.positions[hnd], before @ m[:3, :3].T + m[:3, 3], atol=1e-9)


def test_grip_drag_scales_uniformly_about_the_centroid(editor):
    ed, s = editor, editor.session
    piv = ed.gizmo.handle_centre().copy()
    c, rad = ed.gizmo.scale_circle(W, H)
    d = np.array([-0.6, 0.8])
    m = drag(ed, [tuple(c + d * rad), tuple(c + d * rad * 1.2), tuple(c + d * rad * 1.5)])
    assert np.allclose(m[:3, :3], 1.5 * np.eye(3))
    assert np.allclose(m[:3, :3] @ piv + m[:3, 3], piv)
    assert len(s.edits) == 1
    # inward, even through the centre: the factor stays > 0
    assert s.wait_fit() and s.active_fitted()
    c, rad = ed.gizmo.scale_circle(W, H)
    m = drag(ed, [tuple(c + d * rad), tuple(c + d * 0.5 * rad), tuple(c)])
    assert m[0, 0] > 0 and np.allclose(m[:3, :3], m[0, 0] * np.eye(3)) and m[0, 0] < 0.02


def test_ring_drag_with_several_handles_is_kept_as_a_pending_move(editor):
    ed, s = editor, editor.session
    assert s.add_handle()
    r = np.linalg.norm(s.cloud.positions[:, :2] - [-0.3, -0.3], axis=1)
    s.end_stroke(s.paint(np.flatnonzero(r < 0.15)))
    assert s.wait_fit() and s.active_fitted()
    ed.gizmo._centre_key = None
    c = ed.gizmo.scale_circle(W, H)[0]
    m = drag(ed, around(c, ed.gizmo.ring_grab_point(2, W, H), 20.0))
    assert abs(rotation_axis_angle(m)[0][2]) == pytest.approx(1.0)
    assert s.pose_pending and len(s.edits) == 0
    assert np.allclose(s.pose[s.selection.active], m)


def test_gizmo_is_hidden_when_the_handle_is_far_off_screen(editor):
    assert editor.gizmo.rings(W, H) and editor.gizmo.axes(W, H)
    # look far to the side: the handle projects thousands of pixels outside the window
    editor.cam.target = np.array([40.0, 0.0, 0.0])
    assert not editor.gizmo.rings(W, H) and not editor.gizmo.axes(W, H)
    assert editor.gizmo.scale_circle(W, H) is None


def test_readout_box_keeps_the_margin_on_every_side():
    """The live readout's box follows the cursor (down and right of it) and
    is moved to stay EDITOR_READOUT_MARGIN_PX inside the window."""
    from splatedit.app.tools.gizmo import readout_box
    from splatedit.tolerances import EDITOR_READOUT_MARGIN_PX as M, EDITOR_READOUT_OFFSET_PX as O
    assert readout_box((100, 100), 200, 17, 960, 600) == (100 + O, 100 + O)
    x, y = readout_box((955, 595), 200, 17, 960, 600)
    assert (x + 200, y + 17) == (960 - M, 600 - M)
    assert readout_box((-50, -50), 200, 17, 960, 600) == (M, M)
    assert readout_box((500, 300), 2000, 17, 960, 600)[0] == M       # wider than the window: from the left
