"""Splats from bare points: PCA normals, MST orientation, hole-free sizing.

* :func:`estimate_normals` fits a plane to the k nearest neighbours of every
  point (Hoppe et al. 1992, "Surface reconstruction from unorganized points"):
  the normal is the eigenvector of the smallest eigenvalue of the 3x3
  neighbourhood covariance.  Batched ``np.linalg.eigh`` over chunks.
* :func:`orient_normals` makes the signs consistent by propagating along the
  minimum spanning tree of the k-nearest-neighbour "Riemannian graph" with edge
  weight ``1 - |n_i . n_j|`` (Hoppe et al.): nearly parallel normals are
  traversed first.  Each connected component is seeded at its highest point
  (largest z) whose normal is turned towards +z; on a closed surface the
  outward normal at the highest point *is* +z, so closed shapes come out
  outward-facing.  When that seed normal is nearly horizontal
  (``|n_z| < ORIENT_SEED_MIN_NZ``) it is turned away from the component's
  centroid instead.  The propagation is vectorised: the flip of a point is the
  XOR of the edge flips on its tree path to the seed, computed by pointer
  jumping in O(n log depth).
* :func:`splat_axes` builds an orthonormal tangent frame scaled to a radius
  that closes the surface (see :func:`splat_radii`), capped relative to the
  neighbours' radii and at boundaries (:mod:`splatedit.model.sizing`).
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import breadth_first_order, connected_components, minimum_spanning_tree
from scipy.spatial import cKDTree

from splatedit.errors import ParameterError
from splatedit.model.cloud import SplatCloud
from splatedit.model.outliers import detect_outliers
from splatedit.model.sizing import (boundary_points, limit_outlier_radii, limit_radii,
                                    neighbour_indices, neighbour_median)
from splatedit.model.spacing import nearest_neighbour_distances
from splatedit.progress import report
from splatedit.tolerances import (BOUNDARY_CAP_REL_NEIGHBOURS, ESTIMATE_CHUNK_POINTS,
                                  FALLBACK_SPLAT_RADIUS, MIN_SPLAT_RADIUS_REL_MEDIAN, NORMAL_NEIGHBOURS,
                                  ORIENT_NEIGHBOURS, ORIENT_SEED_MIN_NZ, ORIENT_WEIGHT_EPS,
                                  SIZE_NEIGHBOURS, SPACING_NEIGHBOUR, SPLAT_RADIUS_FACTOR)


def _points(points) -> np.ndarray:
    pts = np.ascontiguousarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ParameterError("points", f"expected shape (n, 3), got {pts.shape}")
    return pts


def knn(points, k: int, *, tree: cKDTree | None = None, query=None,
        progress=None) -> tuple[np.ndarray, np.ndarray]:
    """k nearest neighbours (the point itself included), chunked.

    Args:
        points: (n, 3) float64 positions.
        k: neighbours per point including itself, clamped to n.
        query: optional (m,) indices of the points to query (default all).
    Returns:
        dist (m, k) float64 sorted distances (model units) and idx (m, k)
        int64 indices into ``points``.
    """
    pts = _points(points)
    k = int(min(max(k, 1), len(pts)))
    idx_q = np.arange(len(pts)) if query is None else np.asarray(query, dtype=np.int64)
    tree = cKDTree(pts) if tree is None else tree
    dist = np.empty((len(idx_q), k))
    idx = np.empty((len(idx_q), k), dtype=np.int64)
    step = 8 * ESTIMATE_CHUNK_POINTS
    for lo in range(0, len(idx_q), step):
        d, i = tree.query(pts[idx_q[lo:lo + step]], k=k, workers=-1)
        dist[lo:lo + step] = d.reshape(-1, k)
        idx[lo:lo + step] = i.reshape(-1, k)
        report(progress, "finding neighbours", (lo + step) / max(len(idx_q), 1))
    return dist, idx


def _self_first(idx: np.ndarray, query: np.ndarray) -> np.ndarray:
    """Neighbour lists with the query point itself removed (duplicates of the
    point may come first in a k-d tree answer); returns (m, k-1)."""
    m, k = idx.shape
    is_self = idx == query[:, None]
    # move the (first) self entry to column 0, keep the others in order
    has = is_self.any(axis=1)
    col = np.where(has, is_self.argmax(axis=1), k - 1)
    order = np.argsort(np.arange(k)[None, :] != col[:, None], axis=1, kind="stable")
    return np.take_along_axis(idx, order, axis=1)[:, 1:]


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
    for lo in range(0, len(idx_q), step):
        nbp = pts[neighbours[lo:lo + step, :k]]         # (c, k, 3)
        nbp -= nbp.mean(axis=1, keepdims=True)
        cov = np.einsum("cki,ckj->cij", nbp, nbp)       # (c, 3, 3)
        _, vec = np.linalg.eigh(cov)
        out[lo:lo + step] = vec[:, :, 0]
        report(progress, "estimating normals", (lo + len(nbp)) / len(idx_q))
    out /= np.linalg.norm(out, axis=1, keepdims=True)
    return out


def _seed_flips(pts, nrm, labels, ncomp):
    """Seed (highest point) of every component and whether its normal flips."""
    order = np.lexsort((pts[:, 2], labels))
    last = np.r_[np.flatnonzero(np.diff(labels[order])), len(order) - 1]
    seeds = order[last]                                 # component c -> seed, c = 0..ncomp-1
    nz = nrm[seeds, 2]
    flip = nz < 0
    flat = np.abs(nz) < ORIENT_SEED_MIN_NZ
    if flat.any():
        cnt = np.bincount(labels, minlength=ncomp).astype(np.float64)
        centroid = np.stack([np.bincount(labels, pts[:, j], minlength=ncomp) for j in range(3)], 1)
        centroid /= cnt[:, None]
        out = np.einsum("ij,ij->i", nrm[seeds], pts[seeds] - centroid)
        flip = np.where(flat, out < 0, flip)
    return seeds, flip


def orient_normals(points, normals, k: int = ORIENT_NEIGHBOURS, *, tree: cKDTree | None = None,
                   neighbours=None, progress=None) -> np.ndarray:
    """Consistently orient normals by MST propagation (Hoppe et al. 1992).

    Args:
        points: (n, 3) float64 positions (model units).
        normals: (n, 3) float64 unit normals with arbitrary signs.
        k: neighbours per point in the Riemannian graph.
        tree: optional prebuilt ``cKDTree(points)``.
        neighbours: optional (n, >= k + 1) int64 indices from :func:`knn`.
    Returns:
        (n, 3) float64 normals, each equal to ``+-normals[i]``; every
        connected component of the k-NN graph is seeded at its highest point
        with the normal turned to +z (or away from the component centroid when
        the seed normal is nearly horizontal).
    """
    pts = _points(points)
    nrm = np.array(normals, dtype=np.float64)
    n = len(pts)
    if nrm.shape != pts.shape:
        raise ParameterError("normals", f"expected shape {pts.shape}, got {nrm.shape}")
    if n == 0:
        return nrm
    if n == 1:
        labels = np.zeros(1, dtype=np.int64)
        _, flip = _seed_flips(pts, nrm, labels, 1)
        return np.where(flip[:, None], -nrm, nrm)
    report(progress, "orienting normals", 0.0)
    k = int(min(max(k, 1), n - 1))
    if neighbours is None or neighbours.shape[1] < k + 1:
        _, neighbours = knn(pts, k + 1, tree=tree)
    nb = _self_first(neighbours[:, :k + 1], np.arange(n))
    rows = np.repeat(np.arange(n), k)
    cols = nb.ravel()
    keep = rows < cols      # the MST treats the graph as undirected: one edge per pair
    rows, cols = np.concatenate([rows[keep], cols[~keep]]), np.concatenate([cols[keep], rows[~keep]])
    key = np.sort(rows * n + cols)          # sort + diff: np.unique hashes, far slower here
    key = key[np.r_[True, key[1:] != key[:-1]]]
    rows, cols = key // n, key % n
    w = 1.0 - np.abs(np.einsum("ij,ij->i", nrm[rows], nrm[cols])) + ORIENT_WEIGHT_EPS
    graph = coo_matrix((w, (rows, cols)), shape=(n, n)).tocsr()
    report(progress, "orienting normals", 0.3)
    ncomp, labels = connected_components(graph, directed=False)
    tree_edges = minimum_spanning_tree(graph).tocoo()
    report(progress, "orienting normals", 0.6)
    seeds, seed_flip = _seed_flips(pts, nrm, labels, ncomp)

    # Forest + a virtual root (index n) joined to every component's seed.
    r = np.concatenate([tree_edges.row, np.full(ncomp, n)])
    c = np.concatenate([tree_edges.col, seeds])
    adj = coo_matrix((np.ones(len(r)), (r, c)), shape=(n + 1, n + 1)).tocsr()
    _, pred = breadth_first_order(adj, n, directed=False, return_predecessors=True)
    parent = pred.astype(np.int64)
    parent[n] = n
    flip = np.zeros(n + 1, dtype=bool)
    body = np.flatnonzero(parent[:n] != n)
    flip[body] = np.einsum("ij,ij->i", nrm[body], nrm[parent[body]]) < 0
    flip[seeds] = seed_flip
    # Pointer jumping: flip[i] = XOR of the edge flips from i to parent[i].
    while True:
        grand = parent[parent]
        if np.array_equal(grand, parent):
            break
        flip ^= flip[parent]
        parent = grand
    report(progress, "orienting normals", 1.0)
    nrm[flip[:n]] *= -1.0
    return nrm


def tangent_frame(normals) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal tangent vectors ``(t1, t2)`` with ``t1 x t2 = n``.

    Uses the branch-free construction of Duff et al., "Building an
    Orthonormal Basis, Revisited" (JCGT 2017), which is continuous except
    across the equator sign switch of n_z.

    Args:
        normals: (n, 3) float64 unit normals.
    Returns:
        two (n, 3) float64 arrays of unit vectors.
    """
    nrm = np.asarray(normals, dtype=np.float64)
    x, y, z = nrm[:, 0], nrm[:, 1], nrm[:, 2]
    s = np.where(z >= 0.0, 1.0, -1.0)
    a = -1.0 / (s + z)
    b = x * y * a
    t1 = np.stack([1.0 + s * x * x * a, s * b, -s * x], axis=1)
    t2 = np.stack([b, s + y * y * a, -y], axis=1)
    return t1, t2


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
    r = distances[:, k] * factor
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
    that are not outliers
    (see :mod:`splatedit.model.sizing`).

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
    boundary[test] = boundary_points(pts, normals, nb, query=test)
    r = limit_radii(r, nb, boundary, local=local)
    return limit_outlier_radii(r, detect_outliers(pts, tree=tree, distances=distances).mask, nb)


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


