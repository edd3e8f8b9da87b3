"""The compute tile rasterizer of the Gaussian renderer (splatedit.render.gaussian.tiles)
draws the quad raster path's image within GS_TILE_MEAN_TOL / GS_TILE_MAX_TOL
(the bundled bunny scene and random anisotropic Gaussians, several views, an
image size that is not a multiple of the tile, both accumulator formats, a
GPU deformation); it grows its pair buffers when a frame wants more and then
draws the same; the automatic path and sort follow the documented rule; the
renderer frees every Vulkan object it made on the compute path."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.data import gaussian_scene_path
from splatedit.errors import ParameterError
from splatedit.io import read_gaussians
from splatedit.model.gaussians import GaussianCloud
from splatedit.render import vk as V
from splatedit.render.camera import Camera
from splatedit.render.gaussian.renderer import (CPU_DEVICE_PATH, CPU_DEVICE_SORT, GaussianRenderer, choose_path,
                                        choose_sort, gaussian_bounds)
from splatedit.tolerances import GS_TILE_MAX_TOL, GS_TILE_MEAN_TOL

VIEWS = ((0.0, 0.0, 1.0), (1.0, 0.3, 0.2), (-0.6, -0.4, -0.7))


@pytest.fixture(scope="module")
def dev():
    d = V.Device()
    yield d
    d.close()


@pytest.fixture(scope="module")
def bunny() -> GaussianCloud:
    return read_gaussians(str(gaussian_scene_path()))


def random_scene(n=1500, seed=3) -> GaussianCloud:
    rng = np.random.default_rng(seed)
    return GaussianCloud(positions=rng.uniform(-1, 1, (n, 3)),
                         log_scales=np.log(rng.uniform(0.01, 0.25, (n, 3))).astype(np.float32),
                         rotations=rng.normal(size=(n, 4)).astype(np.float32),
                         opacity_logits=rng.normal(0, 2, n).astype(np.float32),
                         sh=(rng.normal(size=(n, 16, 3)) * 0.3).astype(np.float32))


def camera(cloud, direction, w, h) -> Camera:
    lo, hi = gaussian_bounds(cloud)
    return Camera.frame(lo, hi, aspect=w / h, direction=direction)


def render(dev, cloud, cam, w, h, *, path, fmt="rgba16f", sort="auto", setup=None):
    with GaussianRenderer(path=path, sort=sort, accum_format=fmt, device=dev) as r:
        r.set_gaussians(cloud)
        if setup is not None:
            setup(r)
        img = r.render(cam, w, h)
        assert r.last_timings_ms["visible"] > 0
        return img


def assert_paths_agree(raster, compute, fmt):
    diff = np.abs(raster.astype(np.int16) - compute.astype(np.int16))[..., :3]
    assert diff.mean() <= GS_TILE_MEAN_TOL[fmt] and diff.max() <= GS_TILE_MAX_TOL[fmt], \
        (fmt, float(diff.mean()), int(diff.max()))
    assert (compute[..., :3] != compute[0, 0, :3]).any(axis=2).mean() > 0.05     # not a blank image


@pytest.mark.parametrize("fmt", ["rgba16f", "rgba32f"])
@pytest.mark.parametrize("scene", ["bunny", "random"])
def test_compute_path_draws_the_quad_path_image(dev, bunny, scene, fmt):
    cloud = bunny if scene == "bunny" else random_scene()
    for direction, (w, h) in zip(VIEWS, ((96, 72), (257, 131), (80, 80))):
        cam = camera(cloud, direction, w, h)
        assert_paths_agree(render(dev, cloud, cam, w, h, path="raster", fmt=fmt),
                           render(dev, cloud, cam, w, h, path="compute", fmt=fmt), fmt)


def test_compute_path_with_the_gpu_sort_and_a_deformation_draws_the_quad_path_image(dev, bunny):
    n = len(bunny)
    p = (bunny.positions - bunny.positions.mean(0)) / np.ptp(bunny.positions, axis=0).max()
    B = np.column_stack([np.ones(n), p])                         # affine basis 1, x, y, z
    Bx, By, Bz = (np.zeros((n, 4)) for _ in range(3))
    Bx[:, 1] = By[:, 2] = Bz[:, 3] = 1.0
    dC = np.array([[0.02, 0.0, 0.01], [0.1, 0.05, 0.0], [0.0, -0.1, 0.05], [0.05, 0.0, 0.1]])
    scale = float(np.ptp(bunny.positions, axis=0).max())

    def deform(r):
        r.set_basis(np.arange(n), B, Bx / scale, By / scale, Bz / scale)
        r.set_displacement(dC * scale)
    cam = camera(bunny, VIEWS[1], 96, 72)
    raster = render(dev, bunny, cam, 96, 72, path="raster", sort="cpu", setup=deform)
    undeformed = render(dev, bunny, cam, 96, 72, path="raster", sort="cpu")
    assert np.abs(raster.astype(int) - undeformed).mean() > 1.0            # the deformation shows
    assert_paths_agree(raster, render(dev, bunny, cam, 96, 72, path="compute", sort="gpu", setup=deform),
                       "rgba16f")


def test_compute_path_grows_its_pair_buffers_and_draws_the_same(dev, bunny):
    cam = camera(bunny, VIEWS[0], 120, 90)
    ref = render(dev, bunny, cam, 120, 90, path="compute")

    def tiny(r):
        r._tiles._alloc_pairs(500)
    with GaussianRenderer(path="compute", device=dev) as r:
        r.set_gaussians(bunny)
        tiny(r)
        assert r._tiles.capacity == 500
        img = r.render(cam, 120, 90)
        assert r._tiles.pairs_wanted() > 500
        assert r._tiles.capacity >= r._tiles.pairs_wanted()
    np.testing.assert_array_equal(img, ref)


def test_automatic_path_and_sort_follow_the_documented_rule(dev):
    cpu = V.is_cpu_device(dev)
    assert choose_path(dev) == (CPU_DEVICE_PATH if cpu else "compute")
    assert choose_sort(dev) == (CPU_DEVICE_SORT if cpu else "gpu")
    with GaussianRenderer(device=dev) as r:
        assert (r.path, r.sort) == (choose_path(dev), choose_sort(dev))
    with pytest.raises(ParameterError):
        GaussianRenderer(path="tiles", device=dev)


def test_compute_path_frees_every_vulkan_object(bunny):
    before = V.live_handles()
    r = GaussianRenderer(path="compute", sort="gpu")
    r.set_gaussians(bunny)
    cam = camera(bunny, VIEWS[0], 64, 48)
    r.render(cam, 64, 48)
    r.render(cam, 40, 30)                 # a second size: its ranges and set replace the first's
    r.pick(cam, 40, 30)
    r.set_gaussians(bunny)                # a new scene: new scratch
    r.render(cam, 40, 30)
    r.close()
    assert V.live_handles() == before


def test_compute_path_with_nothing_visible_draws_the_background(dev, bunny):
    """Every Gaussian culled: every indirect dispatch has zero workgroups and
    the image is the background, as on the quad path."""
    lo, hi = gaussian_bounds(bunny)
    c = 0.5 * (lo + hi)
    d = float(np.linalg.norm(hi - lo))
    away = Camera(c + (0.0, 0.0, 2.0 * d), c + (0.0, 0.0, 4.0 * d), up=(0.0, 1.0, 0.0), fov_deg=40.0)
    imgs = []
    for path, sort in (("raster", "cpu"), ("compute", "cpu"), ("compute", "gpu")):
        with GaussianRenderer(path=path, sort=sort, device=dev) as r:
            r.set_gaussians(bunny)
            imgs.append(r.render(away, 48, 32))
            assert r.last_timings_ms["visible"] == 0
    assert (imgs[0] == imgs[0][0, 0]).all()
    for img in imgs[1:]:
        np.testing.assert_array_equal(img, imgs[0])
