"""Outlier points of scans: statistical and isolated.

* Statistical (as PCL's StatisticalOutlierRemoval and Open3D's
  ``remove_statistical_outlier``): the mean distance of every point to its
  ``OUTLIER_NEIGHBOURS`` nearest other points is compared with the
  distribution over all points; a point beyond the mean plus
  ``OUTLIER_STD_RATIO`` standard deviations is an outlier.  The statistics
  are taken of the logarithm of the distances, which makes the test
  independent of the scale and keeps regions that are merely sampled more
  sparsely (a constant factor, a shift in log space) inside the distribution
  (see the measurements in :mod:`splatedit.tolerances`).
* Isolated: no other point within ``ISOLATED_SPACINGS`` times the median
  nearest-neighbour distance.
* Stray clusters (:func:`stray_clusters`): small groups of points far from
  everything else (a LiDAR scan's birds, reflections, far-away debris), each
  point's neighbours being in its own group, so neither test above sees
  them: connected pieces of the k-nearest-neighbour graph cut at the
  isolation radius that hold at most ``STRAY_CLUSTER_MAX_REL`` of the
  points.  Used by ``convert --remove-outliers`` and ``info``, not by splat
  sizing (a mesh's small separate parts are surface).

Both only flag; :meth:`splatedit.model.cloud.SplatCloud.subset` removes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from splatedit.tolerances import (ESTIMATE_CHUNK_POINTS, ISOLATED_SPACINGS, OUTLIER_NEIGHBOURS,
                                  OUTLIER_STD_RATIO, STRAY_CLUSTER_MAX_REL)


@dataclass(frozen=True)
class OutlierFlags:
    """Which points are outliers.

    Attributes:
        statistical: (n,) bool, beyond the mean + ratio * std of the log mean
            neighbour distance.
        isolated: (n,) bool, no other point within the isolation radius.
        threshold: the mean neighbour distance above which a point is a
            statistical outlier (model units; inf when none can be).
        isolation_radius: the isolation radius (model units; inf when the
            spacing is 0).
    """

    statistical: np.ndarray
    isolated: np.ndarray
    threshold: float
    isolation_radius: float

    @property
    def mask(self) -> np.ndarray:
        """(n,) bool, statistical or isolated."""
        return self.statistical | self.isolated

    @property
    def count(self) -> int:
        """Number of outliers (statistical or isolated)."""
        return int(self.mask.sum())


def detect_outliers(points, k: int = OUTLIER_NEIGHBOURS, ratio: float = OUTLIER_STD_RATIO,
                    isolated_spacings: float = ISOLATED_SPACINGS, *,
                    tree: cKDTree | None = None, distances=None) -> OutlierFlags:
    """Flag statistical and isolated outliers.

    Args:
        points: (n, 3) float64 positions (model units).
        k: neighbours (other points) whose mean distance is tested, clamped
            to n - 1.
        ratio: standard deviations (of the log mean distance) above the mean.
        isolated_spacings: isolation radius in median nearest-neighbour
            distances (the median over points whose nearest neighbour is
            not a duplicate).
        tree: optional prebuilt ``cKDTree(points)``.
        distances: optional (n, >= k + 1) sorted distances of a k-NN query
            that includes the point itself (column 0), e.g. from
            :func:`splatedit.model.estimate.knn`; saves the query.
    Returns:
        :class:`OutlierFlags`; nothing is flagged for fewer than 3 points.
    """
    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    none = np.zeros(n, dtype=bool)
    if n < 3:
        return OutlierFlags(none, none.copy(), float("inf"), float("inf"))
    k = int(min(max(k, 1), n - 1))
    if distances is not None and distances.shape[1] >= k + 1:
        mean_d = distances[:, 1:k + 1].mean(axis=1)
        nearest = np.array(distances[:, 1])
    else:
        tree = cKDTree(pts) if tree is None else tree
        mean_d = np.empty(n)
        nearest = np.empty(n)
        step = 8 * ESTIMATE_CHUNK_POINTS
        for lo in range(0, n, step):
            d, _ = tree.query(pts[lo:lo + step], k=k + 1, workers=-1)
            mean_d[lo:lo + step] = d[:, 1:].mean(axis=1)
            nearest[lo:lo + step] = d[:, 1]
    pos = mean_d > 0
    statistical = none.copy()
    threshold = float("inf")
    if pos.sum() >= 3:
        logd = np.log(mean_d[pos])
        mu, sd = float(logd.mean()), float(logd.std())
        if sd > 0:
            threshold = float(np.exp(mu + ratio * sd))
            statistical = mean_d > threshold
    nz = nearest[nearest > 0]
    radius = float(isolated_spacings * np.median(nz)) if len(nz) else float("inf")
    isolated = nearest > radius
    return OutlierFlags(statistical, isolated, threshold, radius)


def stray_clusters(points, radius: float, *, k: int = OUTLIER_NEIGHBOURS,
                   max_fraction: float = STRAY_CLUSTER_MAX_REL, neighbours=None) -> np.ndarray:
    """(n,) bool: points of small pieces of the cloud, far from the rest.

    Args:
        points: (n, 3) float64 positions (model units).
        radius: edges of the k-nearest-neighbour graph longer than this
            (model units; the isolation radius of :func:`detect_outliers`)
            are cut.
        k: neighbours per point.
        max_fraction: pieces with at most this fraction of the points are
            strays; the largest piece never is.
        neighbours: optional (dist, idx), (n, >= k + 1) sorted distances and
            indices of a k-NN query that includes the point itself
            (:func:`splatedit.model.estimate.knn`); saves the query.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    out = np.zeros(n, dtype=bool)
    if n < 3 or not np.isfinite(radius):
        return out
    kk = int(min(k, n - 1))
    if neighbours is None:
        d, j = cKDTree(pts).query(pts, k=kk + 1, workers=-1)
    else:
        d, j = neighbours
    d, j = d[:, 1:kk + 1].ravel(), j[:, 1:kk + 1].ravel()
    i = np.repeat(np.arange(n), kk)
    keep = d <= radius
    graph = coo_matrix((np.ones(int(keep.sum()), np.int8), (i[keep], j[keep])), shape=(n, n))
    count, labels = connected_components(graph, directed=False)
    if count < 2:
        return out
    sizes = np.bincount(labels, minlength=count)
    small = sizes <= max_fraction * n
    small[np.argmax(sizes)] = False
    return small[labels]
