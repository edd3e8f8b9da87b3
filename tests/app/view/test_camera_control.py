"""Orbit camera math: projection consistency, orbit, pan, dolly to cursor, framing."""

import math

import numpy as np
import pytest

from splatedit.app.view.camera_control import OrbitCamera


def make_cam():
    return OrbitCamera(target=np.array([0.1, -0.2, 0.3]), distance=4.0, yaw=0.4, pitch=0.3,
                       fov_deg=45.0, scene_radius=1.0)


def test_view_is_rigid_and_eye_maps_to_origin():
    cam = make_cam()
    v = cam.view()
    assert np.allclose(v[:3, :3] @ v[:3, :3].T, np.eye(3))
    assert np.allclose(v[:3, :3] @ cam.eye + v[:3, 3], 0)
    # the target is straight ahead at the camera distance
    t = v[:3, :3] @ cam.target + v[:3, 3]
    assert np.allclose(t, [0, 0, -4.0])


def test_project_matches_projection_matrix_and_ray():
    cam = make_cam()
    w, h = 640, 480
    pts = np.random.default_rng(0).normal(size=(20, 3)) * 0.5
    px, depth = cam.project(pts, w, h)
    clip = (cam.view_projection(w, h) @ np.c_[pts, np.ones(20)].T).T
    ndc = clip[:, :2] / clip[:, 3:4]
    assert np.allclose(px[:, 0], (ndc[:, 0] + 1) * w / 2)
    assert np.allclose(px[:, 1], (ndc[:, 1] + 1) * h / 2)
    assert np.all((clip[:, 2] / clip[:, 3] > 0) & (clip[:, 2] / clip[:, 3] < 1))
    # the pixel ray through a projected point passes through it
    for p, q, d in zip(pts[:3], px[:3], depth[:3]):
        back = cam.point_at_depth(q[0], q[1], w, h, d)
        assert np.allclose(back, p, atol=1e-9)


def test_target_projects_to_centre():
    cam = make_cam()
    px, _ = cam.project(cam.target, 800, 600)
    assert np.allclose(px[0], [400, 300])


def test_orbit_keeps_distance_and_clamps_pitch():
    cam = make_cam()
    t0 = cam.target.copy()
    cam.orbit(100, 0)
    assert np.isclose(np.linalg.norm(cam.eye - t0), 4.0)
    cam.orbit(0, 1e6)
    assert cam.pitch < math.pi / 2
    r, u, b = cam.basis()
    assert np.isclose(np.linalg.norm(np.cross(r, u) - b), 0)


def test_pan_moves_target_pixel_with_mouse():
    cam = make_cam()
    w, h = 640, 480
    p = cam.target.copy()  # a world point at the pivot depth
    cam.pan(30, -20, h)
    px, _ = cam.project(p, w, h)
    assert np.allclose(px[0], [320 + 30, 240 - 20], atol=1e-6)


def test_dolly_to_cursor_keeps_point_under_cursor():
    cam = make_cam()
    w, h = 640, 480
    x, y = 500.0, 100.0
    p = cam.point_at_depth(x, y, w, h, cam.distance)
    d0 = cam.distance
    cam.dolly(2, x, y, w, h)
    assert cam.distance < d0
    px, _ = cam.project(p, w, h)
    assert np.allclose(px[0], [x, y], atol=1e-6)


def test_frame_fits_sphere():
    cam = make_cam()
    cam.frame([1, 2, 3], 0.5, aspect=16 / 9)
    w, h = 1600, 900
    # points on the sphere's silhouette stay on screen
    r, u, _ = cam.basis()
    for d in (r, -r, u, -u):
        px, depth = cam.project(np.array([1, 2, 3]) + 0.5 * d, w, h)
        assert 0 <= px[0, 0] <= w and 0 <= px[0, 1] <= h and depth[0] > 0
    assert np.allclose(cam.target, [1, 2, 3])


def test_frame_points():
    cam = make_cam()
    pts = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0]], float)
    cam.frame_points(pts, 1.0)
    px, _ = cam.project(pts, 500, 500)
    assert (px >= 0).all() and (px <= 500).all()


