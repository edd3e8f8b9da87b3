"""Farthest-point ordering of RBF centers (Botsch & Kobbelt 2005, Sect. 5).

The incremental QR solver adds basis functions in farthest-point order: each
new center is the constraint point with the largest distance to the centers
chosen so far.  This gives a uniform sampling and "maximally linearly
independent" kernel columns, hence a well-conditioned R.

Cost: O(m) per selected center (one vectorised distance update and one
argmax), O(m n) for n centers.  The ordering is deterministic: the seed is the
point farthest from the centroid and ties go to the lowest index.
"""

from __future__ import annotations

import numpy as np

from splatedit.errors import ParameterError


class FarthestPointSampler:
    """Produces the farthest-point order of ``points`` incrementally.

    ``take(count)`` returns the next ``count`` indices, so the IQR solver only
    pays for the centers it actually uses.  Points already selected are never
    selected again; exact duplicates come last (their distance is 0).
    """

    def __init__(self, points: np.ndarray):
        pts = np.asarray(points, dtype=np.float64)
        if pts.ndim != 2 or pts.shape[1] != 3:
            raise ParameterError("points", f"expected shape (m, 3), got {pts.shape}")
        if pts.shape[0] == 0:
            raise ParameterError("points", "need at least one point")
        # separate contiguous coordinate arrays make each update 3 fused passes
        self._x = np.ascontiguousarray(pts[:, 0])
        self._y = np.ascontiguousarray(pts[:, 1])
        self._z = np.ascontiguousarray(pts[:, 2])
        self.m = pts.shape[0]
        self._mind = np.full(self.m, np.inf)
        self._tmp = np.empty(self.m)
        self._tmp2 = np.empty(self.m)
        self._n = 0
        centroid = pts.mean(axis=0)
        self._dist_to(centroid, self._tmp)
        self._next = int(np.argmax(self._tmp))

    @property
    def n_selected(self) -> int:
        return self._n

    def _dist_to(self, p, out):
        np.subtract(self._x, p[0], out=out)
        np.multiply(out, out, out=out)
        np.subtract(self._y, p[1], out=self._tmp2)
        np.multiply(self._tmp2, self._tmp2, out=self._tmp2)
        out += self._tmp2
        np.subtract(self._z, p[2], out=self._tmp2)
        np.multiply(self._tmp2, self._tmp2, out=self._tmp2)
        out += self._tmp2
        return out

    def take(self, count: int) -> np.ndarray:
        """The next ``min(count, remaining)`` indices of the order."""
        count = max(0, min(int(count), self.m - self._n))
        out = np.empty(count, dtype=np.intp)
        mind, tmp = self._mind, self._tmp
        for i in range(count):
            j = self._next
            out[i] = j
            self._n += 1
            p = (self._x[j], self._y[j], self._z[j])
            self._dist_to(p, tmp)
            np.minimum(mind, tmp, out=mind)
            mind[j] = -1.0  # never select again, even among duplicates
            if self._n < self.m:
                self._next = int(np.argmax(mind))
        return out


def farthest_point_order(points: np.ndarray, count: int | None = None) -> np.ndarray:
    """Permutation of ``range(m)`` (or its first ``count`` entries) in
    farthest-point order, seeded with the point farthest from the centroid."""
    sampler = FarthestPointSampler(points)
    return sampler.take(sampler.m if count is None else count)
