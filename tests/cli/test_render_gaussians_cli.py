"""``splatedit render`` on a Gaussian Splatting scene (issue 13): the loader
hook hands a GaussianCloud to the Gaussian renderer; a one-edit script is
fitted on the splat proxy and applied on the GPU; unsupported flags are
one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

import splatedit.cli as cli
from splatedit.bench.gs_scenes import gaussians_from_splats
from splatedit.data import default_model_path
from splatedit.io import read


@pytest.fixture(scope="module")
def scene():
    cloud = read(default_model_path())
    sub = cloud.subset(np.random.default_rng(0).choice(cloud.n, 3000, replace=False))
    grow = np.sqrt(cloud.n / sub.n) * 0.8
    return gaussians_from_splats(sub.replace(u=sub.u * grow, v=sub.v * grow), seed=2)


@pytest.fixture
def gs_file(scene, tmp_path, monkeypatch):
    """A path whose 'reading' gives the Gaussian scene (until the 3DGS reader lands)."""
    path = tmp_path / "scene.ply"
    path.write_bytes(b"stand-in")
    from splatedit.commands import render
    real = render._read_model
    monkeypatch.setattr(render, "_read_model",
                        lambda p, progress: scene if str(p) == str(path) else real(p, progress))
    return path


def test_render_draws_the_gaussian_scene(gs_file, tmp_path, capsys):
    out = tmp_path / "gs.png"
    assert cli.main(["-q", "render", str(gs_file), "-o", str(out), "--size", "80x60"]) == 0
    assert "3000 Gaussians, SH degree 3" in capsys.readouterr().out
    img = np.asarray(Image.open(out))
    assert img.shape == (60, 80, 4)
    assert (np.abs(img[..., :3].astype(int) - 255).max(axis=2) > 8).mean() > 0.1


def test_render_applies_one_edit_on_the_gpu(gs_file, tmp_path, capsys):
    script = tmp_path / "edit.json"
    script.write_text(json.dumps({"version": 1, "edits": [
        {"support": {"sphere": {"center": [0.0, 0.2, 0.0], "radius": 0.35}},
         "handle": {"sphere": {"center": [0.0, 0.35, 0.0], "radius": 0.12}},
         "transform": {"translate": [0.15, 0.1, 0.0]}}]}))
    plain, edited = tmp_path / "a.png", tmp_path / "b.png"
    assert cli.main(["-q", "render", str(gs_file), "-o", str(plain), "--size", "80x60"]) == 0
    assert cli.main(["-q", "render", str(gs_file), "-o", str(edited), "--size", "80x60", "--edit", str(script)]) == 0
    assert "deformed on the GPU" in capsys.readouterr().out
    a, b = (np.asarray(Image.open(p)).astype(int) for p in (plain, edited))
    changed = (np.abs(a - b)[..., :3].max(axis=2) > 16).mean()
    assert 0.005 < changed < 0.5, changed



def test_render_of_a_rotating_edit_matches_deform_then_render(tmp_path, capsys):
    """A rotation (the default mode, which the Gaussian GPU pass does not draw) is applied on the
    CPU: the image equals rendering the output of `splatedit deform` (it used to be a traceback)."""
    from splatedit.data import default_model_path
    scene = default_model_path().with_name("bunny_gaussians.ply")
    script = tmp_path / "ears.json"
    script.write_text(json.dumps({"version": 1, "edits": [
        {"support": {"box": {"min": [-1, 0.1, -1], "max": [1, 1, 1]}},
         "handle": {"box": {"min": [-1, 0.38, -1], "max": [1, 1, 1]}},
         "transform": {"rotate": {"axis": [1, 0, 0], "degrees": 45}}}]}))
    plain, direct, via = (tmp_path / n for n in ("plain.png", "direct.png", "via.png"))
    deformed = tmp_path / "deformed.ply"
    cam = ["--size", "96x96", "--eye", "0,0.1,2.2", "--target", "0,0.1,0"]
    assert cli.main(["-q", "render", str(scene), "-o", str(plain), *cam]) == 0
    assert cli.main(["-q", "render", str(scene), "-o", str(direct), "--edit", str(script), *cam]) == 0
    out = capsys.readouterr().out
    # it says only what happens: nothing is uploaded to the GPU for this edit
    assert "deformed on the CPU" in out and "rotation edit is applied on the CPU" in out
    assert "GPU" not in out
    assert cli.main(["-q", "deform", str(scene), "--edit", str(script), "-o", str(deformed)]) == 0
    assert cli.main(["-q", "render", str(deformed), "-o", str(via), *cam]) == 0
    a, b, c = (np.asarray(Image.open(p)).astype(int) for p in (plain, direct, via))
    assert (np.abs(a - b)[..., :3].max(axis=2) > 16).mean() > 0.01     # the ears moved
    assert np.abs(b - c).max() <= 2                                      # as deform + render draws them


def test_buffers_flag_is_a_one_line_error(gs_file, tmp_path, capsys):
    code = cli.main(["-q", "render", str(gs_file), "-o", str(tmp_path / "x.png"), "--buffers", str(tmp_path / "b.npz")])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("splatedit: error: parameter '--buffers'") and err.count("\n") == 1
