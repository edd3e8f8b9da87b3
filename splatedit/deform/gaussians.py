"""Deforming Gaussian splatting scenes (pure numpy).

A deformation is given, at the Gaussians it moves, by its displacement and
its Jacobian J (any evaluator: the linear bases ``p + B dC`` of
:class:`~splatedit.deform.basis.DeformationBasis`, a rotation-aware evaluator,
an affine map).  The first-order (EWA-style) transport of a Gaussian is

* centre: ``p' = p + d``;
* covariance: ``Sigma' = J Sigma J^T``, re-decomposed into scales and a unit
  rotation from the SVD of the factor ``J R diag(s)`` (so Sigma' = U S^2 U^T
  without squaring the condition number as eigh of Sigma' would); the new
  axes are matched to the images ``J R e_k`` of the old ones (order and
  sign), so an axis keeps its ``scale_k`` slot and a rigid motion changes
  only the rotation, then made right-handed;
* view-dependent colour: the SH bands 1..3 rotated by the rotation part Q of
  ``J = Q P`` (polar decomposition), so that the colour seen along ``Q d``
  after the edit is the colour seen along ``d`` before it
  (:func:`splatedit.model.spherical_harmonics.rotate_sh`);
* opacity and band 0 unchanged.

2DGS surfels use their two tangent axes (``J R[:, :2] diag(s)``); the normal
becomes their cross product.
"""

from __future__ import annotations

import itertools

import numpy as np

from splatedit.errors import InputError
from splatedit.model.gaussians import GaussianCloud, GaussianKind
from splatedit.model.spherical_harmonics import rotate_sh
from splatedit.progress import report
from splatedit.tolerances import GAUSSIAN_COMMIT_CHUNK

#: progress stage of :func:`deform_gaussians` (an editor commit of a 3DGS document)
GAUSSIAN_STAGE = "deforming the Gaussians"

_PERMS3 = np.array(list(itertools.permutations(range(3))))
_PERMS2 = np.array(list(itertools.permutations(range(2))))


def polar_rotation(jacobians: np.ndarray) -> np.ndarray:
    """Orthogonal factor Q of the polar decomposition ``J = Q P`` (P symmetric
    positive semi-definite): ``Q = U V^T`` from the SVD.

    Args:
        jacobians: (n, 3, 3) float64.
    Returns:
        (n, 3, 3) float64 (a rotation where det J > 0).
    """
    u, _, vt = np.linalg.svd(jacobians)
    return u @ vt


