"""`splatedit render`'s level of detail for one view: where many splats fall
in one pixel, splats thinned at random and enlarged to about a pixel draw
nearly the same image as every splat, with no pinholes."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from splatedit.cli import main
from splatedit.io import write
from splatedit.model.cloud import SplatCloud
from splatedit.model.tangents import splats_from_normals
from splatedit.render.camera import Camera
from splatedit.render.splat.headless import keep_for_pixels, pixel_level
from splatedit.tolerances import RENDER_LOD_MIN_RADIUS_PX, SPLAT_RADIUS_FACTOR


def random_sphere(n: int, seed: int = 0) -> SplatCloud:
    """``n`` uniformly random points of the unit sphere, splats of 1.5x the
    spacing of a hexagonal sampling of the same area (the file's radius
    rule of data_tools/make_large_model.py --normals-radius)."""
    rng = np.random.default_rng(seed)
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    r = SPLAT_RADIUS_FACTOR * np.sqrt(2 * 4 * np.pi / (np.sqrt(3) * n))
    return splats_from_normals(p, p, np.full(n, r))


CAMERA = Camera((0.3, 0.4, 3.2), (0.0, 0.0, 0.0))
W, H = 128, 72


def _pinholes(img) -> int:
    """Background pixels enclosed by the drawn surface."""
    obj = np.abs(img[..., :3].astype(int) - img[0, 0, :3].astype(int)).max(axis=2) > 3
    return int((ndimage.binary_fill_holes(obj) & ~obj).sum())


def test_keep_probability_is_the_squared_radius_in_pixels():
    """A splat ``RENDER_LOD_MIN_RADIUS_PX`` wide on screen keeps 1, one half
    as wide 1/4; one behind the eye keeps 1."""
    f = H / (2 * np.tan(np.radians(CAMERA.fov_deg) / 2))
    z = np.linalg.norm(CAMERA.eye)
    r_one = RENDER_LOD_MIN_RADIUS_PX * z / f
    pts = np.array([[0, 0, 0], [0, 0, 0], 2 * CAMERA.eye])
    c = splats_from_normals(pts, np.tile([0.0, 0.0, 1.0], (3, 1)), np.array([r_one, r_one / 2, 1e-3]))
    np.testing.assert_allclose(keep_for_pixels(c, CAMERA, H), [1.0, 0.25, 1.0], rtol=1e-9)


def test_pixel_level_draws_the_full_image_within_tolerance(renderer):
    """300k random sphere splats at 128x72 (about 90 a covered pixel): the
    level keeps 11.3 % of them; measured mean |difference| 0.55 RGB levels,
    0.52 % of the pixels more than 8 levels off (48, on the silhouette of a
    3,400-pixel disc), no pinhole (the full render has none either)."""
    c = random_sphere(300_000)
    renderer.set_cloud(c)
    full = renderer.render(CAMERA, W, H)
    lvl = pixel_level(c, CAMERA, H)
    assert lvl is not None and lvl.n < 0.15 * c.n
    renderer.set_cloud(lvl.cloud)
    img = renderer.render(CAMERA, W, H)
    d = np.abs(img[..., :3].astype(int) - full[..., :3].astype(int))
    assert d.mean() <= 0.8, f"mean |difference| {d.mean():.3f}"
    assert (d.max(axis=2) > 8).mean() <= 0.012
    assert _pinholes(full) == 0 and _pinholes(img) == 0


def test_no_level_where_splats_are_already_pixel_sized():
    """A 2k-splat sphere at 128x72: its splats are several pixels wide, so
    the full cloud is drawn."""
    assert pixel_level(random_sphere(2000), CAMERA, H) is None


def test_cli_render_draws_the_level_and_full_draws_every_splat(tmp_path, capsys):
    c = random_sphere(200_000, seed=1)
    ply = write(tmp_path / "s.ply", c)
    common = ["-q", "render", str(ply), "--size", "64x36", "--eye", "0.3,0.4,3.2", "--target", "0,0,0", "-f"]
    assert main(common + ["-o", str(tmp_path / "lod.png")]) == 0
    out = capsys.readouterr().out
    assert "200000 splats, drawn as a level of" in out
    assert main(common + ["-o", str(tmp_path / "full.png"), "--full"]) == 0
    out = capsys.readouterr().out
    assert "200000 splats)" in out and "level" not in out
