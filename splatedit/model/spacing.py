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


def point_spacing(points: np.ndarray, tree: cKDTree | None = None, nearest=None) -> float:
    """Typical sample spacing: the median distance of every point to its
    nearest point at a *different* position (model units).

    Coincident points (an unwelded triangle soup stores every vertex several
    times) are looked through: the spacing is that of the distinct
    positions.  Returns 0.0 for fewer than 2 distinct points.  ``nearest``:
    the (n,) distances to the nearest other point if known (column 1 of a
    k-NN query that includes the point itself; saves the query).
    """
    pts = np.asarray(points, dtype=np.float64)
    if len(pts) < 2:
        return 0.0
    d = nearest_neighbour_distances(pts, 1, tree) if nearest is None else np.asarray(nearest)
    if (d > 0).mean() >= 0.5:       # the common case: few duplicates
        d = d[d > 0]
        return float(np.median(d)) if len(d) else 0.0
    distinct = np.unique(pts, axis=0)
    if len(distinct) < 2:
        return 0.0
    return float(np.median(nearest_neighbour_distances(distinct, 1)))