def quaternions_from_matrices(r: np.ndarray) -> np.ndarray:
    """(n, 4) float64 unit quaternions (w, x, y, z) of rotation matrices (n, 3, 3)
    (Shepperd's method: the largest of w, x, y, z is computed from the diagonal)."""
    m = np.asarray(r, dtype=np.float64)
    t = np.stack([m[:, 0, 0] + m[:, 1, 1] + m[:, 2, 2], m[:, 0, 0], m[:, 1, 1], m[:, 2, 2]], 1)
    big = np.argmax(np.stack([t[:, 0], 2 * t[:, 1] - t[:, 0], 2 * t[:, 2] - t[:, 0],
                              2 * t[:, 3] - t[:, 0]], 1), axis=1)
    q = np.empty((len(m), 4))
    for case in range(4):
        sel = big == case
        if not sel.any():
            continue
        a = m[sel]
        if case == 0:
            s = 2.0 * np.sqrt(np.maximum(1.0 + a[:, 0, 0] + a[:, 1, 1] + a[:, 2, 2], 0.0))
            q[sel] = np.column_stack([s / 4, (a[:, 2, 1] - a[:, 1, 2]) / s,
                                      (a[:, 0, 2] - a[:, 2, 0]) / s, (a[:, 1, 0] - a[:, 0, 1]) / s])
        elif case == 1:
            s = 2.0 * np.sqrt(np.maximum(1.0 + a[:, 0, 0] - a[:, 1, 1] - a[:, 2, 2], 0.0))
            q[sel] = np.column_stack([(a[:, 2, 1] - a[:, 1, 2]) / s, s / 4,
                                      (a[:, 0, 1] + a[:, 1, 0]) / s, (a[:, 0, 2] + a[:, 2, 0]) / s])
        elif case == 2:
            s = 2.0 * np.sqrt(np.maximum(1.0 - a[:, 0, 0] + a[:, 1, 1] - a[:, 2, 2], 0.0))
            q[sel] = np.column_stack([(a[:, 0, 2] - a[:, 2, 0]) / s, (a[:, 0, 1] + a[:, 1, 0]) / s,
                                      s / 4, (a[:, 1, 2] + a[:, 2, 1]) / s])
        else:
            s = 2.0 * np.sqrt(np.maximum(1.0 - a[:, 0, 0] - a[:, 1, 1] + a[:, 2, 2], 0.0))
            q[sel] = np.column_stack([(a[:, 1, 0] - a[:, 0, 1]) / s, (a[:, 0, 2] + a[:, 2, 0]) / s,
                                      (a[:, 1, 2] + a[:, 2, 1]) / s, s / 4])
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def decompose_factor(m: np.ndarray):
    """Scales and rotation of the covariance ``M M^T``, axes matched to M's columns.

    Args:
        m: (n, 3, k) float64, k = 3 (3DGS) or 2 (2DGS): column j is the image
            ``J r_j s_j`` of the Gaussian's old axis j.
    Returns:
        (scales (n, k) float64, rotations (n, 3, 3) float64 right-handed): new
        axis j is the principal axis closest in direction to column j (the
        best of the k! assignments), with a non-negative component along it.
    """
    n, _, k = m.shape
    u, s, _ = np.linalg.svd(m, full_matrices=False)          # u (n, 3, k), s (n, k)
    norms = np.linalg.norm(m, axis=1)                          # (n, k)
    a = m / np.where(norms > 0, norms, 1.0)[:, None, :]
    overlap = np.einsum("nij,nik->njk", u, a)                  # [n, principal j, old axis k]
    perms = _PERMS3 if k == 3 else _PERMS2
    score = np.abs(overlap[:, perms, np.arange(k)]).sum(axis=2)   # (n, k!)
    perm = perms[np.argmax(score, axis=1)]                     # (n, k): principal axis per old axis
    rows = np.arange(n)[:, None]
    axes = u.transpose(0, 2, 1)[rows, perm]                    # (n, k, 3)
    sign = np.sign(overlap[rows, perm, np.arange(k)])
    axes = axes * np.where(sign == 0, 1.0, sign)[..., None]
    scales = s[rows, perm]
    rot = np.empty((n, 3, 3))
    rot[:, :, 0] = axes[:, 0]
    rot[:, :, 1] = axes[:, 1]
    if k == 2:
        rot[:, :, 2] = np.cross(axes[:, 0], axes[:, 1])
        return scales, rot
    rot[:, :, 2] = axes[:, 2]
    left = np.linalg.det(rot) < 0
    if left.any():    # flip the axis least aligned with its old image (all flips keep Sigma)
        fit = np.abs(overlap[rows, perm, np.arange(k)])[left]
        col = np.argmin(fit, axis=1)
        rot[np.flatnonzero(left), :, col] *= -1.0
    return scales, rot


