"""What ``splatedit info`` reports about a cloud's cleanliness: outliers,
boundary splats, the largest splat relative to the median."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from splatedit.model.cloud import SplatCloud
from splatedit.model.estimate import knn
from splatedit.model.outliers import OutlierFlags, detect_outliers, stray_clusters
from splatedit.model.sizing import boundary_points, mesh_boundary_vertices, neighbour_indices
from splatedit.tolerances import INFO_SAMPLE_POINTS, OUTLIER_NEIGHBOURS, SIZE_NEIGHBOURS


@dataclass(frozen=True)
class CloudQuality:
    """Counts over one cloud.

    Attributes:
        outliers: the :class:`~splatedit.model.outliers.OutlierFlags` of the positions.
        boundary: (n,) bool, splats on an open border (mesh: vertices of an
            edge used by one face; point cloud: neighbours leave an angular
            gap wider than ``BOUNDARY_GAP_DEG``).
        radius_max_rel_median: the largest splat radius over the median radius.
        stray_clusters: (n,) bool, points of small far pieces that are not
            already outliers (see :func:`~splatedit.model.outliers.stray_clusters`).
    """

    outliers: OutlierFlags
    boundary: np.ndarray
    radius_max_rel_median: float
    stray_clusters: np.ndarray

    @property
    def boundary_count(self) -> int:
        return int(self.boundary.sum())


def assess(cloud: SplatCloud) -> CloudQuality:
    """Outliers, boundary splats and the radius spread of ``cloud``."""
    pts = cloud.positions
    n = cloud.n
    radii = cloud.radii
    spread = float(radii.max() / np.median(radii))
    if n < 3:
        return CloudQuality(detect_outliers(pts), np.zeros(n, dtype=bool), spread, np.zeros(n, dtype=bool))
    # one k-NN query serves the outlier test and the boundary test
    dist, idx = knn(pts, max(SIZE_NEIGHBOURS, OUTLIER_NEIGHBOURS + 1))
    flags = detect_outliers(pts, distances=dist)
    if cloud.faces is not None and len(cloud.faces):
        boundary = mesh_boundary_vertices(n, cloud.faces)
    else:
        nb = neighbour_indices(pts, min(SIZE_NEIGHBOURS, n), neighbours=idx)
        boundary = boundary_points(pts, cloud.normals, nb)
    strays = stray_clusters(pts, flags.isolation_radius) & ~flags.mask
    return CloudQuality(flags, boundary, spread, strays)


@dataclass(frozen=True)
class QualityEstimate:
    """Figures of a large cloud estimated from spatial patches
    (:func:`splatedit.model.sample.patch_sample`): counts are the fraction
    among the exactly-known patch points times the cloud's size.

    Attributes:
        spacing: median nearest-neighbour distance at distinct positions (model units).
        boundary: estimated boundary splats (meshes: exact, from the faces).
        statistical, isolated, outliers: estimated outlier counts.
        sample_points: patch points whose neighbourhoods were known exactly.
    """

    spacing: float
    boundary: int
    statistical: int
    isolated: int
    outliers: int
    sample_points: int


def estimate_quality(cloud: SplatCloud, target: int = INFO_SAMPLE_POINTS,
                     lower=None) -> QualityEstimate | None:
    """:class:`QualityEstimate` of ``cloud`` without an all-points k-NN, or
    None when the patches give no usable points (then use :func:`assess`).
    ``lower``: the bounding box's lower corner, if known."""
    from splatedit.model.sample import patch_sample
    n = cloud.n
    ps = patch_sample(cloud.positions, target, lower=lower)
    if ps is None or len(ps.index) < 100:
        return None
    k = max(SIZE_NEIGHBOURS, OUTLIER_NEIGHBOURS + 1)
    dist, idx, exact = ps.knn(k)
    if exact.sum() < 100:
        return None
    pts = ps.tree.data
    d1 = dist[:, 1]
    use = exact & (d1 > 0)
    spacing = float(np.median(d1[use])) if use.any() else 0.0
    flags = detect_outliers(pts, distances=dist)
    m = int(exact.sum())
    scale = n / m
    stat = int(round(flags.statistical[exact].sum() * scale))
    iso = int(round(flags.isolated[exact].sum() * scale))
    both = int(round(flags.mask[exact].sum() * scale))
    if cloud.faces is not None and len(cloud.faces):
        boundary = int(mesh_boundary_vertices(n, cloud.faces).sum())
    else:
        sel = ps.index
        nrm = np.cross(cloud.u[sel], cloud.v[sel])
        nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
        nb = neighbour_indices(pts, min(SIZE_NEIGHBOURS, len(pts)), neighbours=idx)
        bnd = boundary_points(pts, nrm, nb)
        boundary = int(round(bnd[exact].sum() * scale))
    return QualityEstimate(spacing, boundary, stat, iso, both, m)


def scan_fields_present(cloud: SplatCloud) -> dict[str, bool]:
    """Which scanner dimensions carry data: ``{"intensity": ..., "classification": ...}``,
    True only when the cloud has the dimension and it is not all zero (a LAS
    point record always holds both: a file written from a scan without them
    has zeros there)."""
    return {name: arr is not None and bool(arr.any())
            for name, arr in (("intensity", cloud.intensity), ("classification", cloud.classification))}


def scan_fields_all_zero(cloud: SplatCloud) -> list[str]:
    """The scanner dimensions the cloud holds that are all zero (``info`` lists them)."""
    return [name for name, arr in (("intensity", cloud.intensity), ("classification", cloud.classification))
            if arr is not None and not arr.any()]