def _sphere_outline_px(cam, c, r, w, h):
    d = np.random.default_rng(1).normal(size=(40000, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    return cam.project(np.asarray(c) + r * d, w, h)[0]


@pytest.mark.parametrize("area", [(0.33, 0.03, 1.0, 1.0), (0.0, 0.0, 0.6, 1.0), (0.1, 0.2, 0.5, 0.9)])
def test_frame_into_an_area_touches_its_nearer_sides_and_stays_inside(area):
    """A sphere framed into a part of the window: its perspective outline
    lies inside that part and touches it on the binding pair of sides."""
    cam = make_cam()
    w, h = 960, 600
    c, r = np.array([1.0, 2.0, -3.0]), 0.7
    cam.frame(c, r, w / h, margin=1.0, area=area)
    px = _sphere_outline_px(cam, c, r, w, h)
    x0, y0, x1, y1 = area[0] * w, area[1] * h, area[2] * w, area[3] * h
    lo, hi = px.min(0), px.max(0)
    assert lo[0] >= x0 - 0.5 and hi[0] <= x1 + 0.5 and lo[1] >= y0 - 0.5 and hi[1] <= y1 + 0.5
    gaps = np.array([lo[0] - x0, x1 - hi[0], lo[1] - y0, y1 - hi[1]])
    # one pair of opposite sides is touched (to the sampling of the outline)
    assert min(gaps[:2].max(), gaps[2:].max()) < 1.0
    # and the outline is centred in the area both ways
    assert np.allclose((lo + hi) / 2, [(x0 + x1) / 2, (y0 + y1) / 2], atol=0.5)
    # the pivot is the sphere's centre
    assert np.allclose(cam.pivot(), c)


def test_frame_without_area_is_centred_and_resets_the_offset():
    cam = make_cam()
    cam.frame(np.zeros(3), 1.0, 1.6, area=(0.4, 0.0, 1.0, 1.0))
    assert cam.screen_offset[0] > 0
    cam.frame(np.zeros(3), 1.0, 1.6)
    assert cam.screen_offset == (0.0, 0.0)
    px, _ = cam.project(np.zeros(3), 800, 500)
    assert np.allclose(px[0], [400, 250])


def test_orbit_views_and_dolly_keep_an_offset_pivot_on_its_pixel():
    """Framed beside a panel, orbiting, the numpad views and the dolly drag
    turn / zoom about the framed centre: it keeps its pixel."""
    cam = make_cam()
    w, h = 960, 600
    c = np.array([0.3, 0.1, -0.2])
    cam.frame(c, 0.5, w / h, area=(0.35, 0.05, 1.0, 1.0))
    p0 = cam.project(c, w, h)[0][0]
    assert p0[0] > w * 0.6                         # right of the window centre
    cam.orbit(80.0, -30.0)
    assert np.allclose(cam.project(c, w, h)[0][0], p0, atol=1e-6)
    cam.turn_to(math.pi / 2, 0.0)
    assert np.allclose(cam.project(c, w, h)[0][0], p0, atol=1e-6)
    d = cam.distance
    cam.dolly(3.0)
    assert cam.distance < d and np.allclose(cam.project(c, w, h)[0][0], p0, atol=1e-6)


@pytest.mark.parametrize("up", [(0, 1, 0), (0, 0, 1), (1, 0, 0), (0, -1, 0)])
def test_the_first_view_looks_at_the_front_render_uses_too(up):
    """Yaw 0, pitch 0 (the editor's first view) puts the eye along
    front_direction(up), the direction of ``splatedit render``'s default camera."""
    from splatedit.model.orientation import front_direction
    cam = OrbitCamera(up_axis=np.array(up, float))
    right, cam_up, back = cam.basis()
    assert np.allclose(back, front_direction(up)) and np.allclose(cam_up, up)


def test_the_camera_state_changes_with_the_up_axis_and_the_screen_offset():
    """The editor redraws when the camera state changes: U (a new up axis)
    left the drawn frame stale while the gizmo moved (a tester's report)."""
    cam = OrbitCamera()
    before = cam.state()
    cam.up_axis = np.array([0.0, 0.0, 1.0])
    assert cam.state() != before
    moved = cam.state()
    cam.screen_offset = (0.1, 0.0)
    assert cam.state() != moved
