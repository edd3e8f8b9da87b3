"""Packing through the declared dtypes (splatedit.render.uniforms) writes the
same bytes as the hand-offset packing it replaced: the deformation block (with
rotating handles), the basis rows, the Gaussian geometry records of a bunny
scene, the Gaussian frame block of a rendered frame, the splat geometry upload
and the detail rows.  The ``_legacy_*`` functions (and the inline hand
offsets) are the previous packing code, kept here as the reference."""

from __future__ import annotations

import math

import numpy as np
import pytest

from splatedit.bench.gs_scenes import gaussians_from_splats
from splatedit.data import default_model_path
from splatedit.deform.rotation import HandleRotation, RotationDisplacement
from splatedit.io import read
from splatedit.render.camera import Camera
from splatedit.render.gaussian.renderer import GaussianRenderer, gaussian_bounds
from splatedit.render.gpu_units import gpu_camera, pack_basis_rows, pack_deform_block
from splatedit.render.gaussian.resources import pack_geometry
from splatedit.render.uniforms import BASIS_GROUP, DEFORM_UBO, GS_FRAME_UBO, GS_GEOM, MAX_GROUPS
from splatedit.tolerances import (GS_ALPHA_MAX, GS_ALPHA_MIN, GS_FRUSTUM_CLAMP, GS_LOWPASS_PX2, GS_NEAR_CULL_REL,
                                  GS_PICK_MIN_OPACITY, GS_PICK_SIGMAS, RENDER_TINT_HANDLE, RENDER_TINT_SUPPORT)


def _legacy_deform_block(dC, rot, scale):
    pad = np.zeros((4 * MAX_GROUPS, 3))
    pad[:len(dC)] = np.asarray(dC, np.float64) / scale
    blocks = np.zeros((MAX_GROUPS, 4, 4))
    if rot is not None:
        for g in rot.rotating:
            r = rot.rotations[g]
            blocks[g, 0, :3] = r.w / r.angle
            blocks[g, 0, 3] = r.angle
            blocks[g, 1:, :] = (r.offsets / scale).T
    block = np.concatenate([pad.reshape(MAX_GROUPS, 4, 3).transpose(0, 2, 1).reshape(-1), blocks.reshape(-1)])
    return np.ascontiguousarray(block, np.float32)


def _legacy_basis_rows(mats, scale):
    k = mats[0].shape[1]
    g = (k + 3) // 4
    n = len(mats[0])
    rows = np.zeros((max(n, 1), g, 4, 4), np.float32)
    for j, a in enumerate([mats[0]] + [m * scale for m in mats[1:]]):
        padded = np.zeros((n, 4 * g))
        padded[:, :k] = a
        rows[:n, :, j, :] = padded.reshape(n, g, 4)
    return rows


