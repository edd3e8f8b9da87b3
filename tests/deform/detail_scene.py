"""A bumpy plane bent 90 degrees: the measurement scene of the detail mode."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from splatedit.deform import transform as tf
from splatedit.model.cloud import SplatCloud


@dataclass
class BumpyPlane:
    """Grid plane z = sum of Gaussian bumps (spacing 1), fixed x < fixed_x,
    handle x > handle_x; ``apex`` (m,) splat indices of the bump tops,
    ``rings`` (m, r) indices of each bump's footprint ring."""
    cloud: SplatCloud
    support: np.ndarray
    handle: np.ndarray
    apex: np.ndarray
    rings: list
    height: float


def bumpy_plane(nx: int = 120, ny: int = 36, pitch: float = 12.0, height: float = 2.5,
                width: float = 1.8, foot: float = 5.0) -> BumpyPlane:
    x, y = np.meshgrid(np.arange(nx, dtype=float), np.arange(ny, dtype=float), indexing="ij")
    x, y = x.ravel(), y.ravel()
    cx = np.arange(pitch, nx - pitch / 2, pitch)
    cy = np.arange(pitch / 2, ny, pitch)
    centres = np.array([(a, b) for a in cx for b in cy])
    z = np.zeros_like(x)
    gx = np.zeros_like(x)
    gy = np.zeros_like(x)
    for a, b in centres:
        g = height * np.exp(-((x - a) ** 2 + (y - b) ** 2) / (2 * width ** 2))
        z += g
        gx += -g * (x - a) / width ** 2
        gy += -g * (y - b) / width ** 2
    pos = np.stack([x, y, z], axis=1)
    tu = np.stack([np.ones_like(x), np.zeros_like(x), gx], axis=1)
    tv = np.stack([np.zeros_like(x), np.ones_like(x), gy], axis=1)
    n = np.cross(tu, tv)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    u = tu / np.linalg.norm(tu, axis=1, keepdims=True)
    v = np.cross(n, u)
    r = 0.75  # splat radius in spacings (overlapping neighbours)
    cloud = SplatCloud(pos, u * r * np.linalg.norm(tu, axis=1, keepdims=True), v * r, name="bumpy")
    apex = np.array([int(np.argmin((x - a) ** 2 + (y - b) ** 2)) for a, b in centres])
    d = np.sqrt((x[:, None] - centres[:, 0]) ** 2 + (y[:, None] - centres[:, 1]) ** 2)
    rings = [np.flatnonzero(np.abs(d[:, k] - foot) < 0.75) for k in range(len(centres))]
    support = x >= 0.2 * nx
    handle = x >= 0.8 * nx
    return BumpyPlane(cloud, support, handle, apex, rings, height)


def bend(scene: BumpyPlane, degrees: float = 90.0) -> np.ndarray:
    """(4, 4) rotation of the handle by ``degrees`` about the bend line
    (parallel to y through the middle of the plane, z = 0)."""
    xm = 0.5 * (scene.cloud.positions[:, 0].min() + scene.cloud.positions[:, 0].max())
    return tf.rotate((0.0, 1.0, 0.0), -degrees, (xm, 0.0, 0.0))


def bump_figures(scene: BumpyPlane, positions: np.ndarray, which: np.ndarray):
    """Per bump in ``which``: (height, tilt degrees) of apex over the plane
    fitted to its footprint ring (PCA), ``positions`` (n, 3) a deformed state."""
    hs, tilts = [], []
    for k in which:
        ring = positions[scene.rings[k]]
        c = ring.mean(axis=0)
        _, _, vt = np.linalg.svd(ring - c)
        nrm = vt[2]
        a = positions[scene.apex[k]] - c
        if a @ nrm < 0:
            nrm = -nrm
        hs.append(a @ nrm)
        tilts.append(np.degrees(np.arccos(np.clip(a @ nrm / np.linalg.norm(a), -1, 1))))
    return np.array(hs), np.array(tilts)


def uncovered_fraction(p0: np.ndarray, positions: np.ndarray, u: np.ndarray, v: np.ndarray,
                       reach: float = 1.5) -> float:
    """Holes: the fraction of neighbour pairs (closer than ``reach`` before)
    whose deformed midpoint lies in neither splat's ellipse (projected on its
    plane; axes need not be orthogonal).  0 for the undeformed plane."""
    from scipy.spatial import cKDTree
    pairs = cKDTree(p0).query_pairs(reach, output_type="ndarray")
    mid = 0.5 * (positions[pairs[:, 0]] + positions[pairs[:, 1]])
    covered = np.zeros(len(pairs), bool)
    for side in (0, 1):
        i = pairs[:, side]
        d = mid - positions[i]
        a, b = u[i], v[i]
        e, f, g = (a * a).sum(1), (a * b).sum(1), (b * b).sum(1)
        ra, rb = (d * a).sum(1), (d * b).sum(1)
        det = e * g - f * f
        s = (g * ra - f * rb) / det
        t = (e * rb - f * ra) / det
        covered |= s * s + t * t <= 1.0
    return float(1.0 - covered.mean())
