"""Splats from bare points: PCA normals, MST orientation, hole-free sizing.

* :func:`estimate_normals` fits a plane to the k nearest neighbours of every
  point (Hoppe et al. 1992, "Surface reconstruction from unorganized points"):
  the normal is the eigenvector of the smallest eigenvalue of the 3x3
  neighbourhood covariance, solved in closed form for all points at once
  (:mod:`splatedit.model.pca`; 5x faster than batched ``np.linalg.eigh``).
* :func:`orient_normals` (:mod:`splatedit.model.orient`) makes the signs
  consistent by propagating along Hoppe's minimum spanning tree of the k-NN
  graph with edge weight ``1 - |n_i . n_j|``, in chunks of bounded memory.
* :func:`estimate_splats` finds all neighbours at once with the exact tiled
  k-NN of :mod:`splatedit.model.tiles` (small k-d trees per tile instead of
  one over the whole cloud).
* :func:`splat_axes` builds an orthonormal tangent frame scaled to a radius
  that closes the surface (see :func:`splat_radii`), capped relative to the
  neighbours' radii and at boundaries (:mod:`splatedit.model.sizing`).
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from scipy.spatial import cKDTree

from splatedit.errors import ParameterError
from splatedit.model.cloud import SplatCloud, column_bounds, min_axis_lengths
from splatedit.model.orient import orient_normals
from splatedit.model.outliers import detect_outliers
from splatedit.model.pca import morton_codes, neighbourhood_covariances, smallest_eigenvectors
from splatedit.model.sizing import (boundary_points, limit_outlier_radii, limit_radii,
                                    neighbour_indices, neighbour_median, settle_radii)
from splatedit.model.neighbours import as_points as _points
from splatedit.model.neighbours import knn  # noqa: F401  (part of this module's API)
from splatedit.model.spacing import nearest_neighbour_distances
from splatedit.model.tangents import tangent_frame
from splatedit.model.tiles import tiled_knn
from splatedit.progress import report
from splatedit.tolerances import (BOUNDARY_CAP_REL_NEIGHBOURS, ESTIMATE_CHUNK_POINTS,
                                  FALLBACK_SPLAT_RADIUS, MIN_SPLAT_RADIUS_REL_MEDIAN, NORMAL_NEIGHBOURS,
                                  ORIENT_NEIGHBOURS,
                                  OUTLIER_NEIGHBOURS, SIZE_NEIGHBOURS, SPACING_NEIGHBOUR,
                                  SPLAT_RADIUS_FACTOR)


def estimate_normals(points, k: int = NORMAL_NEIGHBOURS, *, tree: cKDTree | None = None,
                     query=None, neighbours=None, progress=None) -> np.ndarray:
    """Unoriented PCA normals.

    Args:
        points: (n, 3) float64 positions (model units).
        k: neighbourhood size including the point itself, clamped to n.
        tree: optional prebuilt ``cKDTree(points)``.
        query: optional (m,) indices; only their normals are computed.
        neighbours: optional (m, >= k) int64 neighbour indices from
            :func:`knn` (saves the k-d tree query).
        progress: optional progress callback (stage ``"estimating normals"``).
    Returns:
        (n, 3) (or (m, 3) with ``query``) float64 unit normals, signs arbitrary.
    """
    pts = _points(points)
    n = len(pts)
    idx_q = np.arange(n) if query is None else np.asarray(query, dtype=np.int64)
    out = np.zeros((len(idx_q), 3))
    if n == 0 or len(idx_q) == 0:
        return out
    if n < 3:
        out[:, 2] = 1.0
        return out
    k = int(min(max(k, 3), n))
    if neighbours is None or neighbours.shape[1] < k:
        _, neighbours = knn(pts, k, tree=tree, query=idx_q, progress=progress)
    step = ESTIMATE_CHUNK_POINTS

    def chunk(lo):
        nbi = neighbours[lo:lo + step, :k]
        cov = neighbourhood_covariances(pts, nbi, centres=pts[idx_q[lo:lo + step]])
        out[lo:lo + step] = smallest_eigenvectors(cov)
        return lo + len(nbi)

    # chunks on a thread pool: numpy's gathers and loops run without the GIL
    starts = range(0, len(idx_q), step)
    with ThreadPoolExecutor(min(os.cpu_count() or 1, len(starts))) as pool:
        for end in pool.map(chunk, starts):
            report(progress, "estimating normals", end / len(idx_q))
    return out


def splat_radii(points, k: int = SPACING_NEIGHBOUR, factor: float = SPLAT_RADIUS_FACTOR, *,
                tree: cKDTree | None = None, query=None, distances=None) -> np.ndarray:
    """Splat radius of every point: ``factor`` * distance to its k-th neighbour.

    Why this closes the surface: a hole at a surface point x means no splat
    centre within its splat radius of x, i.e. x is the centre of an empty
    circle larger than the radii of the samples around it.  The k-th-neighbour
    distance d_k is the radius of the smallest disc around a sample holding k
    others; with k = 6 (the valence of a regular triangulation) those
    neighbours surround the sample, so d_k tracks the size of the empty
    circles (Delaunay circumcircles) next to it.  For a hexagonal lattice of
    spacing h, d_6 = h and the largest gap (covering radius) is h / sqrt(3),
    a 1.7x margin at factor 1; for a square grid d_6 = sqrt(2) h against
    h / sqrt(2), 2x.  Uniformly random samples are the hard case: their large
    empty circles need factor 1.3 (the worst of 12 random sphere samples of
    1k-200k points); the default SPLAT_RADIUS_FACTOR = 1.5 keeps a margin and
    ``test_estimated_splats_cover_sphere`` checks a dense random sample of the
    surface is covered.  (No fixed factor is a proof for random samples: the
    extreme gaps grow slowly with n.)  Degenerate radii (duplicates) get the
    median radius.

    Args:
        points: (n, 3) float64 positions (model units).
        query: optional (m,) indices of the points whose radius is wanted.
        distances: optional (m, >= k + 1) sorted neighbour distances from
            :func:`knn` (column 0 is the point itself).
    Returns:
        (n,) (or (m,)) float64 radii (model units), all > 0.
    """
    pts = _points(points)
    n = len(pts)
    idx_q = np.arange(n) if query is None else np.asarray(query, dtype=np.int64)
    if n < 2:
        return np.full(len(idx_q), FALLBACK_SPLAT_RADIUS)
    k = int(min(k, n - 1))
    if distances is None or distances.shape[1] < k + 1:
        distances, _ = knn(pts, k + 1, tree=tree, query=idx_q)
    r = distances[:, k].astype(np.float64) * factor
    ok = r[np.isfinite(r) & (r > 0)]
    if len(ok) == 0:
        allr = nearest_neighbour_distances(pts, k, tree or cKDTree(pts)) * factor
        allr = allr[allr > 0]
        med = float(np.median(allr)) if len(allr) else FALLBACK_SPLAT_RADIUS
    else:
        med = float(np.median(ok))
    bad = ~(r > MIN_SPLAT_RADIUS_REL_MEDIAN * med)
    r[bad] = med
    return r


def robust_splat_radii(points, normals, *, tree: cKDTree | None = None, distances=None,
                       neighbours=None) -> np.ndarray:
    """Hole-free splat radii (:func:`splat_radii`) with strays and borders tamed.

    Every radius is capped at ``SIZE_CAP_REL_NEIGHBOURS`` times the median
    radius of its ``SIZE_NEIGHBOURS - 1`` nearest neighbours, and the radius
    of a boundary point (:func:`splatedit.model.sizing.boundary_points`) at
    ``BOUNDARY_CAP_REL_NEIGHBOURS`` times it, and the radius of an outlier
    (:func:`splatedit.model.outliers.detect_outliers`) at
    ``OUTLIER_RADIUS_REL_MEDIAN`` times the median radius of its neighbours
    that are not outliers; finally the first cap is applied again against
    these radii (:func:`splatedit.model.sizing.settle_radii`), so a splat
    next to shrunk ones is at most ``SIZE_CAP_REL_NEIGHBOURS`` times their
    median too (see :mod:`splatedit.model.sizing`).

    Args:
        points: (n, 3) float64 positions; normals: (n, 3) float64 unit normals.
        distances, neighbours: optional (n, >= SIZE_NEIGHBOURS) sorted
            distances and indices from :func:`knn` (the point itself included).
    Returns:
        (n,) float64 radii (model units), all > 0.
    """
    pts = _points(points)
    n = len(pts)
    if n < 3:
        return splat_radii(pts, tree=tree, distances=distances)
    k = min(max(SIZE_NEIGHBOURS, SPACING_NEIGHBOUR + 1), n)
    if distances is None or neighbours is None or neighbours.shape[1] < k \
            or distances.shape[1] < SPACING_NEIGHBOUR + 1:
        distances, neighbours = knn(pts, k, tree=tree)
    r = splat_radii(pts, tree=tree, distances=distances)
    nb = neighbour_indices(pts, min(SIZE_NEIGHBOURS, n), neighbours=neighbours)
    local = neighbour_median(r, nb)
    # only a splat above the boundary cap can be changed by it: test just those
    test = np.flatnonzero(r > BOUNDARY_CAP_REL_NEIGHBOURS * local)
    boundary = np.zeros(n, dtype=bool)
    for lo in range(0, len(test), ESTIMATE_CHUNK_POINTS):     # its (m, k, 3) gathers in chunks
        part = test[lo:lo + ESTIMATE_CHUNK_POINTS]
        boundary[part] = boundary_points(pts, normals, nb, query=part)
    first = r
    r = limit_radii(r, nb, boundary, local=local)
    r = limit_outlier_radii(r, detect_outliers(pts, tree=tree, distances=distances).mask, nb)
    return settle_radii(r, nb, r < first)


def splat_axes(points, normals, *, radius=None, tree: cKDTree | None = None,
               distances=None, neighbours=None, progress=None) -> tuple[np.ndarray, np.ndarray]:
    """Circular splats: tangent axes ``(u, v)`` of length ``radius``.

    Args:
        points: (n, 3) float64 positions (model units).
        normals: (n, 3) float64 normals (normalised here; u x v points along them).
        radius: None (estimate with :func:`robust_splat_radii`), a scalar, or
            (n,) float64 radii in model units.
        distances, neighbours: optional (n, >= SIZE_NEIGHBOURS) distances and
            indices from :func:`knn`.
    Returns:
        u, v: (n, 3) float64, orthogonal, ``|u| = |v| = radius``,
        ``normalize(u x v) = normal``.
    """
    pts = _points(points)
    nrm = np.asarray(normals, dtype=np.float64)
    if nrm.shape != pts.shape:
        raise ParameterError("normals", f"expected shape {pts.shape}, got {nrm.shape}")
    report(progress, "sizing splats", 0.0)
    nrm = nrm / np.linalg.norm(nrm, axis=1, keepdims=True)
    if radius is None:
        r = robust_splat_radii(pts, nrm, tree=tree, distances=distances, neighbours=neighbours)
    else:
        r = np.broadcast_to(np.asarray(radius, dtype=np.float64), (len(pts),))
    t1, t2 = tangent_frame(nrm)
    report(progress, "sizing splats", 1.0)
    return t1 * r[:, None], t2 * r[:, None]


def fill_missing_normals(points, normals, *, tree: cKDTree | None = None,
                         neighbours=None) -> np.ndarray:
    """Normalise ``normals`` and replace zero-length or non-finite rows by PCA
    normals (:func:`estimate_normals`) turned to agree with the nearest point
    that has a valid normal (when no row is valid, all are estimated and
    oriented by :func:`orient_normals`).

    Args:
        points: (n, 3) float64 positions; normals: (n, 3) float64.
        neighbours: optional (n, >= NORMAL_NEIGHBOURS) k-NN indices of
            ``points`` (the point itself included), e.g. from
            :func:`splatedit.model.tiles.tiled_knn`: no k-d tree over all points.
    Returns:
        a new (n, 3) float64 array of unit normals.
    """
    pts = _points(points)
    nrm = np.asarray(normals, dtype=np.float64)
    ln = np.linalg.norm(nrm, axis=1)
    good = np.isfinite(ln) & (ln > 0)
    out = np.array(nrm, dtype=np.float64)
    out[good] /= ln[good, None]
    if good.all():
        return out
    if neighbours is not None and neighbours.shape[1] < NORMAL_NEIGHBOURS:
        neighbours = None
    if not good.any():
        return orient_normals(pts, estimate_normals(pts, tree=tree, neighbours=neighbours),
                              tree=tree, neighbours=neighbours)
    bad = np.flatnonzero(~good)
    est = estimate_normals(pts, tree=tree, query=bad,
                           neighbours=None if neighbours is None else neighbours[bad])
    gidx = np.flatnonzero(good)
    _, j = cKDTree(pts[gidx]).query(pts[bad], workers=-1)
    ref = out[gidx[j]]
    s = np.where(np.einsum("ij,ij->i", est, ref) < 0, -1.0, 1.0)
    out[bad] = est * s[:, None]
    return out


def estimate_splats(points, normals=None, colors=None, progress=None, *, radius=None,
                    faces=None, name: str = "", source: str | None = None) -> SplatCloud:
    """A :class:`SplatCloud` from points and whatever attributes are known.

    Args:
        points: (n, 3) float64 positions (model units).
        normals: optional (n, 3) normals; when None they are estimated
            (:func:`estimate_normals`) and oriented (:func:`orient_normals`).
            Zero-length rows are filled with PCA normals.
        colors: optional (n, 4) uint8 RGBA.
        radius: optional scalar or (n,) splat radii (model units); default
            from neighbour spacing (:func:`robust_splat_radii`).
        faces: optional (f, 3) int64 triangles, kept as they are.
    Returns:
        SplatCloud with circular splats.
    """
    pts = _points(points)
    n = len(pts)
    # Work in Morton order (cache-local queries and gathers: 2x faster k-NN
    # at 1M points); the results go back to the caller's order at the end.
    codes, lo, scale = morton_codes(pts)
    order = np.argsort(codes, kind="stable") if n > 1 else np.arange(n)
    codes = codes[order]
    sp = pts[order]
    dist = nb = None
    if n > 1 and (radius is None or normals is None):
        kmax = max(SPACING_NEIGHBOUR + 1, SIZE_NEIGHBOURS)
        if normals is None:
            kmax = max(NORMAL_NEIGHBOURS, ORIENT_NEIGHBOURS + 1, kmax)
        dist, nb = tiled_knn(sp, codes, lo, scale, kmax, progress=progress,
                             dist_columns=max(SPACING_NEIGHBOUR, OUTLIER_NEIGHBOURS) + 1)
        _self_first(nb)
    del codes
    if normals is None:
        nrm = estimate_normals(sp, neighbours=nb, progress=progress)
        nrm = orient_normals(sp, nrm, neighbours=nb, progress=progress, inplace=True)
    else:
        nrm = np.asarray(normals, dtype=np.float64)
        if nrm.shape != pts.shape:
            raise ParameterError("normals", f"expected shape {pts.shape}, got {nrm.shape}")
        nrm = fill_missing_normals(sp, nrm[order], neighbours=nb)
    report(progress, "sizing splats", 0.0)
    for lo_i in range(0, n, ESTIMATE_CHUNK_POINTS):
        part = nrm[lo_i:lo_i + ESTIMATE_CHUNK_POINTS]
        part /= np.linalg.norm(part, axis=1, keepdims=True)
    if radius is None:
        r = robust_splat_radii(sp, nrm, distances=dist, neighbours=nb)
        # a far stray point's radius is capped by its neighbours' (the main
        # body's): at least twice what the cloud's validation requires there
        lo_b, hi_b = column_bounds(sp)
        diag = float(np.linalg.norm(hi_b - lo_b))
        for lo_i in range(0, n, ESTIMATE_CHUNK_POINTS):
            part = r[lo_i:lo_i + ESTIMATE_CHUNK_POINTS]
            np.maximum(part, 2.0 * min_axis_lengths(sp[lo_i:lo_i + ESTIMATE_CHUNK_POINTS], diag), out=part)
    elif np.ndim(radius) == 1:
        r = np.asarray(radius, dtype=np.float64)[order]
    else:
        r = np.broadcast_to(np.asarray(radius, dtype=np.float64), (n,))
    del dist, nb, sp
    # the frames chunk by chunk, straight into the caller's order
    u = np.empty((n, 3))
    v = np.empty((n, 3))
    step = 8 * ESTIMATE_CHUNK_POINTS
    for lo_i in range(0, n, step):
        t1, t2 = tangent_frame(nrm[lo_i:lo_i + step])
        rr = r[lo_i:lo_i + step, None]
        u[order[lo_i:lo_i + step]] = t1 * rr
        v[order[lo_i:lo_i + step]] = t2 * rr
    report(progress, "sizing splats", 1.0)
    return SplatCloud(pts, u, v, colors, faces, name=name, source=source)


def _self_first(nb: np.ndarray) -> None:
    """Make every row of a k-NN index table ((n, k) int, from a query that
    includes the point itself) start with its own point, in place: with
    duplicate points a duplicate may come first (both at distance 0); the
    two swap, or, when the point is missing from its row (more than k
    copies), the first duplicate is replaced by it."""
    odd = np.flatnonzero(nb[:, 0] != np.arange(len(nb)))
    if len(odd) == 0:
        return
    sub = nb[odd]
    is_self = sub == odd[:, None]
    col = np.where(is_self.any(axis=1), is_self.argmax(axis=1), 0)
    sub[np.arange(len(odd)), col] = sub[:, 0]
    sub[:, 0] = odd
    nb[odd] = sub
