"""The camera tool's framing area: the window minus the side panel's column
and the menu bar (Home / F frame into it)."""

from __future__ import annotations

import pytest

from splatedit.app.tools.camera import free_area
from splatedit.tolerances import EDITOR_FRAME_MIN_FREE_FRACTION, EDITOR_GUI_PANEL_WIDTH

W, H = 960, 600


def test_left_panel_leaves_the_window_right_of_its_column_below_the_menu():
    x0, y0, x1, y1 = free_area(W, H, (8, 27, EDITOR_GUI_PANEL_WIDTH, 120), top=19)
    assert (x0 * W, y0 * H, x1 * W, y1 * H) == pytest.approx((8 + EDITOR_GUI_PANEL_WIDTH, 19, W, H))


def test_right_panel_leaves_the_window_left_of_it():
    px = W - 8 - EDITOR_GUI_PANEL_WIDTH
    x0, y0, x1, y1 = free_area(W, H, (px, 27, EDITOR_GUI_PANEL_WIDTH, 500))
    assert (x0 * W, y0, x1 * W, y1) == pytest.approx((0, 0, px, 1))


def test_no_panel_or_a_panel_leaving_too_little_is_the_whole_window():
    assert free_area(W, H, None) == (0.0, 0.0, 1.0, 1.0)
    narrow = int(W * (1 - EDITOR_FRAME_MIN_FREE_FRACTION)) + 4      # leaves under the minimum
    assert free_area(W, H, (0, 20, narrow, 300))[::2] == (0.0, 1.0)


def test_home_keeps_the_model_out_of_the_panel_column_and_uses_the_window_without_it():
    """Home through the camera tool of a window-less editor: every splat
    projects right of the panel's column and below the menu bar; with the
    panel hidden the model is centred in the whole window."""
    import types

    import numpy as np

    from splatedit.app.document.session import Session
    from tests.app.ui.test_editor_routing import StubEditor
    from tests.app.sessions import plane_cloud

    s = Session(plane_cloud(), fit_sync=True)
    try:
        ed = StubEditor(s)
        w, h = ed.size
        ed.gui = types.SimpleNamespace(menu_height=19.0)
        ed.panel_box = (8, 27, EDITOR_GUI_PANEL_WIDTH, 300)
        ed.camera.frame_all()
        px, _ = ed.cam.project(s.cloud.positions, w, h)
        assert px[:, 0].min() >= 8 + EDITOR_GUI_PANEL_WIDTH and px[:, 1].min() >= 19.0
        assert px[:, 0].max() <= w and px[:, 1].max() <= h
        lo, hi = s.cloud.bounds()
        assert np.allclose(ed.cam.pivot(), (lo + hi) / 2)       # orbits about the model's centre
        # before the first GUI frame the panel's first place is assumed
        ed.panel_box = (0, 0, 0, 0)
        ed.camera.frame_all()
        assert ed.cam.project(s.cloud.positions, w, h)[0][:, 0].min() >= 8 + EDITOR_GUI_PANEL_WIDTH
        # panel hidden (P): the whole window below the menu bar
        ed.panel_visible = False
        ed.camera.frame_all()
        assert ed.cam.screen_offset[0] == 0 and ed.cam.screen_offset[1] < 0     # a little down
        px, _ = ed.cam.project(s.cloud.positions, w, h)
        assert px[:, 0].min() < 8 + EDITOR_GUI_PANEL_WIDTH and px[:, 1].min() >= 19.0
        assert abs(ed.cam.project(ed.cam.pivot(), w, h)[0][0, 0] - w / 2) < 1e-6
    finally:
        s.close()


def _session_of(cloud):
    from splatedit.app.document.session import Session
    return Session(cloud, fit_sync=True)


