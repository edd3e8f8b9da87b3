"""The Gaussian level of detail in the editor's viewport: moving frames draw a
budgeted prefix of the importance ranking (GaussianRenderer.set_draw_count)
with coverage compensation, close to the full frame; the live deformation
moves the LOD's Gaussians exactly as the full set's (the CPU-deformed scene's
same Gaussians drawn undeformed give the same image); still frames draw all."""

import numpy as np
import pytest

from splatedit.bench.editor import support_and_handle
from splatedit.app.view.camera_control import OrbitCamera
from splatedit.app.document.gaussian import gaussian_document
from splatedit.app.view.viewport import render_camera
from splatedit.data import gaussian_scene_path
from splatedit.io import read_gaussians
from splatedit.model.gaussian_lod import build_gaussian_lod, subset
from splatedit.tolerances import GS_LOD_TEST_MEAN_DIFF, GS_REF_MEAN_TOL

pytestmark = pytest.mark.gpu

W, H = 240, 180


def _camera(doc):
    cam = OrbitCamera(scene_radius=doc.diagonal / 2, yaw=0.4, pitch=0.25)
    lo, hi = doc.bounds()
    cam.frame((lo + hi) / 2, doc.diagonal / 2, W / H)
    return cam


def _mean_diff(a, b):
    return float(np.abs(a[..., :3].astype(int) - b[..., :3]).max(axis=2).mean())


def _sphere_scene(n):
    from splatedit.bench.gs_scenes import gaussians_from_splats
    from splatedit.bench.render import sphere_cloud
    return gaussians_from_splats(sphere_cloud(n, overlap=1.0), seed=0)


@pytest.mark.parametrize("which, share", [("bunny", 0.25), ("sphere100k", 0.1)])
def test_lod_prefix_is_the_subset_and_close_to_the_full_frame(which, share):
    from splatedit.render.gaussian.renderer import GaussianRenderer
    scene = read_gaussians(str(gaussian_scene_path())) if which == "bunny" else _sphere_scene(100_000)
    lod = build_gaussian_lod(scene)
    c = int(share * len(scene))
    cam = render_camera(_camera(gaussian_document(scene)))
    with GaussianRenderer() as r:
        r.set_gaussians(scene)
        full = r.render(cam, W, H)
        with GaussianRenderer(device=r.dev) as q:
            q.set_gaussians(lod.cloud(scene))
            q.set_draw_count(c)
            prefix = q.render(cam, W, H)
            q.splat_scale = lod.compensation(c)
            compensated = q.render(cam, W, H)
            q.set_gaussians(subset(scene, lod.order[:c]))
            q.splat_scale = 1.0
            alone = q.render(cam, W, H)
    # drawing a prefix = uploading only it (up to float32 rounding: each upload is
    # relative to its own box centre and the near/far planes follow its bounds)
    same = np.abs(prefix.astype(int) - alone)[..., :3]
    assert same.mean() < 0.1 * GS_REF_MEAN_TOL and (same.max(axis=2) > 8).mean() < 1e-3, same.max()
    d_plain, d_comp = _mean_diff(prefix, full), _mean_diff(compensated, full)
    assert d_comp < GS_LOD_TEST_MEAN_DIFF, (d_plain, d_comp)
    assert d_comp < d_plain                        # the compensation makes up for the dropped ones
    print(which, share, c, "mean diff plain", round(d_plain, 2), "compensated", round(d_comp, 2))


def test_viewport_draws_the_deformed_lod_while_moving_and_all_when_still():
    from splatedit.app.view.viewport import Viewport
    from splatedit.deform.basis import DeformationBasis
    from splatedit.deform.gaussians import deform_with_evaluator
    from splatedit.render.gaussian.renderer import GaussianRenderer
    scene = read_gaussians(str(gaussian_scene_path()))
    doc = gaussian_document(scene)
    cam = _camera(doc)
    vp = Viewport(budget_ms=1.0)            # any real frame is over budget: moving frames use the LOD
    try:
        vp.set_cloud(doc)
        still = vp.render(cam, W, H, interactive=True)
        assert not vp.last_info.lod and vp.last_info.splats == len(scene)     # no ranking yet: all
        lod = build_gaussian_lod(scene)
        vp.set_gaussian_lod(lod)
        sup, hnd = support_and_handle(doc, 1500)
        basis = DeformationBasis.fit(doc, sup, [hnd])
        vp.set_basis(basis)
        m = np.eye(4)
        m[:3, 3] = np.array([0.0, 0.12, 0.05]) * doc.diagonal
        dc = basis.displacement([m])
        vp.set_dc(dc)
        for _ in range(2):                  # the first LOD frame uploads (not measured)
            live = vp.render(cam, W, H, interactive=True)
        info = vp.last_info
        assert info.lod and info.gaussians and info.interactive and info.splats < len(scene)
        assert np.abs(live.astype(int) - still)[..., :3].max(axis=2).__gt__(16).mean() > 0.01   # it moved
        # the same Gaussians deformed on the CPU (the commit's path), drawn undeformed
        moved = deform_with_evaluator(scene, basis, dc)
        rw, rh = W // info.div, H // info.div
        with GaussianRenderer(device=vp.full.r.dev) as r:
            r.set_gaussians(lod.cloud(moved))
            r.set_draw_count(info.splats)
            r.splat_scale = lod.compensation(info.splats)
            want = r.render(render_camera(cam), rw, rh)
        want = np.repeat(np.repeat(want, info.div, axis=0), info.div, axis=1)[:H, :W]
        diff = np.abs(live[:want.shape[0], :want.shape[1]].astype(int) - want)[..., :3]
        assert diff.mean() < GS_REF_MEAN_TOL, diff.mean()
        full = vp.render(cam, W, H)              # still: every Gaussian
        assert not vp.last_info.lod and vp.last_info.splats == len(scene)
        assert _mean_diff(full, live) < GS_LOD_TEST_MEAN_DIFF + 6    # the same edit, at full detail
    finally:
        vp.close()


def test_gpu_sort_of_a_prefix_sorts_only_the_prefix_and_draws_the_same():
    """With the GPU's bitonic sort, a drawn prefix of 1,000 Gaussians out of
    the bunny's 5,000 is sorted at the prefix's power of two (1,024 keys, not
    8,192) and draws what the CPU sort draws."""
    from splatedit.render.gaussian.renderer import GaussianRenderer
    scene = read_gaussians(str(gaussian_scene_path()))
    cam = render_camera(_camera(gaussian_document(scene)))
    images = {}
    with GaussianRenderer(sort="cpu") as cpu:
        cpu.set_gaussians(scene)
        cpu.set_draw_count(1000)
        images["cpu"] = cpu.render(cam, W, H)
        with GaussianRenderer(sort="bitonic", device=cpu.dev) as gpu:
            gpu.set_gaussians(scene)
            gpu.set_draw_count(1000)
            assert gpu._sort_length() == 1024
            images["gpu"] = gpu.render(cam, W, H)
    diff = np.abs(images["cpu"].astype(int) - images["gpu"])[..., :3]
    assert diff.mean() < 0.1 * GS_REF_MEAN_TOL, diff.mean()
