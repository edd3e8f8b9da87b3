"""Batched neighbourhood PCA for normal estimation, and a cache-friendly point order.

* :func:`morton_order` sorts points along a Z-order (Morton) curve, so that
  points close in space are close in memory.  Estimating normals and sizes
  of a scan in that order makes every k-d tree query and neighbour gather
  cache-local (a 1M-point k-NN query: 2.7 s in file order, 1.2 s in Morton
  order on the 2-core development machine).
* :func:`neighbourhood_covariances` returns the six distinct entries of the
  3x3 covariance of every point's neighbours, computed relative to the point
  itself (no cancellation for georeferenced coordinates).
* :func:`smallest_eigenvectors` solves all 3x3 symmetric eigenproblems at
  once in closed form: the smallest eigenvalue from the trigonometric
  solution of the characteristic cubic (O. K. Smith, "Eigenvalues of a
  symmetric 3x3 matrix", CACM 1961), the eigenvector as the largest cross
  product of two rows of ``A - lambda I``.  Rows whose smallest eigenvalue
  is not well separated (the cross products vanish) fall back to
  ``np.linalg.eigh``.
"""

from __future__ import annotations

import numpy as np

from splatedit.tolerances import EIGEN_CROSS_MIN_REL, ESTIMATE_CHUNK_POINTS

_MORTON_BITS = 21


def _spread_bits(x: np.ndarray) -> np.ndarray:
    """Insert two zero bits between the low 21 bits of every uint64."""
    x = x & np.uint64(0x1FFFFF)
    x = (x | x << np.uint64(32)) & np.uint64(0x1F00000000FFFF)
    x = (x | x << np.uint64(16)) & np.uint64(0x1F0000FF0000FF)
    x = (x | x << np.uint64(8)) & np.uint64(0x100F00F00F00F00F)
    x = (x | x << np.uint64(4)) & np.uint64(0x10C30C30C30C30C3)
    x = (x | x << np.uint64(2)) & np.uint64(0x1249249249249249)
    return x


def morton_codes(points) -> tuple[np.ndarray, np.ndarray, float]:
    """Z-order (Morton) code of every point on a 2^21 grid over the bounding
    cube of ``points`` ((n, 3) float).

    Returns:
        codes (n,) uint64 (bits ``z y x`` interleaved, x lowest), the cube's
        corner ``lo`` (3,) float64 and ``scale`` (grid steps per model unit):
        a point's grid coordinates are ``floor((p - lo) * scale)``.
    """
    pts = np.asarray(points)
    n = len(pts)
    if n == 0:
        return np.zeros(0, np.uint64), np.zeros(3), 0.0
    lo = pts.min(axis=0).astype(np.float64)
    ext = float((pts.max(axis=0) - lo).max())
    scale = (2 ** _MORTON_BITS - 1) / ext if ext > 0 else 0.0
    code = np.zeros(n, dtype=np.uint64)
    step = 16 * ESTIMATE_CHUNK_POINTS
    for lo_i in range(0, n, step):
        q = ((pts[lo_i:lo_i + step] - lo) * scale).astype(np.uint64)
        code[lo_i:lo_i + step] = interleave(q)
    return code, lo, scale


def interleave(q: np.ndarray) -> np.ndarray:
    """Morton codes of (m, 3) non-negative integer grid coordinates below
    2^21: (m,) uint64."""
    q = np.asarray(q).astype(np.uint64, copy=False)
    return (_spread_bits(q[:, 0]) | _spread_bits(q[:, 1]) << np.uint64(1)
            | _spread_bits(q[:, 2]) << np.uint64(2))


def morton_order(points) -> np.ndarray:
    """Permutation sorting ``points`` ((n, 3) float) along a Z-order curve
    on a 2^21 grid over their bounding cube; (n,) int64."""
    n = len(points)
    if n < 2:
        return np.arange(n, dtype=np.int64)
    code, _, _ = morton_codes(points)
    return np.argsort(code, kind="stable").astype(np.int64, copy=False)


