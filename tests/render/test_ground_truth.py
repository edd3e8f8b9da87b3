"""Rendered splat surfaces against analytic ground truth (sphere, plane)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

from splatedit.render.camera import Camera
from tests.render.scenes import plane, sphere

W = H = 256
RHO = 1.0


def eye_rays(cam: Camera, w: int, h: int):
    near, far = 0.1, 100.0
    p = cam.projection_matrix(w / h, near, far)
    x = (np.arange(w) + 0.5) * 2.0 / w - 1.0
    y = (np.arange(h) + 0.5) * 2.0 / h - 1.0
    X, Y = np.meshgrid(x, y)
    return np.stack([X / p[0, 0], Y / p[1, 1], -np.ones_like(X)], axis=-1)   # (h, w, 3), d.z = -1


def analytic_sphere(cam, center=(0.0, 0.0, 0.0), rho=RHO):
    d = eye_rays(cam, W, H)
    c = (cam.view_matrix() @ np.r_[center, 1.0])[:3]
    a = np.einsum("hwi,hwi->hw", d, d)
    b = d @ c
    disc = b * b - a * (c @ c - rho * rho)
    hit = disc > 0
    t = (b - np.sqrt(np.where(hit, disc, 0.0))) / a          # depth along the view axis
    nrm = (t[..., None] * d - c) / rho
    return hit, np.where(hit, t, np.nan), nrm


@pytest.fixture(scope="module")
def sphere_buffers(renderer):
    cloud = sphere(20000, overlap=1.0)
    cam = Camera(eye=(0.3, 0.5, 4.2), target=(0, 0, 0), fov_deg=32.0)
    renderer.set_cloud(cloud)
    bufs = renderer.render_buffers(cam, W, H)
    return cam, bufs


def test_sphere_silhouette_iou(sphere_buffers):
    cam, bufs = sphere_buffers
    hit, _, _ = analytic_sphere(cam)
    fg = bufs["weight"] > 0
    iou = (fg & hit).sum() / (fg | hit).sum()
    assert hit.sum() > 0.4 * W * H * 0.5
    assert iou >= 0.98, f"IoU {iou:.4f}"


def test_sphere_hole_free(sphere_buffers):
    cam, bufs = sphere_buffers
    hit, _, _ = analytic_sphere(cam)
    inner = ndimage.binary_erosion(hit, iterations=2)
    holes = inner & ~(bufs["weight"] > 0)
    assert holes.sum() == 0, f"{holes.sum()} background pixels inside the silhouette"


def test_sphere_normals(sphere_buffers):
    cam, bufs = sphere_buffers
    hit, _, nrm = analytic_sphere(cam)
    both = hit & (bufs["weight"] > 0)
    cosang = np.clip(np.einsum("hwi,hwi->hw", bufs["normal"], nrm)[both], -1, 1)
    ang = np.degrees(np.arccos(cosang))
    assert np.median(ang) < 2.0, f"median normal error {np.median(ang):.3f} deg"
    inner = ndimage.binary_erosion(hit, iterations=4) & both
    cos_in = np.clip(np.einsum("hwi,hwi->hw", bufs["normal"], nrm)[inner], -1, 1)
    assert np.percentile(np.degrees(np.arccos(cos_in)), 95) < 6.0


def test_sphere_depth(sphere_buffers):
    cam, bufs = sphere_buffers
    hit, t, _ = analytic_sphere(cam)
    inner = ndimage.binary_erosion(hit, iterations=4) & (bufs["weight"] > 0)
    err = np.abs(bufs["depth"][inner] - t[inner])
    assert np.median(err) < 2e-3 * RHO, f"median depth error {np.median(err):.2e}"
    assert np.percentile(err, 99) < 2e-2 * RHO, f"99th percentile depth error {np.percentile(err, 99):.2e}"
    assert np.isnan(bufs["depth"][~(bufs["weight"] > 0)]).all()


def test_grazing_plane_hole_free(renderer):
    size = 2.0
    cloud = plane(80, size=size, overlap=1.0)
    elev = np.radians(6.0)
    cam = Camera(eye=(0.0, -3.0 * np.cos(elev), 3.0 * np.sin(elev)), target=(0, 0.3, 0), up=(0, 0, 1),
                 fov_deg=40.0)
    renderer.set_cloud(cloud)
    bufs = renderer.render_buffers(cam, W, H)
    # analytic coverage: ray-plane (z = 0) intersection inside the square, shrunk by one spacing
    d_eye = eye_rays(cam, W, H)
    view = cam.view_matrix()
    d = d_eye @ view[:3, :3]                       # eye -> world directions (rows of R^T)
    e = cam.eye
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -e[2] / d[..., 2]
    pts = e + t[..., None] * d
    lim = size / 2 - size / 80
    inside = (t > 0) & (np.abs(pts[..., 0]) < lim) & (np.abs(pts[..., 1]) < lim)
    inside = ndimage.binary_erosion(inside, iterations=1)
    assert inside.sum() > 2000
    holes = inside & ~(bufs["weight"] > 0)
    assert holes.sum() == 0, f"{holes.sum()} holes in the grazing plane"
    # back-face culling off must give the same coverage from below? (two-sided splats)


def test_million_splat_sphere_hole_free_1280x720(renderer):
    """1M splats at 1280x720: nearly all are drawn as square points (footprint
    within RENDER_POINT_SPLAT_MAX_PX of the centre); the silhouette has no
    holes and the coverage equals that of the all-quads path."""
    n = 1_000_000
    cloud = sphere(n, overlap=1.0)
    w, h = 1280, 720
    cam = Camera.frame(*cloud.bounds(), aspect=w / h, direction=(0.3, 0.4, 1.0))
    renderer.set_cloud(cloud)
    bufs = renderer.render_buffers(cam, w, h)
    draws = renderer.prepass_part.current.draws.read().view(np.uint32)
    assert draws[5] > 0.9 * (draws[1] + draws[5]), draws          # the point path is exercised
    saved = renderer.point_splats
    try:
        renderer.point_splats = False
        quads = renderer.render_buffers(cam, w, h)
    finally:
        renderer.point_splats = saved
    # analytic silhouette of the unit sphere
    p = cam.projection_matrix(w / h, 0.1, 100.0)
    X, Y = np.meshgrid(((np.arange(w) + 0.5) * 2.0 / w - 1.0) / p[0, 0], ((np.arange(h) + 0.5) * 2.0 / h - 1.0) / p[1, 1])
    d = np.stack([X, Y, -np.ones_like(X)], axis=-1)
    c = (cam.view_matrix() @ np.r_[0.0, 0.0, 0.0, 1.0])[:3]
    a = np.einsum("hwi,hwi->hw", d, d)
    b = d @ c
    hit = b * b - a * (c @ c - 1.0) > 0
    inner = ndimage.binary_erosion(hit, iterations=2)
    fg = bufs["weight"] > 0
    assert inner.sum() > 0.1 * w * h
    assert (inner & ~fg).sum() == 0, f"{(inner & ~fg).sum()} holes inside the silhouette"
    assert (fg != (quads["weight"] > 0)).sum() <= 0.0005 * fg.sum()
    both = fg & (quads["weight"] > 0)
    np.testing.assert_allclose(bufs["weight"][both], quads["weight"][both], rtol=2e-2, atol=1e-2)