def test_basis_rows_bytes_equal_the_hand_packing():
    rng = np.random.default_rng(9)
    for n, k in ((300, 16), (50, 7), (0, 4)):
        mats = [rng.normal(size=(n, k)) for _ in range(4)]
        new, old = pack_basis_rows(mats, 8.0), _legacy_basis_rows(mats, 8.0)
        assert new.dtype == old.dtype and new.shape == old.shape and new.tobytes() == old.tobytes()
        assert new.shape[1:] == ((k + 3) // 4, 4, 4) and new.itemsize * 16 == BASIS_GROUP.itemsize


def _legacy_geometry(cloud, origin, scale):
    n = len(cloud)
    geom = np.zeros((n, 16), np.float32)
    geom[:, 0:3] = (cloud.positions - origin) / scale
    geom[:, 3] = cloud.opacities()
    c = cloud.covariances() / (scale * scale)
    geom[:, 4:10] = c[:, [0, 0, 0, 1, 1, 2], [0, 1, 2, 1, 2, 2]]
    geom[:, 10:13] = cloud.sh[:, 0, :]
    shortest = np.argmin(cloud.scales(), axis=1)
    geom[:, 13:16] = cloud.rotation_matrices()[np.arange(n), :, shortest]
    return geom


@pytest.fixture(scope="module")
def bunny_gaussians():
    cloud = read(default_model_path())
    sub = cloud.subset(np.random.default_rng(4).choice(cloud.n, 800, replace=False))
    return gaussians_from_splats(sub.replace(u=sub.u * 2.0, v=sub.v * 2.0), degree=3, seed=6)


def test_deform_block_bytes_equal_the_hand_packing_with_rotating_handles():
    rng = np.random.default_rng(7)
    rots = []
    for g in range(3):                                   # handle 1 does not rotate
        w = np.zeros(3) if g == 1 else rng.normal(size=3)
        rots.append(HandleRotation(w, rng.normal(size=3), rng.normal(size=(4, 3)) * 30.0))
    dC = rng.normal(size=(4 * MAX_GROUPS - 3, 3)) * 50.0
    rot = RotationDisplacement(dC, tuple(rots))
    for d, r in ((dC, rot), (dC[:5], None), (np.zeros((0, 3)), None)):
        new, old = pack_deform_block(d, r, 64.0), _legacy_deform_block(d, r, 64.0)
        assert new.dtype == old.dtype and new.shape == old.shape and new.tobytes() == old.tobytes()
        assert new.nbytes == DEFORM_UBO.itemsize
    assert np.count_nonzero(pack_deform_block(dC, rot, 64.0)[12 * MAX_GROUPS:]) == 2 * 16


def test_gaussian_geometry_bytes_equal_the_hand_packing(bunny_gaussians):
    lo, hi = gaussian_bounds(bunny_gaussians)
    origin = 0.5 * (lo + hi)
    geom, _ = pack_geometry(bunny_gaussians, origin, 0.125)
    old = _legacy_geometry(bunny_gaussians, origin, 0.125)
    assert geom.shape == old.shape == (len(bunny_gaussians), GS_GEOM.itemsize // 4)
    assert geom.tobytes() == old.tobytes()
    rec = geom.view(GS_GEOM)[:, 0]                     # the same buffer read by field name
    np.testing.assert_allclose(np.linalg.norm(rec["normal"], axis=1), 1.0, atol=1e-6)
    np.testing.assert_array_equal(rec["opacity"], old[:, 3])


def test_gaussian_frame_block_bytes_equal_the_hand_packing(bunny_gaussians):
    w, h = 80, 60
    lo, hi = gaussian_bounds(bunny_gaussians)
    cam = Camera.frame(lo, hi, w / h, direction=(0.3, 0.2, 1.0))
    with GaussianRenderer() as r:
        r.set_gaussians(bunny_gaussians)
        r.splat_scale, r.grey_shading = 1.5, True
        r.render(cam, w, h)
        got = r.ubo.read(GS_FRAME_UBO.itemsize)
        sc = r.scale
        near, far = (x / sc for x in r.near_far)
        gpu_cam = gpu_camera(cam, r.origin, sc)
        fpx = 0.5 * (1.0 / math.tan(math.radians(cam.fov_deg) / 2.0)) * h
        u = np.zeros(56, np.float32)                     # the previous hand offsets
        u[0:16] = gpu_cam.view_matrix().T.reshape(-1)
        u[16:20] = (fpx, fpx, 0.5 * w, 0.5 * h)
        u[20:24] = (w, h, near, far)
        u[24:28] = (*gpu_cam.eye, r.degree)
        u[28:32] = (GS_FRUSTUM_CLAMP * 0.5 * w / fpx, GS_FRUSTUM_CLAMP * 0.5 * h / fpx, GS_LOWPASS_PX2, GS_ALPHA_MIN)
        u[32:36] = (GS_ALPHA_MAX, GS_PICK_MIN_OPACITY, GS_PICK_SIGMAS ** 2, near * GS_NEAR_CULL_REL)
        u[36:40] = (*r.background, 1.0)
        u[40:44].view(np.uint32)[:] = (r.n, r._rest_uints, r._n2 if r.sort == "gpu" else r.n, 0)
        u[44:48] = RENDER_TINT_SUPPORT
        u[48:52] = RENDER_TINT_HANDLE
        u[52:56] = (1.5, 1.0, 0.0, 0.0)
    # near / far go through model units and back: exact, the scale is a power of two
    assert got.tobytes() == u.tobytes()
    assert got.view(np.uint32)[40] == len(bunny_gaussians)


def test_splat_geometry_and_detail_rows_bytes_equal_the_hand_packing(renderer, monkeypatch):
    from splatedit.render.splat import uploads
    from splatedit.render.uniforms import DETAIL_ROW, SPLAT_GEOM
    cloud = read(default_model_path())
    monkeypatch.setattr(uploads, "RENDER_UPLOAD_CHUNK_SPLATS", 3000)    # several chunks, a partial last one
    renderer.set_cloud(cloud)
    got = renderer.uploads.geom.read(cloud.n * SPLAT_GEOM.itemsize)
    inv = 1.0 / renderer.scale
    old = np.zeros((cloud.n, 9), np.float32)                             # the previous hand offsets
    np.multiply(cloud.positions - renderer.origin, inv, out=old[:, 0:3], casting="same_kind")
    np.multiply(cloud.u, inv, out=old[:, 3:6], casting="same_kind")
    np.multiply(cloud.v, inv, out=old[:, 6:9], casting="same_kind")
    assert cloud.n > 2 * 3000 and got.tobytes() == old.tobytes()

    rng = np.random.default_rng(8)
    idx = rng.choice(cloud.n, 500, replace=False)
    n_b = rng.normal(size=(500, 3))
    detail = np.column_stack([n_b / np.linalg.norm(n_b, axis=1, keepdims=True), rng.normal(size=500) * 1e-3])
    renderer.set_detail(idx, detail)
    got = renderer.uploads.detail_buf.read(cloud.n * DETAIL_ROW.itemsize)
    old = np.zeros((cloud.n, 4), np.float32)
    old[idx, :3] = detail[:, :3]
    old[idx, 3] = detail[:, 3] / renderer.scale
    assert got.tobytes() == old.tobytes() and np.count_nonzero(old[:, 3]) == 500
    renderer.clear_basis()
