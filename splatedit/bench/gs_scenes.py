"""Synthetic Gaussian Splatting scenes for the renderer's tests and benchmark.

:func:`gaussians_from_splats` turns a surface-splat cloud into Gaussians lying
on its splats (a stand-in until the shipped 3DGS test scene exists; the
benchmark keeps using it for its 100k / 1M counts): each splat's tangent
frame gives the rotation, its axes the two in-plane standard deviations (a
thin third one along the normal), the colour comes from the normal
direction, bands 1-3 add view-dependent colour, and opacities and
anisotropies are spread.
"""

from __future__ import annotations

import numpy as np

from splatedit.model.cloud import SplatCloud
from splatedit.model.gaussians import GaussianCloud

SH_C0 = 0.28209479177387814


def _quat_from_matrix(r: np.ndarray) -> np.ndarray:
    """(n, 3, 3) proper rotations -> (n, 4) unit quaternions (w, x, y, z)."""
    tr = np.trace(r, axis1=1, axis2=2)
    q = np.empty((len(r), 4))
    w = np.sqrt(np.maximum(1.0 + tr, 0.0)) / 2.0
    q[:, 0] = w
    q[:, 1] = np.copysign(np.sqrt(np.maximum(1 + r[:, 0, 0] - r[:, 1, 1] - r[:, 2, 2], 0.0)) / 2,
                          r[:, 2, 1] - r[:, 1, 2])
    q[:, 2] = np.copysign(np.sqrt(np.maximum(1 - r[:, 0, 0] + r[:, 1, 1] - r[:, 2, 2], 0.0)) / 2,
                          r[:, 0, 2] - r[:, 2, 0])
    q[:, 3] = np.copysign(np.sqrt(np.maximum(1 - r[:, 0, 0] - r[:, 1, 1] + r[:, 2, 2], 0.0)) / 2,
                          r[:, 1, 0] - r[:, 0, 1])
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def gaussians_from_splats(cloud: SplatCloud, *, degree: int = 3, seed: int = 0, view_dependence: float = 0.25,
                          min_opacity: float = 0.05) -> GaussianCloud:
    """Gaussians on the splats of ``cloud`` (one per splat).

    Standard deviations are half the splat axes' lengths (times a random
    anisotropy factor in 0.6..1.6 on each), 0.1 of the smaller along the normal;
    opacities uniform in ``min_opacity``..1 with a quarter of them at 0.9+;
    SH DC = the normal's colour, bands 1..``degree`` random with standard
    deviation ``view_dependence`` / band (so colours change with the view)."""
    rng = np.random.default_rng(seed)
    n = cloud.n
    u, v = np.asarray(cloud.u, np.float64), np.asarray(cloud.v, np.float64)
    su, sv = np.linalg.norm(u, axis=1), np.linalg.norm(v, axis=1)
    e1 = u / su[:, None]
    e2 = v - np.einsum("ij,ij->i", v, e1)[:, None] * e1
    e2 /= np.linalg.norm(e2, axis=1, keepdims=True)
    e3 = np.cross(e1, e2)
    rot = np.stack([e1, e2, e3], axis=2)               # columns: local axes in world
    aniso = rng.uniform(0.6, 1.6, (n, 2))
    s = np.stack([0.5 * su * aniso[:, 0], 0.5 * sv * aniso[:, 1], np.zeros(n)], axis=1)
    s[:, 2] = 0.1 * s[:, :2].min(axis=1)
    op = rng.uniform(min_opacity, 1.0, n)
    hi = rng.random(n) < 0.25
    op[hi] = rng.uniform(0.9, 0.99, int(hi.sum()))
    k = (degree + 1) ** 2
    sh = np.zeros((n, k, 3))
    rgb = np.clip(0.5 + 0.45 * e3, 0.05, 0.95)
    sh[:, 0, :] = (rgb - 0.5) / SH_C0
    for band in range(1, degree + 1):
        sh[:, band * band:(band + 1) ** 2, :] = rng.normal(0, view_dependence / band, (n, 2 * band + 1, 3))
    return GaussianCloud(positions=np.asarray(cloud.positions, np.float64).copy(),
                         log_scales=np.log(s).astype(np.float32),
                         rotations=_quat_from_matrix(rot).astype(np.float32),
                         opacity_logits=np.log(op / (1.0 - op)).astype(np.float32),
                         sh=sh.astype(np.float32), name=f"gaussians({cloud.name or 'splats'})")
