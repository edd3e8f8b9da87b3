"""Point spacing from nearest neighbours (scipy.spatial.cKDTree)."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree


def nearest_neighbour_distances(points: np.ndarray, k: int = 1, tree: cKDTree | None = None) -> np.ndarray:
    """Distance of every point to its k-th nearest other point.

    Args:
        points: (n, 3) float64.
        k: which neighbour (1 = nearest), clamped to n - 1.
    Returns:
        (n,) float64 distances (model units); zeros when n == 1.
    """
    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    if n < 2:
        return np.zeros(n)
    k = min(k, n - 1)
    tree = cKDTree(pts) if tree is None else tree
    d, _ = tree.query(pts, k=k + 1, workers=-1)
    return d[:, k]


def point_spacing(points: np.ndarray, tree: cKDTree | None = None) -> float:
    """Typical sample spacing: the median nearest-neighbour distance (model units).

    Duplicate points (distance 0) are ignored; returns 0.0 for fewer than 2
    distinct points.
    """
    d = nearest_neighbour_distances(points, 1, tree)
    d = d[d > 0]
    return float(np.median(d)) if len(d) else 0.0
