"""Geometric region selections: which splats lie in a sphere, a box, or a list.

A selection is always an ``(n,) bool`` mask over the cloud's splats.  The
editor paints masks with a brush (``splatedit.app``); edit scripts describe
them with the shapes here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Sphere:
    """Ball of ``radius`` (model units) around ``center`` (3,)."""
    center: tuple[float, float, float]
    radius: float

    def mask(self, points: np.ndarray) -> np.ndarray:
        """(n,) bool: points (n, 3) within the closed ball."""
        d2 = ((np.asarray(points) - np.asarray(self.center)) ** 2).sum(axis=1)
        return d2 <= self.radius ** 2


@dataclass(frozen=True)
class Box:
    """Axis-aligned box with corners ``min`` <= ``max`` (3,) each."""
    min: tuple[float, float, float]
    max: tuple[float, float, float]

    def mask(self, points: np.ndarray) -> np.ndarray:
        """(n,) bool: points (n, 3) inside the closed box."""
        p = np.asarray(points)
        return ((p >= np.asarray(self.min)) & (p <= np.asarray(self.max))).all(axis=1)


@dataclass(frozen=True)
class Indices:
    """An explicit list of splat indices (0-based)."""
    indices: tuple[int, ...]

    def mask(self, points: np.ndarray) -> np.ndarray:
        """(n,) bool with True at the listed indices (all must be < n)."""
        m = np.zeros(len(points), dtype=bool)
        m[np.asarray(self.indices, dtype=np.int64)] = True
        return m


Region = Sphere | Box | Indices
