"""Deforming Gaussian scenes: rigid motions through the bases equal the rigid
transform (with SH rotation), covariances follow J Sigma J^T through a save,
re-decomposition keeps axis order, 2DGS stays flat."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from splatedit.data import gaussian_scene_path
from splatedit.deform.basis import DeformationBasis
from splatedit.deform.gaussians import (deform_gaussians, deform_with_evaluator, polar_rotation,
                                        quaternions_from_matrices, transform_gaussians)
from splatedit.errors import InputError
from splatedit.io import read_gaussians, write_gaussians
from splatedit.model.gaussians import GaussianCloud, GaussianKind
from splatedit.model.spherical_harmonics import sh_colors
from splatedit.tolerances import GAUSSIAN_RIGID_ATTR_TOL, GAUSSIAN_SAVE_COV_REL_TOL


@pytest.fixture(scope="module")
def scene() -> GaussianCloud:
    return read_gaussians(gaussian_scene_path())


def _rigid(rotvec, t):
    a = np.eye(4)
    a[:3, :3] = Rotation.from_rotvec(rotvec).as_matrix()
    a[:3, 3] = t
    return a


def _quat_mul(a, b):
    """Hamilton product of (w, x, y, z) quaternions."""
    w1, x1, y1, z1 = a.T
    w2, x2, y2, z2 = b.T
    return np.column_stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def test_rigid_motion_as_a_deformation_equals_the_rigid_transform(scene):
    """Support = every Gaussian (nothing fixed), handle = 80 % of them (a
    handle may not cover the whole support: nothing would be left free), rotated
    90 degrees and moved: the free rest follows the affine map exactly, so the
    whole scene moves rigidly.  Reference: quaternion product, unchanged scales, colours seen along R d
    equal the old colours along d (no colour bleed)."""
    a = _rigid(np.pi / 2 * np.array([0.0, 0.6, 0.8]), [0.3, -0.1, 0.2])
    proxy = scene.proxy_splats()
    everything = np.ones(len(scene), bool)
    handle = proxy.positions[:, 1] > np.percentile(proxy.positions[:, 1], 20)
    basis = DeformationBasis.fit(proxy, everything, [handle], fill_holes=False)
    assert len(basis.indices) == len(scene)
    out = deform_with_evaluator(scene, basis, basis.displacement([a]))
    r = a[:3, :3]
    tol = GAUSSIAN_RIGID_ATTR_TOL
    assert np.abs(out.positions - (scene.positions @ r.T + a[:3, 3])).max() < tol
    q_ref = _quat_mul(np.tile(quaternions_from_matrices(r[None]), (len(scene), 1)), scene.unit_rotations())
    assert np.abs(np.abs((out.unit_rotations() * q_ref).sum(1)) - 1).max() < tol
    assert np.abs(out.rotation_matrices() - r @ scene.rotation_matrices()).max() < tol
    assert np.abs(out.log_scales - scene.log_scales).max() < tol
    assert np.array_equal(out.opacity_logits, scene.opacity_logits)
    d = np.random.default_rng(0).normal(size=(len(scene), 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    assert np.abs(sh_colors(out.sh, d @ r.T) - sh_colors(scene.sh, d)).max() < tol
    # without the SH rotation the colours would be off by far more (the bleed it prevents)
    assert np.abs(sh_colors(scene.sh, d @ r.T) - sh_colors(scene.sh, d)).max() > 100 * tol
    # the direct rigid transform agrees too
    direct = transform_gaussians(scene, a)
    for nm in ("positions", "log_scales", "sh"):
        assert np.abs(getattr(direct, nm) - getattr(out, nm)).max() < tol, nm


def test_deformed_save_reread_gives_j_sigma_jt(scene, tmp_path):
    proxy = scene.proxy_splats()
    p = proxy.positions
    basis = DeformationBasis.fit(proxy, p[:, 1] > 0.05, [p[:, 1] > 0.38])
    d_c = basis.displacement([_rigid([0.6, 0.0, 0.2], [0.0, 0.05, 0.0])])
    jac = basis.jacobians(d_c)
    assert np.abs(jac - np.eye(3)).max() > 0.1          # a real, non-rigid deformation
    expect = scene.covariances()
    idx = basis.indices
    expect[idx] = jac @ expect[idx] @ jac.transpose(0, 2, 1)
    out = write_gaussians(tmp_path / "def.ply", deform_with_evaluator(scene, basis, d_c))
    back = read_gaussians(out)
    cov = back.covariances()
    rel = np.linalg.norm(cov - expect, axis=(1, 2)) / np.linalg.norm(expect, axis=(1, 2))
    assert rel.max() < GAUSSIAN_SAVE_COV_REL_TOL
    # Gaussians outside the support are untouched, bit for bit
    out_idx = np.setdiff1d(np.arange(len(scene)), idx)
    assert np.array_equal(back.rotations[out_idx], scene.rotations[out_idx])
    assert np.array_equal(back.sh[out_idx], scene.sh[out_idx])


def test_redecomposition_keeps_axis_slots_under_mild_shear(scene):
    """A 10 % shear keeps each axis in its scale_k slot (the thin normal axis stays scale_2)."""
    jac = np.eye(3) + 0.1 * np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 0.5], [0.3, 0.0, 0.0]])
    out = deform_gaussians(scene, np.arange(len(scene)), np.zeros((len(scene), 3)),
                           np.broadcast_to(jac, (len(scene), 3, 3)))
    assert np.array_equal(np.argmin(out.log_scales, 1), np.argmin(scene.log_scales, 1))
    r0, r1 = scene.rotation_matrices(), out.rotation_matrices()
    thin = np.argmin(scene.log_scales, 1)
    rows = np.arange(len(scene))
    assert np.abs((r0[rows, :, thin] * r1[rows, :, thin]).sum(1)).min() > 0.9
    assert np.allclose(np.linalg.det(r1), 1.0)


def test_2dgs_surfels_stay_flat_and_follow_the_tangent_map(scene):
    g = GaussianCloud(scene.positions, scene.log_scales[:, :2].copy(), scene.rotations, scene.opacity_logits,
                      scene.sh, kind=GaussianKind.GS2D)
    a = _rigid([0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    a[:3, :3] = np.diag([2.0, 1.0, 1.0])
    out = transform_gaussians(g, a)
    assert out.log_scales.shape == (len(g), 2) and out.kind == GaussianKind.GS2D
    lin = a[:3, :3]
    expect = lin @ g.covariances() @ lin.T
    rel = np.linalg.norm(out.covariances() - expect, axis=(1, 2)) / np.linalg.norm(expect, axis=(1, 2))
    assert rel.max() < GAUSSIAN_SAVE_COV_REL_TOL


def test_polar_rotation_is_the_closest_rotation():
    rng = np.random.default_rng(2)
    q = Rotation.random(50, random_state=1).as_matrix()
    v = Rotation.random(50, random_state=2).as_matrix()
    p = v @ (rng.uniform(0.2, 3.0, (50, 3))[:, :, None] * v.transpose(0, 2, 1))   # SPD stretch
    np.testing.assert_allclose(polar_rotation(q @ p), q, atol=1e-12)


def test_a_singular_jacobian_is_refused_naming_the_gaussian(scene):
    jac = np.repeat(np.eye(3)[None], 3, axis=0)
    jac[1] = 0.0
    with pytest.raises(InputError, match="row 12"):
        deform_gaussians(scene, np.array([10, 12, 14]), np.zeros((3, 3)), jac)
