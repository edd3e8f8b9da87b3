"""The compute-shader rasterizer (splatedit.render.splat.compute_raster) draws the
same frame as the raster path: images within the reference tolerance, the
same covered pixels, the same accumulated weights; the path choice and the
frame's pass lists."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.errors import ParameterError
from splatedit.render.splat.compute_raster import probe_key
from splatedit.render.camera import Camera
from splatedit.render.splat.passes import ComputeAttributes, Frame, Prepass, pick_frame, splat_frame
from tests.render.conftest import REF_BAD_SHARE, REF_MEAN_TOL, REF_PIXEL_TOL
from tests.render.deform_util import gaussian_basis
from tests.render.scenes import sphere

W, H = 160, 120


def _needs_compute(renderer):
    if not renderer.dev.compute_raster:
        pytest.skip("the device lacks 64-bit buffer atomics or float32 buffer atomicAdd")


def _both(renderer, cam, w=W, h=H):
    """(raster image, compute image, raster weights, compute weights)."""
    saved = renderer.raster_path
    out = {}
    try:
        for path in ("raster", "compute"):
            renderer.raster_path = path
            assert renderer.frame_path(w, h) == path
            out[path] = (renderer.render(cam, w, h), renderer.render_buffers(cam, w, h)["weight"])
    finally:
        renderer.raster_path = saved
    return out["raster"][0], out["compute"][0], out["raster"][1], out["compute"][1]


def _assert_same_frame(a, b, wa, wb):
    """Images within the reference-image tolerance (tests/render/conftest.py),
    the same covered pixels, weights within the RGBA16F accumulation of the
    raster path (half-float blending rounds each add to 11 bits)."""
    diff = np.abs(a.astype(np.int16) - b.astype(np.int16))[..., :3]
    assert diff.mean() <= REF_MEAN_TOL, diff.mean()
    assert (diff.max(axis=2) > REF_PIXEL_TOL).mean() <= REF_BAD_SHARE
    assert ((wa > 0) == (wb > 0)).all(), "covered pixels differ"
    assert (wa > 0).sum() > 100
    fg = wa > 0
    rel = np.abs(wa[fg] - wb[fg]) / wa[fg]
    assert rel.max() < 0.01, rel.max()


def test_compute_path_matches_raster_on_a_deformed_tinted_sphere(renderer):
    _needs_compute(renderer)
    cloud = sphere(30000, overlap=1.0, colors=True)
    renderer.set_cloud(cloud)
    idx = np.flatnonzero(cloud.positions[:, 2] > 0.2)
    renderer.set_basis(idx, *gaussian_basis(cloud.positions[idx], seed=3))
    renderer.set_displacement(np.full((4, 3), 0.15))
    renderer.set_selection(idx, idx[:200])
    # far: mostly point-sized splats; near: large quads, some over the
    # 256-pixel bound (the workgroup list) and some crossing the near plane
    for cam in (Camera(eye=(0, 0.3, 6.0), target=(0, 0, 0), fov_deg=30),
                Camera(eye=(0.2, 0.3, 1.3), target=(0, 0, 0), fov_deg=70)):
        _assert_same_frame(*_both(renderer, cam))


def test_compute_path_draws_the_heat_map(renderer):
    _needs_compute(renderer)
    cloud = sphere(8000, overlap=1.2)
    renderer.set_cloud(cloud)
    idx = np.arange(cloud.n)
    renderer.set_basis(idx, *gaussian_basis(cloud.positions, seed=5))
    renderer.set_displacement(np.full((4, 3), 0.3))
    renderer.distortion_map = True
    try:
        a, b, wa, wb = _both(renderer, Camera(eye=(0, 0.3, 4.0), target=(0, 0, 0), fov_deg=40))
    finally:
        renderer.distortion_map = False
    _assert_same_frame(a, b, wa, wb)
    colours = a[wa > 0][:, :3].astype(int)
    assert np.ptp(colours[:, 0] - colours[:, 2]) > 20       # a heat ramp, not flat grey


def test_compute_path_matches_raster_on_a_real_scan(renderer, shared_data):
    """A real scan: 6,104 splats with estimated sizes, large on screen."""
    _needs_compute(renderer)
    from splatedit.io import read
    cloud = read(shared_data / "hippo1.ply")
    renderer.set_cloud(cloud)
    cam = Camera.frame(*cloud.bounds(), aspect=W / H, direction=(0.3, 0.4, 1.0))
    _assert_same_frame(*_both(renderer, cam))


def test_compute_path_matches_raster_in_prepass_windows(renderer, monkeypatch):
    """Clouds over one storage binding are prepared window by window; the
    compute passes run each window's pre-pass before their dispatches."""
    _needs_compute(renderer)
    renderer.set_cloud(sphere(20000, overlap=1.0))
    limits = renderer.dev.limits

    class Small:
        def __getattr__(self, name):
            return getattr(limits, name)
        maxStorageBufferRange = 48 * 8192      # 8,192 splats of records per window

    cam = Camera(eye=(0.2, 0.3, 2.5), target=(0, 0, 0), fov_deg=50)
    monkeypatch.setattr(renderer.dev, "limits", Small())
    renderer.prepass_part.free()
    try:
        got = _both(renderer, cam, 96, 72)
        assert renderer.prepass_windows == 3
    finally:
        monkeypatch.undo()
        renderer.prepass_part.free()
    _assert_same_frame(*got)


