"""Progressive full-quality frames (splatedit.render.splat.progressive)."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.data import default_model_path
from splatedit.io import read
from splatedit.render.camera import Camera
from splatedit.render.splat.progressive import ProgressiveFrame, composite

W, H = 120, 90


@pytest.fixture
def vertex_path(renderer):
    renderer.prepass = False
    yield renderer
    renderer.prepass = True


def test_progressive_frame_sharpens_and_ends_equal_to_the_single_frame(vertex_path):
    """The bundled bunny in chunks of 5000 splats (8 chunks, the last partial):
    visibility steps give no image, then every attribute step covers at least
    the pixels of the one before, covered pixels are opaque, and the last
    image is the single-submit frame bit for bit."""
    r = vertex_path
    bunny = read(default_model_path())
    r.set_cloud(bunny)
    cam = Camera.frame(*bunny.bounds(), aspect=W / H, direction=(0.3, 0.4, 1.0))
    full = r.render(cam, W, H)
    chunks = -(-bunny.n // 5000)
    covered = []
    with ProgressiveFrame(r, cam, W, H, 5000) as pf:
        for _ in range(chunks):
            assert pf.step() is None
        assert pf.phase == "attr" and pf.fraction == pytest.approx(0.5)
        while not pf.done:
            img = pf.step()
            covered.append(img[..., 3] > 0)
            assert set(np.unique(img[..., 3])) <= {0, 255}
        assert pf.step() is None and pf.restarts == 0
    assert len(covered) == chunks
    assert all((a <= b).all() for a, b in zip(covered, covered[1:]))
    assert covered[0].sum() < 0.9 * covered[-1].sum()          # it fills in
    assert np.array_equal(img[..., :3], full[..., :3])
    under = np.zeros_like(full)
    assert np.array_equal(composite(img, under)[covered[-1]], full[covered[-1]])


def test_images_composed_on_the_device_equal_the_cpu_composite(vertex_path):
    """Chunks drawn without readback and composed on the device (:meth:`show`)
    over a level-of-detail frame give, at every shown step, exactly the CPU
    composite of the read-back image so far over that frame (vertex path:
    deterministic) although each shading pass covers only the projected boxes
    of its chunks; visibility steps show the frame under unchanged; the last
    one is the single frame with its background (alpha 255)."""
    r = vertex_path
    bunny = read(default_model_path())
    r.set_cloud(bunny)
    cam = Camera.frame(*bunny.bounds(), aspect=W / H, direction=(0.3, 0.4, 1.0))
    full = r.render(cam, W, H)
    under = np.random.default_rng(3).integers(0, 256, (H, W, 4), dtype=np.uint8)
    under[..., 3] = 255
    expected = []
    with ProgressiveFrame(r, cam, W, H, 7000) as pf:
        while not pf.done:
            img = pf.step()
            if img is not None:
                expected.append(composite(img, under))
    shown, rects = [], []
    with ProgressiveFrame(r, cam, W, H, 7000) as pf:
        pf.set_under(under)
        while not pf.done:
            phase = pf.phase
            pf.step(readback=False)
            out = pf.show(readback=True)
            if phase == "depth":
                assert np.array_equal(out, under)
            else:
                shown.append(out)
                rects.append(pf.shaded_rect)
        last = pf.show(readback=True)
    assert len(shown) == len(expected) >= 5
    for got, want in zip(shown[:-1], expected[:-1]):
        assert np.array_equal(got[..., :3], want[..., :3])
    assert np.array_equal(last, full)
    # each shading pass covered only the rect its chunks can reach (the bunny file is not
    # spatially sorted: every chunk spans the model, whose box is ~53% of the image)
    areas = [w * h for _, _, w, h in rects]
    assert max(areas) < 0.6 * W * H, areas


def test_under_a_half_size_device_image_is_pixel_doubled(renderer):
    """A level-of-detail frame left on the device by another renderer of the
    same device at half size is blitted (pixel-doubled) under the chunks:
    uncovered pixels show it as the CPU path's np.repeat would."""
    from splatedit.render.splat.renderer import Renderer
    r = renderer
    bunny = read(default_model_path())
    r.set_cloud(bunny)
    cam = Camera.frame(*bunny.bounds(), aspect=W / H, direction=(0.3, 0.4, 1.0))
    with Renderer(device=r.dev) as lod:
        lod.set_cloud(bunny)
        lod.background = (0.2, 0.6, 0.3, 1.0)        # told apart from the full frame's background
        lod.prepass = False                           # deterministic: the two frames below are equal
        small = lod.render(cam, W // 2, H // 2)
        image = lod.render_resident(cam, W // 2, H // 2)
        doubled = np.repeat(np.repeat(small, 2, axis=0), 2, axis=1)
        with ProgressiveFrame(r, cam, W, H, 20000) as pf:
            pf.set_under((image, (W // 2, H // 2)))
            pf.step(readback=False)
            first = pf.show(readback=True)            # a visibility step: the frame under alone
            while not (pf.phase == "attr" and pf.next > 0):
                pf.step(readback=False)
            out = pf.show(readback=True)
    assert np.array_equal(first, doubled)
    changed = (out != doubled).any(axis=2)
    assert 0.01 < changed.mean() < 0.9, changed.mean()   # the first chunk, drawn over it


def test_progressive_frame_starts_over_when_another_frame_is_drawn(vertex_path):
    r = vertex_path
    bunny = read(default_model_path())
    r.set_cloud(bunny)
    cam = Camera.frame(*bunny.bounds(), aspect=W / H, direction=(0.3, 0.4, 1.0))
    with ProgressiveFrame(r, cam, W, H, 20000) as pf:
        pf.step()
        r.render(cam, W, H)                  # overwrites the shared depth target
        pf.step()
        assert pf.restarts == 1 and pf.phase == "depth" and pf.next == 20000
        while not pf.done:
            img = pf.step()
    assert np.array_equal(img[..., :3], r.render(cam, W, H)[..., :3])


def _close_to(img, ref):
    """The pre-pass tolerance (tests/render/test_paths.py): records are blended
    in the pre-pass's atomic order, not splat order."""
    diff = np.abs(img.astype(int) - ref.astype(int))[..., :3]
    assert diff.mean() < 0.6, diff.mean()
    assert (diff.max(axis=2) > 24).mean() < 0.003


def test_progressive_frame_draws_its_chunks_through_the_prepass(renderer):
    """Default renderer (pre-pass on): chunks of 5000 splats are rounded up to
    whole workgroups (5056), each chunk is prepared then drawn, the image fills
    in and the last one matches the one-submit pre-pass frame."""
    r = renderer
    bunny = read(default_model_path())
    r.set_cloud(bunny)
    cam = Camera.frame(*bunny.bounds(), aspect=W / H, direction=(0.3, 0.4, 1.0))
    full = r.render(cam, W, H)
    chunks = -(-bunny.n // 5056)
    covered, steps = [], 0
    with ProgressiveFrame(r, cam, W, H, 5000) as pf:
        while not pf.done:
            img = pf.step()
            steps += 1
            assert pf.prepared
            if img is not None:
                covered.append(img[..., 3] > 0)
        assert pf.restarts == 0
    assert steps == 2 * chunks and len(covered) == chunks
    assert all((a <= b).all() for a, b in zip(covered, covered[1:]))
    assert covered[0].sum() < 0.9 * covered[-1].sum()
    _close_to(img, full)


def test_progressive_frame_in_prepass_windows_of_a_deformed_cloud(renderer, monkeypatch):
    """A deformed 60k-splat sphere in forced pre-pass windows of 16,384 splats
    and 16-column basis windows of 3,072: chunks of 10,000 never cross a
    window (so 2 per window, 8 per phase) and the last image matches the
    one-submit windowed frame."""
    from tests.render.deform_util import gaussian_basis
    from tests.render.scenes import sphere
    r = renderer
    cloud = sphere(60000, overlap=1.0)
    r.set_cloud(cloud)
    idx = np.flatnonzero(cloud.positions[:, 2] > 0.2)
    r.set_basis(idx, *gaussian_basis(cloud.positions[idx], k=16, seed=9))
    r.set_displacement(np.random.default_rng(9).normal(scale=0.1, size=(16, 3)))
    limits = r.dev.limits

    class Small:
        def __getattr__(self, name):
            return getattr(limits, name)
        maxStorageBufferRange = 48 * 16384

    cam = Camera(eye=(0.2, 0.3, 1.9), target=(0, 0, 0), fov_deg=60)
    monkeypatch.setattr(r.dev, "limits", Small())
    r.prepass_part.free()
    try:
        full = r.render(cam, W, H)
        assert r.prepass_windows == 4
        starts = []
        with ProgressiveFrame(r, cam, W, H, 10000) as pf:
            while not pf.done:
                if pf.phase == "attr":
                    starts.append(pf.next)
                img = pf.step()
    finally:
        monkeypatch.undo()
        r.prepass_part.free()
    assert starts == [0, 10048, 16384, 26432, 32768, 42816, 49152, 59200]
    _close_to(img, full)


def test_progressive_frame_in_the_detail_mode_matches_the_single_frame(renderer):
    """The detail mode (prepare_detail.comp, pre-pass only) drawn in chunks of
    1,000 splats: the last image matches its one-submit frame, so the editor
    refines detail-mode edits progressively too."""
    from splatedit.deform.detail import DetailBasis
    from tests.deform.detail_scene import bend, bumpy_plane
    plane = bumpy_plane(nx=90, ny=30)
    c = plane.cloud
    det = DetailBasis.fit(c, plane.support, [plane.handle])
    dC = det.displacement([bend(plane)])
    r = renderer
    r.set_cloud(c)
    r.set_basis(*det.rows_for_gpu())
    r.set_detail(det.indices, det.detail_for_gpu())
    r.set_displacement(dC)
    cam = Camera.frame(*det.apply(c, dC).bounds(), W / H, direction=(0.3, -1.0, 0.6))
    full = r.render(cam, W, H)
    under = np.zeros_like(full)
    with ProgressiveFrame(r, cam, W, H, 1000) as pf:
        pf.set_under(under)
        steps = 0
        while not pf.done:
            pf.step(readback=False)
            steps += 1
        assert pf.prepared and steps == 2 * -(-c.n // 1024)
        img = pf.show(readback=True)
    _close_to(img, full)
    assert (full[..., :3] < 250).any() and not np.array_equal(full, under)


def test_pick_map_in_chunks_equals_the_single_pick(vertex_path):
    """After the frame, the view's pick map drawn in chunks of 7,000 splats
    (6 steps) equals :meth:`Renderer.pick` of the same view (vertex path:
    deterministic), index and depth."""
    r = vertex_path
    bunny = read(default_model_path())
    r.set_cloud(bunny)
    cam = Camera.frame(*bunny.bounds(), aspect=W / H, direction=(0.3, 0.4, 1.0))
    idx, depth = r.pick(cam, W, H)
    with ProgressiveFrame(r, cam, W, H, 7000) as pf:
        while not pf.done:
            pf.step(readback=False)
        steps = 0
        while not pf.pick_done:
            pf.pick_step()
            steps += 1
        got_idx, got_depth = pf.pick_result()
    assert steps == -(-bunny.n // 7000)
    assert (idx >= 0).mean() > 0.1
    assert np.array_equal(got_idx, idx)
    assert np.array_equal(np.isnan(got_depth), np.isnan(depth))
    assert np.allclose(got_depth[idx >= 0], depth[idx >= 0], rtol=1e-6)


def test_progressive_frame_with_eye_dome_lighting_ends_equal_to_the_edl_frame(vertex_path):
    """With ``Renderer.edl`` (the editor's Shift+E) the progressive frame's
    last image is the one-submit eye-dome frame bit for bit, and differs from
    the frame without it (a large model refined in the editor keeps EDL)."""
    r = vertex_path
    bunny = read(default_model_path())
    r.set_cloud(bunny)
    cam = Camera.frame(*bunny.bounds(), aspect=W / H, direction=(0.3, 0.4, 1.0))
    plain = r.render(cam, W, H)
    r.edl = True
    try:
        full = r.render(cam, W, H)
        with ProgressiveFrame(r, cam, W, H, 10000) as pf:
            img = None
            while not pf.done:
                img = pf.step()
        assert np.array_equal(img[..., :3], full[..., :3])
        assert not np.array_equal(full[..., :3], plain[..., :3])
    finally:
        r.edl = False
