"""Viewport (renderer + levels of detail) on lavapipe, headless."""

import numpy as np
import pytest

from splatedit.app.view.camera_control import OrbitCamera
from splatedit.bench.editor import bunny_surface_cloud, support_and_handle
from splatedit.model.lod import LodPyramid

pytestmark = pytest.mark.gpu


@pytest.fixture(scope="module")
def scene():
    from splatedit.app.view.viewport import Viewport
    cloud = bunny_surface_cloud(30000)
    vp = Viewport(budget_ms=100.0)
    vp.set_cloud(cloud)
    vp.set_pyramid(LodPyramid(cloud, budgets=(8000, 2000)))
    cam = OrbitCamera(scene_radius=cloud.diagonal / 2)
    lo, hi = cloud.bounds()
    cam.frame((lo + hi) / 2, cloud.diagonal / 2, 160 / 120)
    yield vp, cloud, cam
    vp.close()


def test_idle_full_quality_and_interactive_lod(scene):
    vp, cloud, cam = scene
    img = vp.render(cam, 160, 120)
    assert img.shape == (120, 160, 4) and vp.last_info.splats == cloud.n and not vp.last_info.lod
    fg = img[..., :3].min(axis=2) < 240
    assert fg.mean() > 0.1
    # pretend the device is slow: the interactive frame falls back to a level
    vp.assume_cost(100.0 / 5000, 160 * 120)
    img2 = vp.render(cam, 160, 120, interactive=True)
    info = vp.last_info
    assert info.lod and info.splats <= 5000
    assert img2.shape == img.shape
    fg2 = img2[..., :3].min(axis=2) < 240
    # the level covers (about) the same pixels: hole-free, slightly fatter
    assert (fg & ~fg2).mean() < 0.01
    vp.assume_cost(100.0 / 500, 160 * 120)    # even the coarsest level is too slow: lower resolution
    vp.render(cam, 160, 120, interactive=True)
    assert vp.last_info.div > 1 and vp.last_info.lod
    vp.assume_cost(None, 1)


def test_handle_moves_in_lod_and_full(scene):
    from splatedit.deform.basis import DeformationBasis
    vp, cloud, cam = scene
    sup, hnd = support_and_handle(cloud, 3000)
    vp.set_selection(sup, hnd, 1)
    basis = DeformationBasis.fit(cloud, sup, [hnd])
    vp.set_basis(basis)
    m = np.eye(4)
    m[:3, 3] = [0.0, 0.15, 0.0]
    before = vp.render(cam, 160, 120)
    vp.set_dc(basis.displacement([m]))
    after = vp.render(cam, 160, 120)
    assert np.abs(after.astype(int) - before).sum() > 1000
    vp.assume_cost(100.0 / 5000, 160 * 120)
    lod_img = vp.render(cam, 160, 120, interactive=True)
    assert vp.last_info.lod
    # the deformed level looks like the deformed full cloud
    fa = after[..., :3].min(axis=2) < 240
    fl = lod_img[..., :3].min(axis=2) < 240
    assert (fa != fl).mean() < 0.05
    vp.assume_cost(None, 1)
    vp.set_dc(None)
    vp.set_basis(None)
    vp.set_selection(None, None, 2)


