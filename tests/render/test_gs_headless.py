"""One Gaussian splat proxy (GaussianCloud.proxy_splats, model layer): the
render layer's ``splat_proxy`` is that proxy, and on the bundled
bunny_gaussians.ply it keeps what the render layer's own proxy gave before
(``_legacy_splat_proxy``, its previous code, kept as the reference): the same
centres and axis directions (the axes now at GAUSSIAN_PROXY_SIGMAS standard
deviations instead of one), the same fitted edit, and the same ``splatedit
render --edit`` image of the scene."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

import splatedit.cli as cli
from splatedit.data import default_model_path
from splatedit.io import read_gaussians
from splatedit.model.cloud import SplatCloud
from splatedit.model.gaussians import GaussianCloud
from splatedit.render.gaussian import headless as gs_headless
from splatedit.script import fit_edit, load_script
from splatedit.tolerances import GAUSSIAN_PROXY_SIGMAS

SCENE = default_model_path().with_name("bunny_gaussians.ply")
EDIT = {"version": 1, "edits": [
    {"support": {"sphere": {"center": [0.0, 0.2, 0.0], "radius": 0.35}},
     "handle": {"sphere": {"center": [0.0, 0.35, 0.0], "radius": 0.12}},
     "deformation": "linear", "transform": {"translate": [0.15, 0.1, 0.0]}}]}


def _legacy_splat_proxy(cloud) -> SplatCloud:
    r = cloud.rotation_matrices()
    s = cloud.scales()
    order = np.argsort(-s, axis=1)
    rows = np.arange(len(cloud))
    a0, a1 = order[:, 0], order[:, 1]
    u = r[rows, :, a0] * s[rows, a0][:, None]
    v = r[rows, :, a1] * s[rows, a1][:, None]
    return SplatCloud(cloud.positions.copy(), u, v, None, name=cloud.name, source=cloud.source)


@pytest.fixture(scope="module")
def scene():
    return read_gaussians(SCENE)


@pytest.fixture
def edit_script(tmp_path):
    path = tmp_path / "edit.json"
    path.write_text(json.dumps(EDIT))
    return path


def test_splat_proxy_is_the_model_proxy(scene):
    a, b = gs_headless.splat_proxy(scene), scene.proxy_splats()
    for name in ("positions", "u", "v", "colors"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name


def test_the_proxy_keeps_the_old_centres_and_axes_at_the_proxy_sigmas(scene):
    old, new = _legacy_splat_proxy(scene), scene.proxy_splats()
    assert new.n == old.n == len(scene) == 5000
    assert np.array_equal(new.positions, old.positions)
    # the same axes (largest, second largest) in the same directions, GAUSSIAN_PROXY_SIGMAS times as long
    assert np.array_equal(new.u, old.u * GAUSSIAN_PROXY_SIGMAS)
    assert np.array_equal(new.v, old.v * GAUSSIAN_PROXY_SIGMAS)
    assert np.array_equal(new.colors[:, :3], np.round(scene.dc_colors() * 255.0).astype(np.uint8))


def test_an_edit_fitted_on_the_proxy_is_unchanged(scene, edit_script):
    script = load_script(edit_script)
    fits = [fit_edit(c, script.edits[0], script.solver, source=str(edit_script))
            for c in (_legacy_splat_proxy(scene), scene.proxy_splats())]
    (_, old_basis, old_dc), (_, new_basis, new_dc) = fits
    assert len(old_basis.indices) > 100
    assert np.array_equal(old_dc, new_dc)
    for o, n in zip(old_basis.rows_for_gpu(), new_basis.rows_for_gpu()):
        assert np.array_equal(o, n)


@pytest.mark.gpu
def test_render_with_an_edit_draws_the_same_image(edit_script, tmp_path, monkeypatch, capsys):
    """``splatedit render`` of the Gaussian scene with a GPU edit: the image
    with the model proxy equals the one with the old proxy, pixel for pixel."""
    args = ["-q", "render", str(SCENE), "--size", "96x96", "--edit", str(edit_script)]
    new, old = tmp_path / "new.png", tmp_path / "old.png"
    assert cli.main(args + ["-o", str(new)]) == 0
    monkeypatch.setattr(GaussianCloud, "proxy_splats", _legacy_splat_proxy)
    assert cli.main(args + ["-o", str(old)]) == 0
    assert capsys.readouterr().out.count("deformed on the GPU") == 2
    a, b = (np.asarray(Image.open(p)) for p in (new, old))
    assert (np.abs(a.astype(int) - 255)[..., :3].max(axis=2) > 8).mean() > 0.1     # the bunny is drawn
    assert np.array_equal(a, b)
