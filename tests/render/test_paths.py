"""The compute pre-pass path (default) and the all-in-vertex-shader path
(prepass=False, point_splats on/off) render the same image."""

from __future__ import annotations

import numpy as np

from splatedit.render.camera import Camera
from tests.render.deform_util import gaussian_basis
from tests.render.scenes import sphere

W = H = 160


def _frames(renderer, cam):
    out = {}
    saved = renderer.prepass, renderer.point_splats
    try:
        for prepass, points in ((True, True), (False, True), (False, False)):
            renderer.prepass, renderer.point_splats = prepass, points
            out[(prepass, points)] = (renderer.render(cam, W, H), renderer.pick(cam, W, H)[0])
    finally:
        renderer.prepass, renderer.point_splats = saved
    return out


def test_paths_agree_with_tiny_and_large_splats(renderer):
    # 60k splats at 160 px: most are below a pixel (point path); a close
    # camera makes the near ones large (quads)
    cloud = sphere(60000, overlap=1.0)
    renderer.set_cloud(cloud)
    idx = np.flatnonzero(cloud.positions[:, 2] > 0.2)
    renderer.set_basis(idx, *gaussian_basis(cloud.positions[idx], seed=9))
    renderer.set_displacement(np.full((4, 3), 0.15))
    renderer.set_selection(idx, idx[:100])
    for cam in (Camera(eye=(0, 0.3, 6.0), target=(0, 0, 0), fov_deg=30),
                Camera(eye=(0.2, 0.3, 1.9), target=(0, 0, 0), fov_deg=60)):
        frames = _frames(renderer, cam)
        ref, ref_pick = frames[(False, False)]
        for key, (img, pick) in frames.items():
            diff = np.abs(img.astype(int) - ref.astype(int))[..., :3]
            assert diff.mean() < 0.6, (key, diff.mean())
            assert (diff.max(axis=2) > 24).mean() < 0.003, key
            assert ((pick >= 0) == (ref_pick >= 0)).mean() > 0.995, key
