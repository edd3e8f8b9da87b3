"""Synthetic smooth deformation bases with analytic derivatives, and the CPU
reference deformation p' = p + B dC, u' = J u, v' = J v."""

from __future__ import annotations

import numpy as np

from splatedit.model.cloud import SplatCloud


def gaussian_basis(points: np.ndarray, k: int = 4, sigma: float = 0.8, seed: int = 0):
    """B_k(p) = a_k exp(-|p - q_k|^2 / sigma^2) and its gradient (Bx, By, Bz)."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(-0.8, 0.8, size=(k, 3))
    a = rng.uniform(0.5, 1.0, size=k)
    diff = points[:, None, :] - q[None, :, :]                       # (n, k, 3)
    B = a * np.exp(-np.einsum("nki,nki->nk", diff, diff) / sigma ** 2)
    grad = -2.0 / sigma ** 2 * diff * B[..., None]                  # (n, k, 3)
    return B, grad[..., 0], grad[..., 1], grad[..., 2]


def cpu_deform(cloud: SplatCloud, idx, B, Bx, By, Bz, dC) -> SplatCloud:
    """Deform the splats ``idx``: p' = p + B dC; J_ij = delta_ij + sum_k dC_k[i] B{j}_k."""
    p, u, v = cloud.positions.copy(), cloud.u.copy(), cloud.v.copy()
    p[idx] += B @ dC
    J = np.eye(3)[None] + np.einsum("ki,nk->ni", dC, Bx)[:, :, None] * np.array([1.0, 0, 0]) \
        + np.einsum("ki,nk->ni", dC, By)[:, :, None] * np.array([0, 1.0, 0]) \
        + np.einsum("ki,nk->ni", dC, Bz)[:, :, None] * np.array([0, 0, 1.0])
    u[idx] = np.einsum("nij,nj->ni", J, u[idx])
    v[idx] = np.einsum("nij,nj->ni", J, v[idx])
    return cloud.replace(positions=p, u=u, v=v)


def bump_basis(points: np.ndarray, centre, sigma: float):
    """One column B(p) = exp(-|p - c|^2 / sigma^2) and its gradient: a smooth
    bump that moves the splats near ``centre`` by up to the whole dC."""
    diff = points - np.asarray(centre, dtype=np.float64)
    B = np.exp(-np.einsum("ni,ni->n", diff, diff) / sigma ** 2)[:, None]
    grad = -2.0 / sigma ** 2 * diff * B
    return B, grad[:, 0:1], grad[:, 1:2], grad[:, 2:3]
