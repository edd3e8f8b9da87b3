"""Vertex splats for a triangle mesh.

Every vertex becomes a circular splat:

* normal: the area-weighted average of the incident face normals (the sum of
  the unnormalised cross products, whose lengths are twice the face areas);
* radius: ``MESH_SPLAT_RADIUS_FACTOR`` times the longest edge of the incident
  triangles.  Why that closes the surface: any point x of a triangle with
  longest edge L lies within L / sqrt(3) of its nearest corner.  (For an acute
  triangle the farthest point from all corners is the circumcentre, at
  R = L / (2 sin A) with A >= 60 degrees the angle opposite L, so R <= L/sqrt(3),
  equality for the equilateral triangle; for a right or obtuse triangle the
  farthest point lies on the longest edge, within L / 2.)  That corner is
  incident to the triangle, so its radius is at least L / sqrt(3) >= |x - corner|,
  and the orthogonal projection of x onto the corner's tangent plane is no
  farther, so it falls inside the corner's splat disc.  The factor
  1.2 / sqrt(3) adds a 20 % overlap so the EWA kernels blend.

Vertices without usable faces (isolated, only degenerate faces, or opposite
faces cancelling) fall back to a PCA normal and the neighbour-spacing radius
of :mod:`splatedit.model.estimate`.

The radii are then capped relative to the median radius of the
``SIZE_NEIGHBOURS - 1`` nearest vertices (:func:`splatedit.model.sizing.limit_radii`):
at most ``SIZE_CAP_REL_NEIGHBOURS`` times it, and at most
``BOUNDARY_CAP_REL_NEIGHBOURS`` times it for a vertex of a face that touches a
border edge (an edge of a single face).  A strip of long sliver triangles at
an open border would otherwise give its corners discs that overhang the border
as flaps, and an unreferenced stray vertex a disc the size of its distance to
the surface (outlier vertices, :mod:`splatedit.model.outliers`, are kept at
most ``OUTLIER_RADIUS_REL_MEDIAN`` times the median radius of their
neighbours).  On a mesh of regular triangles the caps change nothing, so the
covering argument above holds; where they cut, the covering is no longer
proved but measured (see the constants in :mod:`splatedit.tolerances`): a
sliver is thin, so the discs of its neighbours still cover it.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from splatedit.errors import InputError
from splatedit.model.cloud import SplatCloud
from splatedit.model.estimate import fill_missing_normals, knn, splat_radii
from splatedit.model.tangents import tangent_frame
from splatedit.model.outliers import detect_outliers
from splatedit.model.sizing import (limit_outlier_radii, limit_radii, mesh_border_ring,
                                    neighbour_indices)
from splatedit.progress import report
from splatedit.tolerances import MESH_NORMAL_MIN_REL, MESH_SPLAT_RADIUS_FACTOR, SIZE_NEIGHBOURS


def mesh_vertex_normals(vertices, faces) -> np.ndarray:
    """Area-weighted vertex normals, unnormalised.

    Args:
        vertices: (n, 3) float64; faces: (f, 3) int64 (counter-clockwise =
            front side).
    Returns:
        (n, 3) float64, the sum over incident faces of ``(b - a) x (c - a)``
        (length twice the face area); zero rows for vertices without faces.
    """
    V = np.asarray(vertices, dtype=np.float64)
    F = np.asarray(faces, dtype=np.int64)
    fn = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    flat = F.ravel()
    out = np.empty((len(V), 3))
    for j in range(3):
        out[:, j] = np.bincount(flat, weights=np.repeat(fn[:, j], 3), minlength=len(V))
    return out


def mesh_vertex_radii(vertices, faces) -> np.ndarray:
    """(n,) float64: longest edge of the triangles incident to each vertex
    (model units), 0 for vertices without faces."""
    V = np.asarray(vertices, dtype=np.float64)
    F = np.asarray(faces, dtype=np.int64)
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    longest = np.maximum(np.maximum(np.linalg.norm(b - a, axis=1), np.linalg.norm(c - b, axis=1)),
                         np.linalg.norm(a - c, axis=1))
    out = np.zeros(len(V))
    np.maximum.at(out, F.ravel(), np.repeat(longest, 3))
    return out


def cloud_from_mesh(vertices, faces, *, normals=None, colors=None, name: str = "",
                    source: str | None = None, progress=None) -> SplatCloud:
    """Vertex splats of a triangle mesh; the faces are kept.

    Args:
        vertices: (n, 3) float64 positions (model units).
        faces: (f, 3) int64 vertex indices of the triangles.
        normals: optional (n, 3) vertex normals from the file; used where
            non-zero instead of the area-weighted face normals.
        colors: optional (n, 4) uint8 RGBA.
        name, source: as in :class:`SplatCloud`.
    Returns:
        SplatCloud with circular splats, radius
        ``MESH_SPLAT_RADIUS_FACTOR * longest incident edge``, capped relative
        to the neighbouring vertices' radii (see the module docstring).
    Raises:
        InputError: a face index outside 0..n-1 (naming the face row).
    """
    V = np.ascontiguousarray(vertices, dtype=np.float64)
    F = np.ascontiguousarray(faces, dtype=np.int64).reshape(-1, 3)
    n = len(V)
    if n == 0:
        raise InputError("zero vertices", path=source, element="vertex")
    if len(F):
        bad = (F < 0).any(axis=1) | (F >= n).any(axis=1)
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise InputError(f"vertex index out of range 0..{n - 1}: {F[row].tolist()}",
                             path=source, element="face", row=row, prop="vertex_indices")
    report(progress, "building mesh splats", 0.0)
    vn = mesh_vertex_normals(V, F)
    edge = mesh_vertex_radii(V, F)
    ln = np.linalg.norm(vn, axis=1)
    nrm = np.zeros_like(vn)
    good = (edge > 0) & (ln > MESH_NORMAL_MIN_REL * edge * edge)
    nrm[good] = vn[good] / ln[good, None]
    if normals is not None:
        given = np.asarray(normals, dtype=np.float64)
        gl = np.linalg.norm(given, axis=1)
        use = np.isfinite(gl) & (gl > 0)
        nrm[use] = given[use] / gl[use, None]
    radius = edge * MESH_SPLAT_RADIUS_FACTOR
    lonely = np.flatnonzero(edge <= 0)
    tree = cKDTree(V) if n > 1 else None
    if len(lonely) or not np.all(np.linalg.norm(nrm, axis=1) > 0):
        nrm = fill_missing_normals(V, nrm, tree=tree)
    if len(lonely):
        radius[lonely] = splat_radii(V, tree=tree, query=lonely)
    if n > 2:
        report(progress, "building mesh splats", 0.5)
        dist, nb = knn(V, SIZE_NEIGHBOURS, tree=tree)
        nb = neighbour_indices(V, SIZE_NEIGHBOURS, neighbours=nb)
        radius = limit_radii(radius, nb, mesh_border_ring(n, F))
        radius = limit_outlier_radii(radius, detect_outliers(V, tree=tree, distances=dist).mask, nb)
    t1, t2 = tangent_frame(nrm)
    report(progress, "building mesh splats", 1.0)
    return SplatCloud(V, t1 * radius[:, None], t2 * radius[:, None], colors, F,
                      name=name, source=source)
