"""Chunked cloud upload (Renderer.set_cloud through one staging buffer)."""

from __future__ import annotations

import numpy as np

from splatedit.data import default_model_path
from splatedit.io import read
from splatedit.model.cloud import SplatCloud
from splatedit.render.camera import Camera


def test_upload_in_many_chunks_gives_the_same_gpu_data_and_image(renderer, monkeypatch):
    """The bundled bunny (with colours) uploaded in chunks of 1000 splats, the
    last one partial: the device buffers hold exactly the float32 geometry and
    the colours of a one-chunk upload, and the frames agree."""
    import splatedit.render.splat.uploads as umod
    bunny = read(default_model_path())
    rng = np.random.default_rng(4)
    colors = rng.integers(0, 256, (bunny.n, 4), dtype=np.uint8)
    cloud = SplatCloud(bunny.positions, bunny.u, bunny.v, colors, None)
    cam = Camera.frame(*cloud.bounds(), aspect=1.0, direction=(0.3, 0.4, 1.0))
    out = []
    for chunk in (cloud.n, 1000):
        monkeypatch.setattr(umod, "RENDER_UPLOAD_CHUNK_SPLATS", chunk)
        renderer.set_cloud(cloud)
        geom = renderer.uploads.geom.read().view(np.float32).reshape(cloud.n, 9)
        col = renderer.uploads.color.read().reshape(cloud.n, 4)
        out.append((geom, col, renderer.render(cam, 96, 96)))
    assert cloud.n % 1000 != 0
    assert np.array_equal(out[0][0], out[1][0])
    assert np.array_equal(out[1][1], colors)
    expect = ((cloud.positions - renderer.origin) / renderer.scale).astype(np.float32)
    assert np.array_equal(out[1][0][:, :3], expect)
    # the same buffers give the same frame up to the blending order of the
    # pre-pass (its slots come from atomics): a rounding step of the fp16 sums
    diff = np.abs(out[0][2].astype(int) - out[1][2].astype(int))
    assert diff.max() <= 3 and diff.mean() < 0.05
