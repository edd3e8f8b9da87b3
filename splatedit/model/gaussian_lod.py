"""Level of detail of a Gaussian Splatting scene: a budgeted importance subset.

The editor draws a 3DGS scene's *most important* Gaussians while the camera
moves or a handle is dragged, as many as fit the frame budget, then all of
them when motion stops (:class:`splatedit.app.view.viewport.Viewport`).

Importance (view-independent) = opacity x sigma_1 sigma_2, the two largest
standard deviations: proportional to the opacity-weighted area of the
Gaussian's largest cross-section, i.e. to its projected area from a view
along its thinnest axis at any fixed distance.  The Gaussians are ranked once
(:func:`build_gaussian_lod`, in the background on open); the level of detail
of ``count`` Gaussians is the first ``count`` of that ranking, so one upload
in ranking order serves every budget (the renderer draws a prefix,
:meth:`GaussianRenderer.set_draw_count`).  The dropped Gaussians' coverage is
made up by drawing the kept ones' standard deviations ``(n / count) **
GS_LOD_COVER_EXP`` times larger (:meth:`GaussianLod.compensation`).

Why a subset and not a voxel merge by moment matching: the subset's
Gaussians *are* the scene's Gaussians (same index, same centre, covariance
and SH), so the live deformation applies to them row for row (their basis
rows are the scene's rows, :meth:`GaussianLod.rows`) and an edit or a commit
changes nothing in the ranking (it is by index; the subset of the new scene
is taken again).  The measured image difference against the full frame is in
docs/PERFORMANCE.md ("Gaussian level of detail").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from splatedit.errors import ParameterError
from splatedit.model.gaussians import GaussianCloud
from splatedit.tolerances import GS_LOD_COVER_EXP, GS_LOD_MAX_COMPENSATION, GS_LOD_MAX_FRACTION, GS_LOD_MIN_COUNT


def importance(scene: GaussianCloud) -> np.ndarray:
    """(n,) float64: opacity x product of the two largest standard deviations
    (model units squared) of every Gaussian (2DGS: its two axes)."""
    s = np.sort(scene.scales().astype(np.float64), axis=1)
    return scene.opacities().astype(np.float64) * s[:, -1] * s[:, -2]


def subset(scene: GaussianCloud, index: np.ndarray) -> GaussianCloud:
    """The Gaussians ``index`` (m,) int64 of ``scene`` in that order (the
    drawn arrays only: no unknown properties, no file layout)."""
    idx = np.asarray(index, dtype=np.int64)
    return GaussianCloud(positions=scene.positions[idx], log_scales=scene.log_scales[idx],
                         rotations=scene.rotations[idx], opacity_logits=scene.opacity_logits[idx],
                         sh=scene.sh[idx], normals=None if scene.normals is None else scene.normals[idx],
                         kind=scene.kind, name=f"{scene.name} (LOD)")


@dataclass(frozen=True)
class GaussianLod:
    """The ranking of a scene's Gaussians for its levels of detail.

    Attributes:
        n: Gaussians of the scene it was built for.
        order: (m,) int64 scene indices, most important first; m = the
            largest level (``GS_LOD_MAX_FRACTION`` of n, at least
            ``GS_LOD_MIN_COUNT``, at most n).
        rank: (n,) int64 position of every scene Gaussian in ``order``, -1
            for the Gaussians of no level.
        cumulative: (m,) float64 summed importance of the first 1..m ranked
            Gaussians (model units squared).
        total: summed importance of all n.
    """
    n: int
    order: np.ndarray
    rank: np.ndarray
    cumulative: np.ndarray
    total: float

    @property
    def m(self) -> int:
        return len(self.order)

    def fits(self, scene: GaussianCloud | None) -> bool:
        """The ranking indexes ``scene`` (same Gaussian count: the scene or an edit of it)."""
        return scene is not None and len(scene) == self.n

    def cloud(self, scene: GaussianCloud) -> GaussianCloud:
        """The largest level of ``scene`` (an edit of the ranked scene), in ranking order."""
        if not self.fits(scene):
            raise ParameterError("scene", f"has {len(scene)} Gaussians, the level of detail {self.n}")
        return subset(scene, self.order)

    def masks(self, *masks):
        """Scene masks (n,) bool (or None) restricted to the largest level, in ranking order."""
        return tuple(None if m is None else np.asarray(m, bool)[self.order] for m in masks)

    def rows(self, indices, *mats):
        """Deformation basis rows of the scene (``indices`` (N,) scene indices,
        ``mats`` (N, ...) arrays) for the level: the rows of its Gaussians,
        indices replaced by their ranking positions."""
        r = self.rank[np.asarray(indices, dtype=np.int64)]
        keep = r >= 0
        return (r[keep],) + tuple(np.asarray(a)[keep] for a in mats)

    def compensation(self, count: int) -> float:
        """Factor >= 1 on the standard deviations of the first ``count``
        Gaussians drawn instead of all n: (total importance / the first
        ``count``'s) ** GS_LOD_COVER_EXP, at most GS_LOD_MAX_COMPENSATION."""
        c = min(max(int(count), 1), self.m)
        kept = float(self.cumulative[c - 1])
        if c >= self.n or not kept > 0:
            return 1.0
        return float(min(max(self.total / kept, 1.0) ** GS_LOD_COVER_EXP, GS_LOD_MAX_COMPENSATION))


def build_gaussian_lod(scene: GaussianCloud, progress=None) -> GaussianLod:
    """Rank ``scene``'s Gaussians by :func:`importance` (ties: lower index
    first), keeping the largest level's; ``progress(stage, fraction)`` as
    :class:`splatedit.app.document.jobs.Job`'s (may raise to cancel)."""
    n = len(scene)
    if n == 0:
        raise ParameterError("scene", "has no Gaussians")
    m = min(n, max(GS_LOD_MIN_COUNT, int(GS_LOD_MAX_FRACTION * n)))
    imp = importance(scene)
    if progress is not None:
        progress("ranking Gaussians", 0.5)
    if m < n:
        top = np.argpartition(-imp, m - 1)[:m]
        order = top[np.lexsort((top, -imp[top]))]
    else:
        order = np.lexsort((np.arange(n), -imp))
    rank = np.full(n, -1, np.int64)
    rank[order] = np.arange(m)
    if progress is not None:
        progress("ranking Gaussians", 1.0)
    return GaussianLod(n, order.astype(np.int64), rank, np.cumsum(imp[order]), float(imp.sum()))