def test_home_frames_the_main_body_of_a_cloud_with_far_clumps_and_says_so():
    """Home with 9 stray splats 50 units from a 2-unit plane (1 %): the plane
    fills the window as it does without them, the strays are off screen, the
    status line names them; the extent is computed once per cloud revision."""
    import numpy as np

    from splatedit.model.cloud import SplatCloud
    from tests.app.sessions import plane_cloud
    from tests.app.ui.test_editor_routing import StubEditor

    plane = plane_cloud()
    far = 50.0 * np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, -1, 0],
                           [0, 0, -1], [0.6, 0.8, 0], [0, 0.6, 0.8], [0.8, 0, -0.6]])
    cloud = SplatCloud(np.vstack([plane.positions, far]), np.vstack([plane.u, plane.u[:9]]),
                       np.vstack([plane.v, plane.v[:9]]), name="plane+strays")
    boxes = []
    for c in (plane, cloud):
        s = _session_of(c)
        try:
            ed = StubEditor(s)
            ed.panel_visible = False
            w, h = ed.size
            ed.camera.frame_all()
            px, depth = ed.cam.project(plane.positions, w, h)
            boxes.append((px.min(0), px.max(0)))
            if c is cloud:
                assert ed.messages[-1] == ("view: the whole model; left out of the view: 9 points far outside the main body "
                                           "(outliers?): `splatedit convert --remove-outliers`")
                strays, d = ed.cam.project(far, w, h)
                off = (d <= 0) | (strays[:, 0] < 0) | (strays[:, 0] > w) | (strays[:, 1] < 0) | (strays[:, 1] > h)
                assert off.all()
                before = ed.camera.extent()
                assert ed.camera.extent() is before                     # cached for the revision
                s.cloud = cloud.replace(positions=cloud.positions * 2)   # an edit: a new cloud
                after = ed.camera.extent()
                assert after is not before and np.isclose(after.radius, 2 * before.radius)
            else:
                assert ed.messages == ["view: the whole model"]      # no far points to name
        finally:
            s.close()
    assert np.allclose(boxes[0][0], boxes[1][0]) and np.allclose(boxes[0][1], boxes[1][1])


def test_home_on_the_clean_bunny_frames_its_full_bounding_sphere():
    """The bundled bunny (no far points): Home frames exactly the box's
    bounding sphere, as before the main-body extent."""
    import numpy as np

    from splatedit.app.view.camera_control import OrbitCamera
    from splatedit.data import default_model_path
    from splatedit.io import read
    from tests.app.ui.test_editor_routing import StubEditor

    cloud = read(default_model_path())
    s = _session_of(cloud)
    try:
        ed = StubEditor(s)
        w, h = ed.size
        ed.camera.frame_all()
        lo, hi = cloud.bounds()
        ref = OrbitCamera(yaw=ed.cam.yaw, pitch=ed.cam.pitch, up_axis=ed.cam.up_axis)
        ref.frame((lo + hi) / 2, float(np.linalg.norm(hi - lo)) / 2, w / h, area=ed.camera.view_area())
        assert np.allclose(ref.target, ed.cam.target, rtol=0, atol=1e-12) and ref.distance == ed.cam.distance
        assert ed.messages == ["view: the whole model"]
    finally:
        s.close()


@pytest.mark.parametrize("keys,name", [
    (("KEY_1", "MOD_SHIFT"), "view: front"), (("KEY_3", "MOD_SHIFT"), "view: right"),
    (("KEY_7", "MOD_SHIFT"), "view: top"), (("KEY_KP_7", 0), "view: top"),
    (("KEY_KP_1", "MOD_CONTROL"), "view: back"), (("KEY_7", "MOD_CONTROL|MOD_SHIFT"), "view: bottom"),
    (("KEY_HOME", 0), "view: the whole model"), (("KEY_F", 0), "view: the support"),
])
def test_a_view_key_replaces_the_previous_status_message_with_the_views_name(keys, name):
    """Shift+1/3/7, the numpad and Home / F: the status line names the new
    view instead of keeping the message of whatever was done before."""
    import glfw

    from splatedit.app.document.session import Session
    from tests.app.sessions import plane_cloud
    from tests.app.ui.test_editor_routing import StubEditor, key

    s = Session(plane_cloud(), fit_sync=True)
    try:
        ed = StubEditor(s)
        s.set_selection(s.cloud.positions[:, 0] > 0, None)
        ed.say("splat size 1.25x (display only; saves are unchanged)")     # an older message
        mods = 0 if keys[1] == 0 else eval("|".join(f"glfw.{m}" for m in keys[1].split("|")))
        key(ed, getattr(glfw, keys[0]), mods)
        assert ed.messages[-1].startswith(name), ed.messages
    finally:
        s.close()
