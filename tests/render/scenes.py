"""Small procedural splat clouds for the render tests (no files needed)."""

from __future__ import annotations

import numpy as np

from splatedit.model.cloud import SplatCloud


def _tangents(normals):
    a = np.where(np.abs(normals[:, [0]]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
    t1 = np.cross(normals, a)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(normals, t1)
    return t1, t2


def sphere(n=4000, radius=1.0, center=(0.0, 0.0, 0.0), overlap=1.6, colors=False, seed=None):
    """Fibonacci-sampled sphere; splat radius = overlap * sampling spacing / 2 * ... (hole-free)."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = np.pi * (1.0 + 5 ** 0.5) * i
    r = np.sqrt(1.0 - z * z)
    nrm = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
    # v x u orientation such that u x v = outward normal
    t1, t2 = _tangents(nrm)
    if (np.einsum("ij,ij->i", np.cross(t1, t2), nrm) < 0).any():
        t2 = -t2
    spacing = radius * np.sqrt(4 * np.pi / n)
    s = overlap * spacing
    pos = np.asarray(center) + radius * nrm
    col = None
    if colors:
        col = np.empty((n, 4), np.uint8)
        col[:, :3] = np.clip((nrm * 0.5 + 0.5) * 255, 0, 255).astype(np.uint8)
        col[:, 3] = 255
    return SplatCloud(pos, t1 * s, t2 * s, col, name="sphere")


def torus(nu=120, nv=48, R=1.0, r=0.35, overlap=1.4):
    """Regularly sampled torus with anisotropic splats (elliptic where sampling is anisotropic)."""
    a = (np.arange(nu) + 0.5) / nu * 2 * np.pi
    b = (np.arange(nv) + 0.5) / nv * 2 * np.pi
    A, Bv = np.meshgrid(a, b, indexing="ij")
    A, Bv = A.reshape(-1), Bv.reshape(-1)
    ca, sa, cb, sb = np.cos(A), np.sin(A), np.cos(Bv), np.sin(Bv)
    pos = np.stack([(R + r * cb) * ca, (R + r * cb) * sa, r * sb], axis=1)
    du = np.stack([-sa, ca, np.zeros_like(A)], axis=1)                # along the big circle
    dv = np.stack([-sb * ca, -sb * sa, cb], axis=1)                   # along the small circle
    lu = overlap * (R + r * cb) * np.pi / nu
    lv = overlap * r * np.pi / nv
    u = du * lu[:, None]
    v = dv * lv
    nrm = np.stack([cb * ca, cb * sa, sb], axis=1)
    flip = np.einsum("ij,ij->i", np.cross(u, v), nrm) < 0
    v[flip] *= -1
    col = np.empty((len(pos), 4), np.uint8)
    col[:, 0] = (128 + 100 * ca).astype(np.uint8)
    col[:, 1] = (128 + 100 * sb).astype(np.uint8)
    col[:, 2] = 180
    col[:, 3] = 255
    return SplatCloud(pos, u, v, col, name="torus")


def plane(n_side=60, size=2.0, overlap=1.5):
    """Square grid in the z = 0 plane, normal +z."""
    g = (np.arange(n_side) + 0.5) / n_side * size - size / 2
    X, Y = np.meshgrid(g, g, indexing="ij")
    pos = np.stack([X.reshape(-1), Y.reshape(-1), np.zeros(X.size)], axis=1)
    h = overlap * size / n_side / 2 * 1.42
    u = np.tile([h, 0.0, 0.0], (len(pos), 1))
    v = np.tile([0.0, h, 0.0], (len(pos), 1))
    return SplatCloud(pos, u, v, None, name="plane")
