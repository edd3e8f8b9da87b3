"""Neighbourhood figures of a large cloud from spatial patches, without an
all-points k-NN (``splatedit info`` above ``INFO_EXACT_MAX_POINTS``).

A random subsample is not enough: thinning a surface changes its spacing
(by sqrt of the thinning factor) and so every neighbour distance.  Instead
whole cells of a grid are kept (a Kronecker sequence over the integer cell
coordinates picks about ``target`` points' worth of cells), so the points of
a picked cell keep all their neighbours; figures are taken at the patch
points far enough from their cell's faces (:meth:`PatchSample.knn`).  Cells
are ``INFO_PATCH_SPACINGS`` rough spacings wide, the rough spacing estimated
from a random subsample (surface scaling).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from splatedit.model.cloud import column_bounds
from splatedit.tolerances import INFO_PATCH_REACH_QUANTILE, INFO_PATCH_SPACINGS, INFO_SAMPLE_POINTS

_CHUNK = 1 << 20


@dataclass(frozen=True)
class PatchSample:
    """Points of the picked cells.

    Attributes:
        index: (m,) int64 indices into the cloud of the patch points.
        face_distance: (m,) float64, distance of each patch point to the
            nearest face of its cell (model units).
        tree: cKDTree of the patch points.
    """

    index: np.ndarray
    face_distance: np.ndarray
    tree: cKDTree

    def knn(self, k: int):
        """k-NN of the patch points within the patch (the point itself first).

        Returns:
            (dist (m, k), idx (m, k) into the patch, used (m,) bool): the
            points at least R from their cell's faces, R the
            ``INFO_PATCH_REACH_QUANTILE`` quantile of the k-th distances
            found.  Their neighbours within R are all found, so every figure
            is exact except for the few with k-th distance beyond R, whose
            distances found are upper bounds (and beyond R either way).  The choice does not depend on
            a point's own neighbourhood, so it does not favour dense parts.
        """
        k = min(k, len(self.index))
        d, j = self.tree.query(self.tree.data, k=k, workers=-1)
        reach = float(np.quantile(d[:, -1], INFO_PATCH_REACH_QUANTILE))
        return d, j, self.face_distance >= reach


def _rough_spacing(points, rng, m: int) -> float:
    n = len(points)
    sub = points[rng.integers(0, n, size=m)]
    d, _ = cKDTree(sub).query(sub, k=2, workers=-1)
    d = d[:, 1][d[:, 1] > 0]
    if not len(d):
        return 0.0
    return float(np.median(d)) * np.sqrt(m / n)     # surface: spacing ~ 1/sqrt(density)


def patch_sample(points, target: int = INFO_SAMPLE_POINTS, seed: int = 0,
                 lower=None) -> PatchSample | None:
    """Pick grid cells holding about ``target`` points in all.

    Args:
        points: (n, 3) float64 positions (model units).
        lower: (3,) lower corner of their bounding box, if known.
    Returns:
        :class:`PatchSample`, or None when no spacing can be estimated
        (all points coincide).
    """
    n = len(points)
    rng = np.random.default_rng(seed)
    h0 = _rough_spacing(points, rng, min(n, 50_000))
    if not h0 > 0:
        return None
    cell = INFO_PATCH_SPACINGS * h0
    lo = column_bounds(points)[0] if lower is None else np.asarray(lower, dtype=np.float64)
    keep_frac = min(1.0, target / n)
    # a cell (i, j, k) is picked when frac(i a + j b + k c) < keep_frac, with
    # a, b, c irrational (a Kronecker sequence): cells spread evenly over
    # the cloud, one matrix-vector product per chunk
    w = np.array([0.6180339887498949, 0.7548776662466927, 0.5698402909980532])
    inv = 1.0 / cell
    picked = []
    cbuf = np.empty((min(n, _CHUNK), 3))
    kbuf = np.empty(min(n, _CHUNK))
    fbuf = np.empty(min(n, _CHUNK))
    # the corner repeated per row: subtracting a (3,) row broadcast over (m, 3)
    # runs numpy's length-3 inner loop m times, 3-4x slower (same values)
    lo_rows = np.tile(lo, (min(n, _CHUNK), 1))
    for a in range(0, n, _CHUNK):
        blk = points[a:a + _CHUNK]
        m = len(blk)
        c, key, fl = cbuf[:m], kbuf[:m], fbuf[:m]
        np.subtract(blk, lo_rows[:m], out=c)     # reused buffers: no allocation per chunk
        c *= inv
        np.floor(c, out=c)
        np.matmul(c, w, out=key)
        np.floor(key, out=fl)
        key -= fl
        picked.append(a + np.flatnonzero(key < keep_frac))
    index = np.concatenate(picked)
    pts = points[index]
    off = (pts - lo) / cell
    frac = off - np.floor(off)
    face = cell * np.minimum(frac, 1.0 - frac).min(axis=1)
    return PatchSample(index, face, cKDTree(pts))