def fill_missing_normals(points, normals, *, tree: cKDTree | None = None) -> np.ndarray:
    """Normalise ``normals`` and replace zero-length or non-finite rows by PCA
    normals (:func:`estimate_normals`) turned to agree with the nearest point
    that has a valid normal (when no row is valid, all are estimated and
    oriented by :func:`orient_normals`).

    Args:
        points: (n, 3) float64 positions; normals: (n, 3) float64.
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
    if not good.any():
        return orient_normals(pts, estimate_normals(pts, tree=tree), tree=tree)
    bad = np.flatnonzero(~good)
    est = estimate_normals(pts, tree=tree, query=bad)
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
    tree = cKDTree(pts) if len(pts) > 1 else None
    dist = nb = None
    if len(pts) > 1:
        kmax = max(SPACING_NEIGHBOUR + 1, SIZE_NEIGHBOURS)
        if normals is None:
            kmax = max(NORMAL_NEIGHBOURS, ORIENT_NEIGHBOURS + 1, kmax)
        if radius is None or normals is None:
            dist, nb = knn(pts, kmax, tree=tree, progress=progress)
    if normals is None:
        nrm = estimate_normals(pts, tree=tree, neighbours=nb, progress=progress)
        nrm = orient_normals(pts, nrm, tree=tree, neighbours=nb, progress=progress)
    else:
        nrm = np.asarray(normals, dtype=np.float64)
        if nrm.shape != pts.shape:
            raise ParameterError("normals", f"expected shape {pts.shape}, got {nrm.shape}")
        nrm = fill_missing_normals(pts, nrm, tree=tree)
    u, v = splat_axes(pts, nrm, radius=radius, tree=tree, distances=dist, neighbours=nb,
                      progress=progress)
    return SplatCloud(pts, u, v, colors, faces, name=name, source=source)
