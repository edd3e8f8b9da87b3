"""What ``splatedit info`` reports about a cloud's cleanliness: outliers,
boundary splats, the largest splat relative to the median."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from splatedit.model.cloud import SplatCloud
from splatedit.model.outliers import OutlierFlags, detect_outliers
from splatedit.model.sizing import boundary_points, mesh_boundary_vertices, neighbour_indices
from splatedit.tolerances import SIZE_NEIGHBOURS


@dataclass(frozen=True)
class CloudQuality:
    """Counts over one cloud.

    Attributes:
        outliers: the :class:`~splatedit.model.outliers.OutlierFlags` of the positions.
        boundary: (n,) bool, splats on an open border (mesh: vertices of an
            edge used by one face; point cloud: neighbours leave an angular
            gap wider than ``BOUNDARY_GAP_DEG``).
        radius_max_rel_median: the largest splat radius over the median radius.
    """

    outliers: OutlierFlags
    boundary: np.ndarray
    radius_max_rel_median: float

    @property
    def boundary_count(self) -> int:
        return int(self.boundary.sum())


def assess(cloud: SplatCloud) -> CloudQuality:
    """Outliers, boundary splats and the radius spread of ``cloud``."""
    pts = cloud.positions
    tree = cKDTree(pts) if cloud.n > 1 else None
    flags = detect_outliers(pts, tree=tree)
    if cloud.faces is not None and len(cloud.faces):
        boundary = mesh_boundary_vertices(cloud.n, cloud.faces)
    elif cloud.n >= 3:
        nb = neighbour_indices(pts, min(SIZE_NEIGHBOURS, cloud.n), tree=tree)
        boundary = boundary_points(pts, cloud.normals, nb)
    else:
        boundary = np.zeros(cloud.n, dtype=bool)
    radii = cloud.radii
    return CloudQuality(flags, boundary, float(radii.max() / np.median(radii)))