def test_detail_mode_draws_the_cpu_commit_in_full_and_lod(scene):
    """A DetailBasis in the viewport (basis rows at the base points plus the
    (n_b, lambda) rows; a level takes its representatives' rows) draws what
    the CPU commit gives: the same foreground as the committed cloud drawn
    without a basis."""
    from splatedit.app.view.viewport import Viewport
    from splatedit.deform import transform as tf
    from splatedit.deform.detail import DetailBasis
    vp, cloud, cam = scene
    sup, hnd = support_and_handle(cloud, 3000)
    basis = DetailBasis.fit(cloud, sup, [hnd])
    c = cloud.positions[hnd].mean(axis=0)
    dc = basis.displacement([tf.rotate((0.0, 0.0, 1.0), 60.0, c)])
    vp.set_basis(basis)
    vp.set_dc(dc)
    full = vp.render(cam, 160, 120)
    vp.assume_cost(100.0 / 5000, 160 * 120)
    level, div = vp.choose(True, 160, 120)
    lod = vp.render(cam, 160, 120, interactive=True)
    assert vp.last_info.lod and level is not None and div == 1
    vp.assume_cost(None, 1)
    vp.set_dc(None)
    vp.set_basis(None)
    new = basis.commit(cloud, dc)
    ref_vp = Viewport()
    try:
        ref_vp.set_cloud(new)
        ref = ref_vp.render(cam, 160, 120)
        ref_vp.set_cloud(level.deformed(new.positions, new.u, new.v))   # the level of the commit
        ref_lod = ref_vp.render(cam, 160, 120)
    finally:
        ref_vp.close()
    before = vp.render(cam, 160, 120)
    diff = lambda a, b: np.abs(a[..., :3].astype(int) - b[..., :3]).max(axis=2).mean()  # noqa: E731
    moved = diff(before, ref)
    assert moved > 0.5                   # the edit changes the picture (measured 0.8 levels/pixel)
    assert diff(full, ref) < 0.05 * moved    # measured 0.007
    assert diff(lod, ref_lod) < 0.05 * moved


def test_pick_matches_projection(scene):
    vp, cloud, cam = scene
    idx, depth = vp.pick(cam, 160, 120)
    ys, xs = np.nonzero(idx >= 0)
    assert len(xs) > 1000
    px, d = cam.project(cloud.positions[idx[ys, xs]], 160, 120)
    err = np.hypot(px[:, 0] - xs - 0.5, px[:, 1] - ys - 0.5)
    assert np.median(err) < 3.0


@pytest.mark.parametrize("n", [30000, 400000])
def test_brush_paints_only_visible_splats_as_a_solid_patch(n):
    """The brush on the real pick pass: a disc on the bunny selects the front
    surface under it (no back-facing or hidden splats) without holes, also
    when splats are much smaller than a pixel."""
    from splatedit.app.tools.pick_brush import picker_for_view
    from splatedit.app.view.viewport import Viewport
    cloud = bunny_surface_cloud(n, seed=3)
    w, h = 320, 240
    cam = OrbitCamera(scene_radius=cloud.diagonal / 2)
    lo, hi = cloud.bounds()
    cam.frame((lo + hi) / 2, cloud.diagonal / 2, w / h)
    vp = Viewport()
    try:
        vp.set_cloud(cloud)
        idx, front = vp.pick(cam, w, h)
    finally:
        vp.close()
    picker = picker_for_view(idx, front, cam, cloud.positions, cloud.radii)
    ys, xs = np.nonzero(idx >= 0)
    cx, cy = float(np.median(xs)), float(np.median(ys))
    sel = picker.query(cx, cy, 15)
    assert len(sel) > 0
    # visible side only: every selected splat faces the camera and sits near the front surface
    nrm = cloud.normals[sel]
    to_eye = cam.eye - cloud.positions[sel]
    assert (np.einsum("ij,ij->i", nrm, to_eye) > 0).mean() > 0.97
    px, depth = cam.project(cloud.positions[sel], w, h)
    assert depth.max() - depth.min() < 0.15 * cloud.diagonal
    # solid: nearly every front-facing splat whose centre falls well inside the disc is selected
    allpx, alld = cam.project(cloud.positions, w, h)
    inner = np.hypot(allpx[:, 0] - cx, allpx[:, 1] - cy) < 10
    inner &= alld < depth.max()
    inner &= np.einsum("ij,ij->i", cloud.normals, cam.eye - cloud.positions) > 0
    got = np.isin(np.flatnonzero(inner), sel).mean()
    assert got > 0.95, got