def neighbourhood_covariances(points, neighbours, centres=None) -> np.ndarray:
    """Covariance of every neighbourhood, as its six distinct entries.

    Args:
        points: (n, 3) float64 positions (model units).
        neighbours: (m, k) integer indices into ``points`` (k >= 1).
        centres: optional (m, 3) float64 reference points subtracted before
            the products (default: the first neighbour of each row); any
            point near the neighbourhood keeps the sums well conditioned.
    Returns:
        (m, 6) float64: ``xx, xy, xz, yy, yz, zz`` of
        ``mean((p - mean p)(p - mean p)^T)`` over each row's neighbours
        (model units squared).
    """
    nb = np.asarray(neighbours)
    pts = np.asarray(points, dtype=np.float64)
    ref = pts[nb[:, 0]] if centres is None else np.asarray(centres, dtype=np.float64)
    k = nb.shape[1]
    # one coordinate at a time (x[nb] gathers of (m, k)): 2.4x faster than a
    # (m, k, 3) gather and a batched matmul
    d = [pts[:, j][nb] - ref[:, j, None] for j in range(3)]
    s = [dj.sum(axis=1) / k for dj in d]
    out = np.empty((len(nb), 6))
    for c, (i, j) in enumerate(((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))):
        out[:, c] = np.einsum("mk,mk->m", d[i], d[j]) / k - s[i] * s[j]
    return out


def smallest_eigenvectors(cov) -> np.ndarray:
    """Unit eigenvector of the smallest eigenvalue of each symmetric 3x3 matrix.

    Args:
        cov: (m, 6) float64 entries ``xx, xy, xz, yy, yz, zz``.
    Returns:
        (m, 3) float64 unit vectors (sign arbitrary).  A multiple of the
        identity (no preferred direction) gives +z.
    """
    a = np.asarray(cov, dtype=np.float64)
    xx, xy, xz, yy, yz, zz = (a[:, c] for c in range(6))
    q = (xx + yy + zz) / 3.0
    bxx, byy, bzz = xx - q, yy - q, zz - q
    p2 = bxx * bxx + byy * byy + bzz * bzz + 2.0 * (xy * xy + xz * xz + yz * yz)
    p = np.sqrt(p2 / 6.0)
    safe = np.where(p > 0, p, 1.0)
    det = (bxx * (byy * bzz - yz * yz) - xy * (xy * bzz - yz * xz) + xz * (xy * yz - byy * xz))
    r = np.clip(det / (2.0 * safe ** 3), -1.0, 1.0)
    phi = np.arccos(r) / 3.0
    lam = q + 2.0 * p * np.cos(phi + 2.0 * np.pi / 3.0)      # smallest root
    r0 = np.stack([xx - lam, xy, xz], axis=1)
    r1 = np.stack([xy, yy - lam, yz], axis=1)
    r2 = np.stack([xz, yz, zz - lam], axis=1)
    c = np.stack([np.cross(r0, r1), np.cross(r0, r2), np.cross(r1, r2)], axis=1)   # (m, 3, 3)
    n2 = np.einsum("mij,mij->mi", c, c)
    best = n2.argmax(axis=1)
    rows = np.arange(len(a))
    vec = c[rows, best]
    norm = np.sqrt(n2[rows, best])
    # |cross| ~ (l1 - l3)(l2 - l3): small against p^2 when l3 is not simple
    weak = ~(norm > EIGEN_CROSS_MIN_REL * p2)
    out = vec / np.where(weak, 1.0, norm)[:, None]
    if weak.any():
        w = np.flatnonzero(weak)
        full = np.empty((len(w), 3, 3))
        full[:, 0, 0], full[:, 0, 1], full[:, 0, 2] = xx[w], xy[w], xz[w]
        full[:, 1, 0], full[:, 1, 1], full[:, 1, 2] = xy[w], yy[w], yz[w]
        full[:, 2, 0], full[:, 2, 1], full[:, 2, 2] = xz[w], yz[w], zz[w]
        _, ev = np.linalg.eigh(full)
        out[w] = ev[:, :, 0]
        iso = w[p[w] == 0]
        out[iso] = (0.0, 0.0, 1.0)
    return out
