"""Progressive full-quality frames (splatedit.render.progressive)."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.data import default_model_path
from splatedit.io import read
from splatedit.render.camera import Camera
from splatedit.render.progressive import ProgressiveFrame, composite

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
