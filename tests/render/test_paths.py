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


def test_windowed_prepass_matches_the_vertex_path(renderer, monkeypatch):
    """A cloud whose records exceed the storage-buffer range is prepared and
    drawn in splat windows (here the range is forced small: 60k splats in 4
    windows, the last one shorter, a 16-column basis bound in several windows
    per splat window); image and pick equal the vertex path's."""
    cloud = sphere(60000, overlap=1.0)
    renderer.set_cloud(cloud)
    idx = np.flatnonzero(cloud.positions[:, 2] > 0.2)
    renderer.set_basis(idx, *gaussian_basis(cloud.positions[idx], k=16, seed=9))
    renderer.set_displacement(np.random.default_rng(9).normal(scale=0.1, size=(16, 3)))
    renderer.set_selection(idx, idx[:100])
    limits = renderer.dev.limits

    class Small:
        def __getattr__(self, name):
            return getattr(limits, name)
        maxStorageBufferRange = 48 * 16384      # 16,384 splats of records per window

    cam = Camera(eye=(0.2, 0.3, 1.9), target=(0, 0, 0), fov_deg=60)
    ref = _frames(renderer, cam)[(False, False)]
    assert renderer.prepass_windows == 1
    monkeypatch.setattr(renderer.dev, "limits", Small())
    renderer.prepass_part.free()
    try:
        saved = renderer.prepass
        renderer.prepass = True
        img, pick = renderer.render(cam, W, H), renderer.pick(cam, W, H)[0]
        windows = renderer.prepass_part.current.windows
        assert renderer.prepass_windows == 4
    finally:
        renderer.prepass = saved
        monkeypatch.undo()
        renderer.prepass_part.free()
    assert [cnt for _, cnt, _ in windows] == [16384, 16384, 16384, 60000 - 3 * 16384]
    for w0, wn, chunks in windows:         # basis windows of 3,072 splats tile each splat window
        assert len(chunks) == -(-wn // 3072)
        assert chunks[0][1] == w0 and sum(cnt for _, _, cnt in chunks) == wn
    diff = np.abs(img.astype(int) - ref[0].astype(int))[..., :3]
    assert diff.mean() < 0.6, diff.mean()
    assert (diff.max(axis=2) > 24).mean() < 0.003
    assert ((pick >= 0) == (ref[1] >= 0)).mean() > 0.995
    same = (pick >= 0) & (ref[1] >= 0)
    assert (pick[same] == ref[1][same]).mean() > 0.95       # global splat ids, not window rows