def deform_gaussians(scene: GaussianCloud, indices, displacements, jacobians, *,
                     progress=None) -> GaussianCloud:
    """Apply a deformation given at some Gaussians.

    Args:
        scene: the base scene.
        indices: (N,) int indices of the Gaussians that move (others are
            copied bit for bit).
        displacements: (N, 3) float64 centre displacements (model units).
        jacobians: (N, 3, 3) float64 Jacobians of the deformation at the centres.
        progress: optional ``progress(GAUSSIAN_STAGE, fraction of the N done)``,
            reported after each chunk of ``GAUSSIAN_COMMIT_CHUNK`` Gaussians
            (the result does not depend on the chunking).
    Returns:
        a new GaussianCloud: positions float64, log scales, unit quaternions
        (in the hemisphere of the old ones) and SH coefficients float32;
        opacity, normals and extra properties shared with ``scene``.
    Raises:
        InputError: a Jacobian flattens a Gaussian (a zero or non-finite scale).
    """
    idx = np.asarray(indices, dtype=np.intp)
    disp = np.asarray(displacements, dtype=np.float64)
    jac = np.asarray(jacobians, dtype=np.float64)
    positions = scene.positions.copy()
    positions[idx] = scene.positions[idx] + disp
    log_scales = scene.log_scales.copy()
    rotations = scene.rotations.copy()
    sh = scene.sh
    if sh.shape[1] > 1 and len(idx):
        sh = sh.copy()
    report(progress, GAUSSIAN_STAGE, 0.0)
    for lo in range(0, len(idx), GAUSSIAN_COMMIT_CHUNK):
        hi = min(len(idx), lo + GAUSSIAN_COMMIT_CHUNK)
        _deform_chunk(scene, idx[lo:hi], jac[lo:hi], log_scales, rotations, sh)
        report(progress, GAUSSIAN_STAGE, hi / len(idx))
    return scene.replace(positions=positions, log_scales=log_scales, rotations=rotations, sh=sh)


def _deform_chunk(scene: GaussianCloud, idx: np.ndarray, jac: np.ndarray, log_scales, rotations, sh) -> None:
    """Write the new log scales, rotations and (when ``sh`` is not
    ``scene.sh``) rotated SH coefficients of the Gaussians ``idx`` (with
    Jacobians ``jac``) into the output arrays."""
    k = 2 if scene.kind == GaussianKind.GS2D else 3
    r_old = scene.rotation_matrices(idx)
    s_old = np.exp(scene.log_scales[idx].astype(np.float64))
    m = (jac @ r_old[:, :, :k]) * s_old[:, None, :]
    scales, rot = decompose_factor(m)
    bad = ~(np.isfinite(scales).all(axis=1) & (scales > 0).all(axis=1))
    if bad.any():
        row = int(idx[np.flatnonzero(bad)[0]])
        raise InputError("the deformation flattens this Gaussian to zero size (a singular "
                         "Jacobian); use a milder edit", path=scene.source, element="vertex",
                         row=row, prop="scale_0")
    q = quaternions_from_matrices(rot)
    q_old = scene.unit_rotations(idx)
    q *= np.where((q * q_old).sum(axis=1) < 0, -1.0, 1.0)[:, None]
    log_scales[idx] = np.log(scales).astype(np.float32)
    rotations[idx] = q.astype(np.float32)
    if sh is not scene.sh:
        sh[idx] = rotate_sh(sh[idx], polar_rotation(jac)).astype(np.float32)


def deform_with_evaluator(scene: GaussianCloud, evaluator, dC, *, progress=None) -> GaussianCloud:
    """:func:`deform_gaussians` with any evaluator that has ``indices`` (N,),
    ``displacements(dC)`` (N, 3) and ``jacobians(dC)`` (N, 3, 3), such as a
    :class:`~splatedit.deform.basis.DeformationBasis` fitted on
    ``scene.proxy_splats()``.  ``progress``: see :func:`deform_gaussians`."""
    report(progress, GAUSSIAN_STAGE, 0.0)
    return deform_gaussians(scene, evaluator.indices, evaluator.displacements(dC),
                            evaluator.jacobians(dC), progress=progress)


def transform_gaussians(scene: GaussianCloud, matrix) -> GaussianCloud:
    """Apply one affine map (4, 4) (acting on column vectors) to every Gaussian."""
    a = np.asarray(matrix, dtype=np.float64)
    lin, t = a[:3, :3], a[:3, 3]
    disp = scene.positions @ lin.T + t - scene.positions
    jac = np.broadcast_to(lin, (len(scene), 3, 3))
    return deform_gaussians(scene, np.arange(len(scene)), disp, jac)
