"""Picking pass and the headless PNG entry point."""

from __future__ import annotations

import os

import numpy as np
import pytest
from PIL import Image

from splatedit.errors import InputError
from splatedit.render.camera import Camera
from splatedit.render.splat.headless import render_to_png
from tests.render.deform_util import gaussian_basis
from tests.render.scenes import sphere


def test_pick_indices_and_depth(renderer):
    cloud = sphere(3000, overlap=1.0)
    renderer.set_cloud(cloud)
    cam = Camera(eye=(0, 0, 4.0), target=(0, 0, 0), fov_deg=35)
    idx, depth = renderer.pick(cam, 128, 128)
    assert idx.shape == (128, 128) and idx.dtype == np.int64
    fg = idx >= 0
    assert fg.sum() > 2000 and idx.max() < cloud.n
    assert np.isnan(depth[~fg]).all() and (idx[0, 0] == -1)
    # the picked splat at the image centre faces the camera: the one with the largest z
    centre = idx[64, 64]
    assert cloud.positions[centre, 2] > 0.99
    assert abs(depth[64, 64] - 3.0) < 0.02
    # picked splats lie in front: their centre is near the pixel's depth
    view = cam.view_matrix()
    zc = -(cloud.positions[idx[fg]] @ view[:3, :3].T + view[:3, 3])[:, 2]
    assert np.median(np.abs(zc - depth[fg])) < 0.03
    # a rectangle equals the same part of the whole image
    ridx, rdepth = renderer.pick(cam, 128, 128, rect=(40, 50, 30, 20))
    assert ridx.shape == (20, 30)
    assert np.array_equal(ridx, idx[50:70, 40:70])
    np.testing.assert_allclose(rdepth, depth[50:70, 40:70], equal_nan=True)


def test_render_to_png(tmp_path):
    cloud = sphere(2000, colors=True)
    out = tmp_path / "sub" / "img.png"
    idx = np.arange(1000)
    B = gaussian_basis(cloud.positions[idx])
    p = render_to_png(cloud, out, size=(96, 64), basis=(idx, *B), dC=np.full((4, 3), 0.1),
                      buffers_path=tmp_path / "b.npz")
    assert p == out and out.is_file()
    img = np.asarray(Image.open(out))
    assert img.shape == (64, 96, 4) and (img[..., :3] < 250).any()
    bufs = np.load(tmp_path / "b.npz")
    assert set(bufs.files) == {"depth", "normal", "weight", "color"}
    assert bufs["normal"].shape == (64, 96, 3)
    assert not list(tmp_path.glob("**/*.tmp"))


def _no_renderer(monkeypatch):
    import splatedit.render.splat.headless as headless

    def refuse(*a, **k):
        raise AssertionError("rendered before checking the output")
    monkeypatch.setattr(headless, "Renderer", refuse)


def test_render_to_png_output_under_a_regular_file(tmp_path, monkeypatch):
    """Checked before rendering: an InputError naming the path."""
    (tmp_path / "file").write_text("x")
    _no_renderer(monkeypatch)
    out = tmp_path / "file" / "img.png"
    with pytest.raises(InputError) as e:
        render_to_png(sphere(50), out, size=(8, 8))
    assert str(out) in str(e.value) and "\n" not in str(e.value)
    with pytest.raises(InputError, match=str(tmp_path / "file" / "b.npz")):
        render_to_png(sphere(50), tmp_path / "ok.png", size=(8, 8), buffers_path=tmp_path / "file" / "b.npz")
    with pytest.raises(InputError, match="is a directory"):
        render_to_png(sphere(50), tmp_path, size=(8, 8))
    assert not (tmp_path / "ok.png").exists()


def test_render_to_png_write_error_is_an_input_error(tmp_path, monkeypatch):
    import errno
    import contextlib
    import splatedit.render.splat.headless as headless

    @contextlib.contextmanager
    def full_disk(path, mode="wb"):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
        yield
    monkeypatch.setattr(headless, "atomic_open", full_disk)
    out = tmp_path / "img.png"
    with pytest.raises(InputError, match="No space left") as e:
        render_to_png(sphere(200), out, size=(16, 16))
    assert e.value.path == str(out)


def test_cli_render_output_under_a_regular_file_is_one_line(tmp_path, capsys):
    from splatedit.cli import main
    from splatedit.io import write
    ply = tmp_path / "s.ply"
    write(ply, sphere(200))
    (tmp_path / "file").write_text("x")
    out = tmp_path / "file" / "img.png"
    assert main(["-q", "render", str(ply), "-o", str(out), "--size", "16x16"]) == 2
    err = capsys.readouterr().err.strip()
    # (the CLI's own check may already refuse the parent directory: then it names that)
    assert err.count("\n") == 0 and str(out.parent) in err and err.startswith("splatedit: error:"), err
