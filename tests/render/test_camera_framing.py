"""The default camera (splatedit.render.framing.default_view): it frames the
main body of a scan with far clumps, leaves a clean model's view as it was,
and sees a Z-up file from the front as the editor does."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.data import default_model_path
from splatedit.io import read
from splatedit.render.camera import Camera
from splatedit.render.framing import default_view

W, H = 320, 180
#: a pixel darker than this in some channel is the model (white background)
FOREGROUND_MAX = 230


def _foreground(img: np.ndarray) -> np.ndarray:
    return img[..., :3].astype(int).min(axis=2) < FOREGROUND_MAX


def _box(fg: np.ndarray) -> tuple[int, int, int, int]:
    ys, xs = np.nonzero(fg)
    return int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1


def _old_default(cloud) -> Camera:
    """The default camera before: the full bounding box, from +z."""
    lo, hi = cloud.bounds()
    return Camera.frame(lo, hi, aspect=W / H, min_radius=float(cloud.radii.max()))


def _render(renderer, cloud, camera) -> np.ndarray:
    renderer.set_cloud(cloud)
    return renderer.render(camera, W, H)


def test_poste_scan_fills_the_image_instead_of_showing_specks(renderer, shared_data):
    """poste_france.xyz (far clumps 190 units out of a ~24-unit scan): the
    full-box view drew 90 model pixels at 320x180 (0.16 %), the default
    view 5,495 (9.5 %), the scan 0.72 of the image high (measured)."""
    path = shared_data / "poste_france.xyz"
    cloud = read(path)
    before = _foreground(_render(renderer, cloud, _old_default(cloud)))
    view = default_view(cloud, (W, H), path=path)
    after = _foreground(_render(renderer, cloud, view.camera))
    assert view.extent.robust and view.extent.n_far > 0
    assert before.mean() < 0.01
    assert after.mean() > 0.05 and after.sum() > 20 * before.sum()
    x0, y0, x1, y1 = _box(after)
    assert (y1 - y0) / H > 0.5 and (x1 - x0) / W > 0.15
    # the scan sits in the middle of the image
    assert abs((x0 + x1) / 2 - W / 2) < 0.15 * W and abs((y0 + y1) / 2 - H / 2) < 0.15 * H


def test_clean_bunny_is_framed_as_before(renderer):
    cloud = read(default_model_path())
    view = default_view(cloud, (W, H), path=default_model_path())
    old = _old_default(cloud)
    assert np.allclose(view.camera.eye, old.eye) and np.allclose(view.camera.target, old.target)
    a = _foreground(_render(renderer, cloud, old))
    b = _foreground(_render(renderer, cloud, view.camera))
    assert np.abs(np.subtract(_box(a), _box(b))).max() <= 2
    assert abs(int(a.sum()) - int(b.sum())) <= 0.01 * a.sum()


def _z_up_las(path, positions):
    import laspy
    header = laspy.LasHeader(point_format=1, version="1.2")
    header.scales = np.array([1e-5, 1e-5, 1e-5])
    header.offsets = np.zeros(3)
    las = laspy.LasData(header)
    las.x, las.y, las.z = positions[:, 0], positions[:, 1], positions[:, 2]
    las.write(str(path))


def test_a_z_up_las_is_seen_from_the_front_like_the_y_up_model(renderer, tmp_path):
    """The bunny turned Z-up ((x, y, z) -> (x, -z, y)) and written as LAS: the
    default camera looks along +Y with Z up (not straight down) and draws the
    same silhouette as the Y-up PLY's default view (measured: the same box,
    7,024 vs 7,020 model pixels: LAS splats are estimated anew)."""
    bunny = read(default_model_path())
    p = bunny.positions
    path = tmp_path / "bunny_zup.las"
    _z_up_las(path, np.column_stack([p[:, 0], -p[:, 2], p[:, 1]]))
    las = read(path)
    view = default_view(las, (W, H), path=path)
    assert view.up is not None and view.up.label == "+Z"
    look = view.camera.target - view.camera.eye
    assert np.allclose(look / np.linalg.norm(look), [0, 1, 0]) and np.allclose(view.camera.up, [0, 0, 1])
    a = _foreground(_render(renderer, bunny, default_view(bunny, (W, H)).camera))
    b = _foreground(_render(renderer, las, view.camera))
    assert np.abs(np.subtract(_box(a), _box(b))).max() <= 2
    assert (a ^ b).sum() < 0.05 * a.sum()
    # the top-down view it used to be shows another silhouette
    lo, hi = las.bounds()
    top = _foreground(_render(renderer, las, Camera.frame(lo, hi, aspect=W / H)))
    assert (a ^ top).sum() > 0.3 * a.sum()


@pytest.mark.parametrize("up", [(0, 0, 1), (1, 0, 0), (0, -1, 0), (0.3, 0.2, 0.9)])
def test_a_given_up_alone_gets_an_eye_across_it(up):
    """``--up`` without ``--eye``: the eye is in front of the model about that
    up (it used to stay at +z: parallel to a Z up, an error)."""
    cloud = read(default_model_path())
    cam = default_view(cloud, (W, H), up=up).camera
    look = cam.target - cam.eye
    assert abs(look @ np.asarray(up, float)) < 1e-9 * np.linalg.norm(look) * np.linalg.norm(up)
    assert np.allclose(cam.target, (cloud.bounds()[0] + cloud.bounds()[1]) / 2)
