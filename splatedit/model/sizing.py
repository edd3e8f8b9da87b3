"""Robust splat sizes: a cap relative to the neighbours' sizes, boundary-aware.

The spacing rules of :mod:`splatedit.model.estimate` (k-th neighbour distance)
and :mod:`splatedit.model.mesh` (longest incident edge) give a splat the size
of the largest gap next to it.  That closes the surface, but two kinds of
points get far too large a disc:

* stray points (scanner outliers, unreferenced mesh vertices): their nearest
  neighbours are far away, so their disc is many times the size of any
  surface splat;
* boundary points (open mesh borders, the edge of a scan): all their
  neighbours lie on one side, and long sliver triangles along a border give
  their corners huge discs that overhang the border as flaps.

:func:`limit_radii` caps every radius at ``SIZE_CAP_REL_NEIGHBOURS`` times
the median radius of the point's neighbours (a robust local spacing: one
stray neighbour does not move a median) and a boundary splat at
``BOUNDARY_CAP_REL_NEIGHBOURS`` times it; :func:`limit_outlier_radii` keeps
outliers (:mod:`splatedit.model.outliers`), which may sit in clusters whose
neighbours are strays too, at most ``OUTLIER_RADIUS_REL_MEDIAN`` times the
median radius of their neighbours that are not outliers; :func:`settle_radii`
then applies the neighbour cap again against the radii those caps left (a
splat next to shrunk ones is capped at their new median), so that no splat
ends more than ``SIZE_CAP_REL_NEIGHBOURS`` times its neighbours as drawn.
Boundary points of a point cloud
are found by :func:`boundary_points` (angular gap of the neighbours projected
into the tangent plane, as PCL's BoundaryEstimation does), those of a mesh by
:func:`mesh_border_ring` (vertices of the faces that touch an edge used by a
single face).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from splatedit.tolerances import (BOUNDARY_CAP_REL_NEIGHBOURS, BOUNDARY_GAP_DEG,
                                  ESTIMATE_CHUNK_POINTS, OUTLIER_RADIUS_REL_MEDIAN,
                                  SIZE_CAP_REL_NEIGHBOURS, SIZE_NEIGHBOURS,
                                  SIZE_SETTLE_ROUNDS)


def neighbour_indices(points, k: int = SIZE_NEIGHBOURS, *, tree: cKDTree | None = None,
                      neighbours=None) -> np.ndarray:
    """The k - 1 nearest other points of every point.

    Args:
        points: (n, 3) float64 positions (model units).
        k: neighbourhood size including the point itself, clamped to n.
        neighbours: optional (n, >= k) int64 indices of a k-NN query that
            includes the point itself (:func:`splatedit.model.estimate.knn`).
    Returns:
        (n, k - 1) integer indices (int64, or the dtype of ``neighbours``:
        int32 from a compact :func:`knn`; a view of ``neighbours``
        when every row starts with its own point); the point itself is left
        out even when duplicates of it came first.
    """
    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    k = int(min(max(k, 2), n))
    if neighbours is None or neighbours.shape[1] < k:
        tree = cKDTree(pts) if tree is None else tree
        neighbours = np.empty((n, k), dtype=np.int64)
        step = 8 * ESTIMATE_CHUNK_POINTS
        for lo in range(0, n, step):
            neighbours[lo:lo + step] = tree.query(pts[lo:lo + step], k=k, workers=-1)[1]
    idx = np.asarray(neighbours[:, :k])
    if idx.dtype.kind not in "iu":
        idx = idx.astype(np.int64)
    odd = np.flatnonzero(idx[:, 0] != np.arange(n))
    if len(odd) == 0:                            # the usual case: the point itself comes first
        return idx[:, 1:]                        # a view: no (n, k - 1) copy
    out = idx[:, 1:].copy()
    if len(odd):                                 # a duplicate came first: drop the point's own entry
        sub = idx[odd]
        is_self = sub == odd[:, None]
        col = np.where(is_self.any(axis=1), is_self.argmax(axis=1), k - 1)
        keep = np.arange(k)[None, :] != col[:, None]
        out[odd] = sub[keep].reshape(len(odd), k - 1)
    return out


def _row_median(values: np.ndarray) -> np.ndarray:
    """Median of every row of a (c, m) array (``np.partition``, faster than
    ``np.median`` for short rows)."""
    m = values.shape[1]
    if m % 2:
        return np.partition(values, m // 2, axis=1)[:, m // 2]
    part = np.partition(values, [m // 2 - 1, m // 2], axis=1)
    return 0.5 * (part[:, m // 2 - 1] + part[:, m // 2])


def largest_angular_gap(points, normals, neighbours, *, query=None) -> np.ndarray:
    """Widest angle between consecutive neighbours around each point.

    The neighbour offsets are projected into the point's tangent plane and
    sorted by angle; an interior point of a well-sampled surface is surrounded
    (gaps well below 180 degrees), a point on a border has an empty half-plane.

    Args:
        points: (n, 3) float64; normals: (n, 3) float64 unit normals.
        neighbours: (n, m) int64 indices of other points (m >= 2).
        query: optional (q,) indices of the points to test (default all).
    Returns:
        (n,) (or (q,)) float64 radians in (0, 2 pi]; 2 pi where all
        neighbours project onto the point or onto one ray.
    """
    allp = np.asarray(points, dtype=np.float64)
    if query is None:
        pts, nrm = allp, np.asarray(normals, dtype=np.float64)
    else:
        query = np.asarray(query, dtype=np.int64)
        pts, nrm = allp[query], np.asarray(normals, dtype=np.float64)[query]
        neighbours = neighbours[query]
    n = len(pts)
    out = np.full(n, 2.0 * np.pi)
    # any tangent frame will do: the gaps do not depend on where angles start
    axis = np.eye(3)[np.argmin(np.abs(nrm), axis=1)]
    t1 = np.cross(nrm, axis)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(nrm, t1)
    step = ESTIMATE_CHUNK_POINTS
    for lo in range(0, n, step):
        d = allp[neighbours[lo:lo + step]] - pts[lo:lo + step, None, :]      # (c, m, 3)
        x = np.einsum("cmj,cj->cm", d, t1[lo:lo + step])
        y = np.einsum("cmj,cj->cm", d, t2[lo:lo + step])
        ok = (x != 0) | (y != 0)                  # not coincident in the tangent plane
        ang = np.where(ok, np.arctan2(y, x), np.inf)
        ang.sort(axis=1)                          # coincident ones last
        valid = ok.sum(axis=1)
        gaps = np.diff(ang, axis=1)               # consecutive gaps; inf - x past the valid ones
        gaps[np.arange(gaps.shape[1])[None, :] >= valid[:, None] - 1] = -np.inf
        rows = np.arange(len(d))
        last = np.maximum(valid - 1, 0)
        wrap = ang[:, 0] + 2.0 * np.pi - ang[rows, last]
        g = np.maximum(gaps.max(axis=1, initial=-np.inf), wrap)
        out[lo:lo + step] = np.where(valid >= 2, g, 2.0 * np.pi)
    return out


def boundary_points(points, normals, neighbours, gap_deg: float = BOUNDARY_GAP_DEG, *,
                    query=None) -> np.ndarray:
    """(n,) (or (q,)) bool: points whose neighbours leave an angular gap wider
    than ``gap_deg`` degrees in the tangent plane (see
    :func:`largest_angular_gap`; arguments as there)."""
    return largest_angular_gap(points, normals, neighbours, query=query) > np.radians(gap_deg)


def mesh_boundary_vertices(n_vertices: int, faces) -> np.ndarray:
    """(n,) bool: vertices on a border edge (an edge used by exactly one face).

    Args:
        n_vertices: number of vertices n.
        faces: (f, 3) int64 triangles.
    """
    F = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    out = np.zeros(n_vertices, dtype=bool)
    if len(F) == 0:
        return out
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    e.sort(axis=1)
    key = e[:, 0] * np.int64(n_vertices) + e[:, 1]
    uniq, count = np.unique(key, return_counts=True)
    border = uniq[count == 1]
    out[border // n_vertices] = True
    out[border % n_vertices] = True
    return out


def mesh_border_ring(n_vertices: int, faces) -> np.ndarray:
    """(n,) bool: the vertices of every face that has a vertex on a border edge
    (:func:`mesh_boundary_vertices` and the ring of vertices inside it).  A
    strip of sliver triangles along a border gives the vertices of that inner
    ring long edges too, so they are sized as boundary splats.
    """
    F = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    border = mesh_boundary_vertices(n_vertices, F)
    out = border.copy()
    if border.any():
        out[F[border[F].any(axis=1)].ravel()] = True
    return out


def neighbour_median(radii, neighbours) -> np.ndarray:
    """(n,) float64: the median of ``radii`` over every point's neighbours
    ((n, m) int64 indices, m >= 1)."""
    r = np.asarray(radii, dtype=np.float64)
    local = np.empty(len(r))
    step = ESTIMATE_CHUNK_POINTS
    for lo in range(0, len(r), step):
        local[lo:lo + step] = _row_median(r[neighbours[lo:lo + step]])
    return local


def limit_radii(radii, neighbours, boundary=None, *, cap: float = SIZE_CAP_REL_NEIGHBOURS,
                boundary_cap: float = BOUNDARY_CAP_REL_NEIGHBOURS, local=None) -> np.ndarray:
    """Cap radii relative to the median radius of each point's neighbours.

    Args:
        radii: (n,) float64 radii from a spacing rule (model units).
        neighbours: (n, m) int64 indices of other points (m >= 1), e.g. from
            :func:`neighbour_indices`.
        boundary: optional (n,) bool, points that get ``boundary_cap``.
        cap, boundary_cap: multiples of the neighbours' median radius.
        local: optional (n,) :func:`neighbour_median` of ``radii``.
    Returns:
        (n,) float64, ``min(radii, cap * median(radii[neighbours]))``
        (``boundary_cap`` for boundary points); never larger than ``radii``.
    """
    r = np.asarray(radii, dtype=np.float64)
    if len(r) < 2 or neighbours.shape[1] == 0:
        return r.copy()
    local = neighbour_median(r, neighbours) if local is None else local
    limit = cap * local
    if boundary is not None:
        limit = np.where(boundary, np.minimum(limit, boundary_cap * local), limit)
    return np.minimum(r, limit)


def settle_radii(radii, neighbours, changed, *, cap: float = SIZE_CAP_REL_NEIGHBOURS,
                 rounds: int = SIZE_SETTLE_ROUNDS) -> np.ndarray:
    """Make the neighbour cap hold against the final sizes.

    :func:`limit_radii` caps a radius relative to its neighbours' radii as
    the spacing rule gave them; the caps then shrink some of those neighbours
    (strays, boundary splats, outliers), so a splat that kept its size can
    end many times larger than the neighbours as drawn (a rotating sensor's
    multipath ghosts and near-sensor dust: up to 13.6x, where only some of a
    cluster are flagged as outliers).  Here every splat next to one that
    shrank is capped again at ``cap`` times the median of its neighbours'
    current radii, round after round while any shrinks (each round only looks
    at the neighbours of the splats that shrank in the one before).  Radii
    only go down, and only where a splat is more than ``cap`` times its
    neighbours' median, which a well-sampled surface never is (see
    ``SIZE_CAP_REL_NEIGHBOURS``).

    Args:
        radii: (n,) float64 radii after the caps (model units).
        neighbours: (n, m) integer indices of other points (m >= 1).
        changed: (n,) bool, the splats whose radius the caps reduced.
        cap: multiple of the neighbours' median radius.
        rounds: at most this many rounds.
    Returns:
        (n,) float64 radii, never larger than ``radii``.
    """
    r = np.array(radii, dtype=np.float64)
    changed = np.asarray(changed, dtype=bool)
    n = len(r)
    if n < 2 or neighbours.shape[1] == 0:
        return r
    step = 8 * ESTIMATE_CHUNK_POINTS
    for _ in range(rounds):
        if not changed.any():
            break
        near = np.concatenate([np.flatnonzero(changed[neighbours[lo:lo + step]].any(axis=1)) + lo
                               for lo in range(0, n, step)])
        local = np.empty(len(near))
        for lo in range(0, len(near), ESTIMATE_CHUNK_POINTS):
            local[lo:lo + ESTIMATE_CHUNK_POINTS] = _row_median(
                r[neighbours[near[lo:lo + ESTIMATE_CHUNK_POINTS]]])
        over = r[near] > cap * local
        changed = np.zeros(n, dtype=bool)
        changed[near[over]] = True
        r[near[over]] = cap * local[over]
    return r


def limit_outlier_radii(radii, outliers, neighbours,
                        rel: float = OUTLIER_RADIUS_REL_MEDIAN) -> np.ndarray:
    """Cap the radii of outliers relative to the surface splats next to them.

    An outlier's radius is at most ``rel`` times the median radius of its
    neighbours that are not outliers themselves, or, when all its neighbours
    are outliers (a cluster of strays), of all the points that are not.

    Args:
        radii: (n,) float64 radii (model units).
        outliers: (n,) bool, e.g. :attr:`splatedit.model.outliers.OutlierFlags.mask`.
        neighbours: (n, m) int64 indices of other points.
    Returns:
        (n,) float64, unchanged where ``outliers`` is False or when every
        point is an outlier.
    """
    r = np.array(radii, dtype=np.float64)
    mask = np.asarray(outliers, dtype=bool)
    if not mask.any() or mask.all():
        return r
    idx = np.flatnonzero(mask)
    nb = neighbours[idx]
    vals = np.where(mask[nb], np.nan, r[nb])
    some = ~np.isnan(vals).all(axis=1)
    local = np.full(len(idx), float(np.median(r[~mask])))
    if some.any():
        local[some] = np.nanmedian(vals[some], axis=1)
    r[idx] = np.minimum(r[idx], rel * local)
    return r
