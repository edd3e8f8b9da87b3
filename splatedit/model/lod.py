"""Levels of detail for interactive display: voxel-grid clustering with enlarged splats.

A level is built by clustering the splat centres on a voxel grid of cell size
``cell``.  Each cluster is shown by one *representative* splat: the member
closest to the cluster centroid, with its own position and orientation and
its tangent axes scaled by the smallest factor ``k >= 1`` such that the
enlarged ellipse covers every member of the cluster (each member's centre
projected onto the representative's plane, plus the member's own radius).
The level therefore keeps the surface hole-free wherever the full cloud was,
with about ``n * (spacing / cell)^2`` splats.

Because every LOD splat *is* a splat of the full cloud (same centre, axes
scaled by a constant), it deforms exactly like its representative: its
deformation-basis rows are the representative's rows (:meth:`LodLevel.rows`),
and its selection flags are the representative's (:meth:`LodLevel.masks`).

Levels are chosen by splat budget (:meth:`LodPyramid.level_for`), e.g. the
number of splats the device can draw within a frame-time budget.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from splatedit.model.cloud import SplatCloud
from splatedit.progress import report
from splatedit.tolerances import EDITOR_LOD_CELL_FACTOR, EDITOR_LOD_MIN_CELL_REL

PROGRESS_STAGE = "building levels of detail"
#: default splat budgets of the coarser levels (levels with more than half of
#: the model's splats are not built: the full model is used instead)
DEFAULT_BUDGETS = (400_000, 120_000, 40_000)
#: cap of the enlargement factor (guards against clusters bridging two sheets)
MAX_ENLARGE = 64.0


@dataclass
class LodLevel:
    """One level: ``cloud`` (m splats) shown instead of the full cloud (n).

    Attributes:
        cloud: the level's splats (representatives with enlarged axes).
        rep: (m,) int64, full-cloud index of each level splat's representative.
        cluster: (n,) int64, level splat index of every full-cloud splat.
        cell: voxel size used.
        scale: (m,) enlargement factors of the axes.
    """
    cloud: SplatCloud
    rep: np.ndarray
    cluster: np.ndarray
    cell: float
    scale: np.ndarray

    @property
    def n(self) -> int:
        return len(self.rep)

    def masks(self, *full_masks: np.ndarray) -> list[np.ndarray]:
        """Level masks of full-cloud masks (a level splat takes its representative's flag)."""
        return [np.asarray(m, bool)[self.rep] for m in full_masks]

    def rows(self, indices: np.ndarray, *bases: np.ndarray):
        """Basis rows for the level: ``indices`` (N,) sorted full-cloud indices
        with rows ``bases`` (each (N, k)).  Returns ``(level_indices,
        *level_bases)`` for the level splats whose representative is listed."""
        indices = np.asarray(indices, np.int64)
        pos = np.searchsorted(indices, self.rep)
        pos_c = np.minimum(pos, max(len(indices) - 1, 0))
        hit = (pos < len(indices)) & (indices[pos_c] == self.rep) if len(indices) else \
            np.zeros(self.n, bool)
        lvl = np.flatnonzero(hit)
        src = pos_c[lvl]
        return (lvl,) + tuple(np.ascontiguousarray(b[src]) for b in bases)

    def deformed(self, full_positions: np.ndarray, full_u: np.ndarray, full_v: np.ndarray) -> SplatCloud:
        """The level of a deformed full cloud (same clusters, axes re-scaled)."""
        s = self.scale[:, None]
        return SplatCloud(full_positions[self.rep], full_u[self.rep] * s, full_v[self.rep] * s,
                          self.cloud.colors, None, name=self.cloud.name)


def _cluster(positions: np.ndarray, cell: float) -> tuple[np.ndarray, int]:
    lo = positions.min(axis=0)
    q = np.floor((positions - lo) / cell).astype(np.int64)
    dims = q.max(axis=0) + 1
    key = (q[:, 0] * dims[1] + q[:, 1]) * dims[2] + q[:, 2]
    _, inv = np.unique(key, return_inverse=True)
    return inv.ravel(), int(inv.max()) + 1


def build_level(cloud: SplatCloud, cell: float) -> LodLevel:
    """Cluster ``cloud`` on a grid of ``cell`` and build the covering level."""
    p, u, v = cloud.positions, cloud.u, cloud.v
    n = len(p)
    inv, m = _cluster(p, cell)
    counts = np.bincount(inv, minlength=m).astype(np.float64)
    cen = np.stack([np.bincount(inv, weights=p[:, k], minlength=m) for k in range(3)], 1) / counts[:, None]
    d2 = ((p - cen[inv]) ** 2).sum(1)
    order = np.lexsort((d2, inv))
    first = np.ones(n, bool)
    first[1:] = inv[order][1:] != inv[order][:-1]
    rep = order[first]                      # sorted by cluster id
    # enlargement: member centres in the representative's (u, v) frame
    ru, rv = u[rep][inv], v[rep][inv]
    d = p - p[rep][inv]
    uu = (ru * ru).sum(1)
    vv = (rv * rv).sum(1)
    uv = (ru * rv).sum(1)
    du = (d * ru).sum(1)
    dv = (d * rv).sum(1)
    det = uu * vv - uv * uv
    s = (du * vv - dv * uv) / det
    t = (dv * uu - du * uv) / det
    ell = np.sqrt(s * s + t * t)
    rmem = np.maximum(np.linalg.norm(u, axis=1), np.linalg.norm(v, axis=1))
    rmin = np.minimum(np.sqrt(uu), np.sqrt(vv))
    need = ell + rmem / rmin
    starts = np.flatnonzero(first)             # group starts in ``order`` (sorted by cluster)
    k = np.maximum.reduceat(need[order], starts)
    k = np.clip(k, 1.0, MAX_ENLARGE)
    k[counts == 1] = 1.0
    colors = None if cloud.colors is None else cloud.colors[rep]
    lvl_cloud = SplatCloud(p[rep], u[rep] * k[:, None], v[rep] * k[:, None], colors, None,
                           name=cloud.name)
    return LodLevel(lvl_cloud, rep.astype(np.int64), inv.astype(np.int64), float(cell), k)


def level_for_budget(cloud: SplatCloud, budget: int, max_iter: int = 12,
                     cell: float | None = None) -> LodLevel:
    """A level with at most ``budget`` splats (grid cell grown until it fits).

    ``cell``: a first guess of the cell size (default: from the bounding box).
    Surface samples on a grid of cell ``c`` give about ``A / c^2`` clusters,
    so each retry rescales the cell by ``sqrt(count / budget)``.
    """
    lo, hi = cloud.bounds()
    ext = hi - lo
    if cell is None:
        # surface area from the splats (pi |u| |v| each, overlapping about twice)
        k = min(cloud.n, 100_000)
        sample = np.linspace(0, cloud.n - 1, k).astype(np.int64)
        disc = np.pi * np.linalg.norm(cloud.u[sample], axis=1) * np.linalg.norm(cloud.v[sample], axis=1)
        area = float(np.median(disc)) * cloud.n / 2.0
        cell = EDITOR_LOD_CELL_FACTOR * math.sqrt(max(area, 1e-30) / max(budget, 1))
    cell = max(cell, float(np.linalg.norm(ext)) * EDITOR_LOD_MIN_CELL_REL)
    level = build_level(cloud, cell)
    it = 0
    while level.n > budget and it < max_iter:
        cell *= max(math.sqrt(level.n / budget) * 1.02, 1.05)
        level = build_level(cloud, cell)
        it += 1
    return level


def _compose(fine: LodLevel, coarse: LodLevel, source: SplatCloud) -> LodLevel:
    """A level of ``source`` from a level ``coarse`` built on ``fine.cloud``."""
    rep = fine.rep[coarse.rep]
    scale = fine.scale[coarse.rep] * coarse.scale
    cl = coarse.cloud
    return LodLevel(cl, rep, coarse.cluster[fine.cluster], coarse.cell, scale)


class LodPyramid:
    """Coarser levels of a cloud, finest first (the full cloud is not a level)."""

    def __init__(self, cloud: SplatCloud, budgets=DEFAULT_BUDGETS, progress=None):
        """Each level is clustered from the next finer level's splats (whose
        enlarged axes already cover their members), so a coarse level costs
        a fraction of clustering the full cloud; the cell size of the next
        level is predicted from the previous one (count ~ 1 / cell^2)."""
        self.source = cloud
        self.levels: list[LodLevel] = []
        budgets = sorted((b for b in budgets if b <= cloud.n // 2), reverse=True)
        prev, cell = None, None
        for i, b in enumerate(budgets):
            report(progress, PROGRESS_STAGE, i / max(len(budgets), 1))
            if prev is not None:
                cell = prev.cell * math.sqrt(prev.n / b) * 1.02
            base = cloud if prev is None else prev.cloud
            lvl = level_for_budget(base, b, cell=cell)
            if prev is not None:
                lvl = _compose(prev, lvl, cloud)
            self.levels.append(lvl)
            prev = lvl
        report(progress, PROGRESS_STAGE, 1.0)

    def level_for(self, max_splats: int) -> LodLevel | None:
        """The finest level with at most ``max_splats`` splats; None when the
        full cloud fits; the coarsest level when nothing fits."""
        if self.source.n <= max_splats or not self.levels:
            return None
        for lvl in self.levels:
            if lvl.n <= max_splats:
                return lvl
        return self.levels[-1]