def test_path_choice_follows_argument_env_and_device(renderer, monkeypatch):
    from splatedit.render.splat.renderer import Renderer
    renderer.set_cloud(sphere(2000))
    saved = renderer.raster_path
    try:
        renderer.raster_path = "raster"
        assert renderer.frame_path(64, 48) == "raster"
        renderer.raster_path = "compute"
        assert renderer.frame_path(64, 48) == ("compute" if renderer.dev.compute_raster else "raster")
        renderer.prepass = False                    # the vertex path has no records: raster
        assert renderer.frame_path(64, 48) == "raster"
        renderer.prepass = True
        renderer.raster_path = "auto"
        renderer.path_probes.clear()
        renderer.render(Camera.frame(*renderer.cloud.bounds(), 64 / 48), 64, 48)
        if renderer.dev.compute_raster:             # measured once per size and count
            probe = renderer.path_probes[probe_key(64, 48, 2000)]
            assert probe["path"] == min(("raster", "compute"), key=lambda p: probe[f"ms_{p}"])
            assert renderer.frame_path(64, 48) == probe["path"]
            assert renderer.frame_path(66, 48) == probe["path"] and len(renderer.path_probes) == 1
    finally:
        renderer.raster_path = saved
        renderer.prepass = True
    monkeypatch.setenv("SPLATEDIT_RASTER", "raster")
    with Renderer(device=renderer.dev) as r:
        assert r.raster_path == "raster"
    monkeypatch.setenv("SPLATEDIT_RASTER", "fast")
    with pytest.raises(ParameterError, match="SPLATEDIT_RASTER"):
        Renderer(device=renderer.dev)
    with pytest.raises(ParameterError, match="raster_path"):
        Renderer(device=renderer.dev, raster_path="gpu")


def test_frames_declare_and_check_their_inputs():
    for path in ("raster", "compute"):
        f = splat_frame(path)
        assert "output" in f.outputs and "accum" in f.outputs
        assert f.timings == ("prepass", "visibility", "attributes", "shading")
    assert "vis_buffer" in splat_frame("compute").outputs and "depth" not in splat_frame("compute").outputs
    assert "pick" in pick_frame().outputs
    with pytest.raises(ValueError, match="vis_buffer"):
        Frame([Prepass(), ComputeAttributes()])        # attributes before any visibility pass
    with pytest.raises(ValueError, match="path"):
        splat_frame("tiles")


def test_compute_path_equals_raster_with_float32_accumulators(renderer):
    """With RGBA32F accumulators (no half-float blending) the two paths give
    the same image and weights and depths within float32 summation order."""
    _needs_compute(renderer)
    from splatedit.render.splat.renderer import Renderer
    cloud = sphere(5000)
    with Renderer(device=renderer.dev, accum_format="rgba32f") as r:
        r.set_cloud(cloud)
        cam = Camera.frame(*cloud.bounds(), 4 / 3)
        out = {}
        for path in ("raster", "compute"):
            r.raster_path = path
            out[path] = (r.render(cam, 128, 96), r.render_buffers(cam, 128, 96))
    (a, ba), (b, bb) = out["raster"], out["compute"]
    assert np.abs(a.astype(int) - b.astype(int)).max() <= 1
    for key in ("weight", "depth"):
        x, y = ba[key], bb[key]
        assert (np.isfinite(x) == np.isfinite(y)).all()
        fg = np.isfinite(x) & (x > 0)
        assert fg.sum() > 1000
        assert np.max(np.abs(x[fg] - y[fg]) / np.abs(x[fg])) < 1e-5, key


def test_auto_path_reuses_the_measurement_of_the_next_splat_count_bucket_but_not_further(renderer):
    """A cloud growing by one half-octave (an out-of-core scan's view refining)
    takes the measured choice of the bucket next to it; a reused choice is not
    passed on, so two buckets from a measurement the paths are measured again."""
    if not renderer.dev.compute_raster:
        pytest.skip("the device lacks the compute rasterizer: the auto path never probes")
    saved = renderer.raster_path
    try:
        renderer.raster_path = "auto"
        renderer.path_probes.clear()
        keys = []
        for n in (2000, 2900, 4100):                # half-octave buckets 22, 23, 24
            renderer.set_cloud(sphere(n))
            path = renderer.frame_path(64, 48)
            keys.append(probe_key(64, 48, n))
            assert path == renderer.path_probes[keys[-1]]["path"]
        assert [k[1] for k in keys] == [22, 23, 24]
        measured, reused, again = (renderer.path_probes[k] for k in keys)
        assert "reused" not in measured and "ms_raster" in measured
        assert reused["reused"] == keys[0] and reused["path"] == measured["path"]
        assert "reused" not in again and "ms_compute" in again     # next to a reused one only: probed
    finally:
        renderer.raster_path = saved
