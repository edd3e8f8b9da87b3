"""Tangent frames of splats, and splats straight from a file's normals and radii.

No scipy here: a file that already says where its surface faces and how large
its splats are (``nx ny nz`` and ``radius``, as scanner pipelines and Open3D
write them) becomes a :class:`SplatCloud` without any neighbour search (Zwicker
et al. 2001, "Surface Splatting": a splat is a disc in the tangent plane).
"""

from __future__ import annotations

import numpy as np

from splatedit.model.cloud import SplatCloud
from splatedit.tolerances import ESTIMATE_CHUNK_POINTS


def tangent_frame(normals) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal tangent vectors ``(t1, t2)`` with ``t1 x t2 = n``.

    Uses the branch-free construction of Duff et al., "Building an
    Orthonormal Basis, Revisited" (JCGT 2017), which is continuous except
    across the equator sign switch of n_z.

    Args:
        normals: (n, 3) float64 unit normals.
    Returns:
        two (n, 3) float64 arrays of unit vectors.
    """
    nrm = np.asarray(normals, dtype=np.float64)
    x, y, z = nrm[:, 0], nrm[:, 1], nrm[:, 2]
    s = np.where(z >= 0.0, 1.0, -1.0)
    a = -1.0 / (s + z)
    b = x * y * a
    t1 = np.stack([1.0 + s * x * x * a, s * b, -s * x], axis=1)
    t2 = np.stack([b, s + y * y * a, -y], axis=1)
    return t1, t2


def usable_normals(normals) -> bool:
    """True when every row of ``normals`` ((n, 3)) is finite and non-zero, so
    that :func:`splats_from_normals` needs no estimated normal."""
    nrm = np.asarray(normals)
    for lo in range(0, len(nrm), 8 * ESTIMATE_CHUNK_POINTS):
        part = nrm[lo:lo + 8 * ESTIMATE_CHUNK_POINTS]
        ln2 = np.einsum("ij,ij->i", part, part)
        if not (np.isfinite(ln2).all() and (ln2 > 0).all()):
            return False
    return True


def splats_from_normals(points, normals, radius, colors=None, faces=None, *, name: str = "",
                        source: str | None = None, progress=None) -> SplatCloud:
    """Circular splats from given normals and radii, chunk by chunk.

    Args:
        points: (n, 3) float64 positions (model units).
        normals: (n, 3) normals, every row finite and non-zero
            (:func:`usable_normals`); normalised here.
        radius: scalar or (n,) radii > 0 (model units).
        colors: optional (n, 4) uint8; faces: optional (f, 3) int64, kept.
    Returns:
        SplatCloud whose ``u``, ``v`` ((n, 3) float64) are orthogonal, of
        length ``radius``, with ``u x v`` along the normal.
    """
    from splatedit.progress import report
    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    r = np.broadcast_to(np.asarray(radius, dtype=np.float64), (n,))
    u = np.empty((n, 3))
    v = np.empty((n, 3))
    step = 8 * ESTIMATE_CHUNK_POINTS
    report(progress, "splats from normals", 0.0)
    for lo in range(0, n, step):
        part = np.asarray(normals[lo:lo + step], dtype=np.float64)
        part = part / np.sqrt(np.einsum("ij,ij->i", part, part))[:, None]
        t1, t2 = tangent_frame(part)
        rr = r[lo:lo + step, None]
        np.multiply(t1, rr, out=u[lo:lo + step])
        np.multiply(t2, rr, out=v[lo:lo + step])
        report(progress, "splats from normals", min(1.0, (lo + step) / n))
    return SplatCloud(pts, u, v, colors, faces, name=name, source=source)
