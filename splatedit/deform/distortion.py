"""Per-splat distortion of a deformation: principal stretches and area change.

For a splat with orthogonal tangent semi-axes u, v and the deformation's
Jacobian J at its centre, the *principal stretches* s1 >= s2 are the singular
values of the 3x2 matrix ``[J u / |u|, J v / |v|]`` (the map of the splat's
unit tangent axes; for axes that are not orthogonal, the singular values of
J restricted to the tangent plane, see :func:`principal_stretches`).  Then

* ``stretch = max(s1, 1 / s2)`` (>= 1; 1 = undistorted, 2 = some direction
  doubled or halved in length),
* ``area change = s1 s2 = |J u x J v| / |u x v|`` (1 = area kept).

Both are computed from the original and deformed axes (``u' = J u``), so
:func:`distortion_from_axes` works for any deformation path;
:class:`DistortionProbe` gets them from a :class:`DeformationBasis` and a
displacement ``dC`` without deforming the cloud (the editor's per-frame
figures).  Thresholds: ``DISTORTION_WARN_STRETCH`` (3x: warn) and
``DISTORTION_BROKEN_STRETCH`` (4x: splats visibly torn) in
:mod:`splatedit.tolerances`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from splatedit.errors import ParameterError
from splatedit.tolerances import (DISTORTION_BROKEN_STRETCH, DISTORTION_CHUNK, DISTORTION_PROBE_CHUNK,
                                  TEAR_APART_SPACINGS, TEAR_NEIGHBOUR_SPACINGS,
                                  DISTORTION_WARN_STRETCH)


@dataclass(frozen=True)
class DistortionStats:
    """Distortion figures of N splats (one edit's support).

    Attributes:
        n: number of splats measured (N).
        max_stretch: largest ``stretch`` (1.0 when N = 0; inf when a splat
            collapsed to a segment or point).
        n_above_warn: splats with stretch > ``warn`` (3x by default).
        n_above_broken: splats with stretch > ``broken`` (4x by default).
        fraction_above_warn: ``n_above_warn / N`` (0 when N = 0).
        min_area_change, max_area_change: range of ``area_change`` (1, 1 when N = 0).
        warn, broken: the thresholds the counts use (stretch factors).
        stretch: (N,) float64 per-splat stretch max(s1, 1/s2) >= 1.
        area_change: (N,) float64 per-splat area ratio s1 s2.
    """
    n: int
    max_stretch: float
    n_above_warn: int
    n_above_broken: int
    fraction_above_warn: float
    min_area_change: float
    max_area_change: float
    warn: float
    broken: float
    stretch: np.ndarray
    area_change: np.ndarray

    @property
    def exceeds_warn(self) -> bool:
        """True when any splat is stretched beyond ``warn``."""
        return self.n_above_warn > 0

    def summary(self) -> str:
        """One line: ``stretch max 1.84x, 0 > 3x, 0 > 4x, area change 0.71..2.30``."""
        return (f"stretch max {self.max_stretch:.2f}x, {self.n_above_warn} > {self.warn:g}x, "
                f"{self.n_above_broken} > {self.broken:g}x, area change "
                f"{self.min_area_change:.3g}..{self.max_area_change:.3g}")


def _gram(a, b):
    """Gram entries (a.a, a.b, b.b) and |a x b| of (3, n) coordinate rows."""
    ax, ay, az = a
    bx, by, bz = b
    e = ax * ax + ay * ay + az * az
    f = ax * bx + ay * by + az * bz
    g = bx * bx + by * by + bz * bz
    cx, cy, cz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
    return e, f, g, np.sqrt(cx * cx + cy * cy + cz * cz)


def _stretches_from_gram(e0, f0, g0, c0, e1, f1, g1, c1):
    """(s1, s2) from the Gram entries and cross-product lengths of the
    original (0) and deformed (1) axis pairs, see :func:`principal_stretches`."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / (e0 * g0 - f0 * f0)
        # M = G0^-1 G1; its eigenvalues are half +- disc (disc from the entries,
        # not from half^2 - det: no cancellation when s1 ~ s2)
        m00 = (g0 * e1 - f0 * f1) * inv
        m01 = (g0 * f1 - f0 * g1) * inv
        m10 = (e0 * f1 - f0 * e1) * inv
        m11 = (e0 * g1 - f0 * f1) * inv
        half = 0.5 * (m00 + m11)
        dd = 0.5 * (m00 - m11)
        disc = np.sqrt(np.maximum(dd * dd + m01 * m10, 0.0))
        area = c1 / c0
        s1 = np.sqrt(half + disc)
        s2 = np.where(s1 > 0.0, area / s1, 0.0)
    return s1, np.minimum(s2, s1)


def principal_stretches(u0: np.ndarray, v0: np.ndarray, u1: np.ndarray, v1: np.ndarray):
    """Principal stretches of the linear maps taking (u0, v0) to (u1, v1).

    Args:
        u0, v0: (n, 3) float original tangent axes (independent, any lengths).
        u1, v1: (n, 3) float their images ``J u0``, ``J v0``.
    Returns:
        ``(s1, s2)`` (n,) float64 with s1 >= s2 >= 0: the singular values of
        the map of the tangent plane, i.e. the square roots of the eigenvalues
        of G0^-1 G1 with the Gram matrices G0 = [u0 v0]^T [u0 v0] and G1 =
        [u1 v1]^T [u1 v1].  For orthogonal axes these are the singular values
        of ``[u1/|u0|, v1/|v0|]``; s1 s2 = |u1 x v1| / |u0 x v0| (the area
        change), and s2 = s1 s2 / s1 stays accurate for flattened splats.
    """
    t = [np.ascontiguousarray(np.asarray(x, dtype=np.float64).T) for x in (u0, v0, u1, v1)]
    return _stretches_from_gram(*_gram(t[0], t[1]), *_gram(t[2], t[3]))


def _finish(stretch: np.ndarray, area: np.ndarray, warn: float, broken: float) -> DistortionStats:
    n = len(stretch)
    n_warn = int(np.count_nonzero(stretch > warn))
    return DistortionStats(
        n=n, max_stretch=float(stretch.max(initial=1.0)), n_above_warn=n_warn,
        n_above_broken=int(np.count_nonzero(stretch > broken)),
        fraction_above_warn=n_warn / n if n else 0.0,
        min_area_change=float(area.min(initial=1.0)) if n else 1.0,
        max_area_change=float(area.max(initial=1.0)) if n else 1.0,
        warn=float(warn), broken=float(broken), stretch=stretch, area_change=area)


def _stretch_area(s1, s2, stretch_out, area_out):
    with np.errstate(divide="ignore"):
        np.maximum(s1, 1.0 / s2, out=stretch_out)
    np.multiply(s1, s2, out=area_out)


def _check_axes(name: str, a) -> np.ndarray:
    arr = np.asarray(a, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ParameterError(name, f"must have shape (n, 3), got {arr.shape}")
    return arr


def distortion_from_axes(u0, v0, u1, v1, *, warn: float = DISTORTION_WARN_STRETCH,
                         broken: float = DISTORTION_BROKEN_STRETCH,
                         chunk: int = DISTORTION_CHUNK) -> DistortionStats:
    """Distortion of splats whose axes went from (u0, v0) to (u1, v1) = (J u0, J v0).

    Args:
        u0, v0: (n, 3) original orthogonal tangent semi-axes (model units, non-zero).
        u1, v1: (n, 3) deformed axes.
        warn, broken: stretch thresholds of the counts.
        chunk: rows per vectorised block (bounds the temporaries).
    """
    u0, v0, u1, v1 = (_check_axes(nm, x) for nm, x in
                      (("u0", u0), ("v0", v0), ("u1", u1), ("v1", v1)))
    n = len(u0)
    if not all(len(x) == n for x in (v0, u1, v1)):
        raise ParameterError("axes", "u0, v0, u1, v1 must have the same number of rows")
    stretch, area = np.empty(n), np.empty(n)
    for s in range(0, n, chunk):
        e = min(n, s + chunk)
        _stretch_area(*principal_stretches(u0[s:e], v0[s:e], u1[s:e], v1[s:e]), stretch[s:e], area[s:e])
    return _finish(stretch, area, warn, broken)


class DistortionProbe:
    """Distortion of one basis' support for any displacement ``dC``, without
    deforming the cloud (the editor's per-frame figures).

    Built once per (basis, base cloud): ``Au = sum_j (u_j/|u|) Bj`` and ``Av``
    likewise (stored transposed, (K, N) float32: 4 K bytes per splat each; Bj
    in Bx, By, Bz), so that the deformed unit axes are ``u/|u| + dC^T Au`` and
    ``v/|v| + dC^T Av``, plus the undeformed Gram entries.  Each
    :meth:`stats` call is then two (3, K) x (K, N) products and elementwise
    float32 arithmetic on contiguous rows, in chunks.  float32 suffices for
    display figures (relative error ~1e-5 on the stretch); the CLI measures the
    committed float64 axes with :func:`distortion_from_axes`.
    """

    def __init__(self, basis, cloud, *, chunk: int = DISTORTION_PROBE_CHUNK):
        idx = basis.indices
        n, k = len(idx), basis.n_columns
        grads = (basis.Bx, basis.By, basis.Bz)
        #: per chunk of ``chunk`` support splats: (uhat, vhat) (3, m) and (Au, Av) (K, m),
        #: each contiguous (a column slice of one (K, N) array made BLAS 5-10x slower)
        self.chunks = []
        for s in range(0, n, chunk):
            e = min(n, s + chunk)
            part = []
            for ax in (cloud.u, cloud.v):
                x = ax[idx[s:e]]
                x = x / np.linalg.norm(x, axis=1, keepdims=True)
                w = x[:, 0:1] * grads[0][s:e] + x[:, 1:2] * grads[1][s:e] + x[:, 2:3] * grads[2][s:e]
                part += [np.ascontiguousarray(x.T, np.float32), np.ascontiguousarray(w.T, np.float32)]
            uh, au, vh, av = part
            self.chunks.append((uh, vh, au, av, _gram(uh, vh)))
        self.n = n
        self.n_columns = k

    def __len__(self) -> int:
        return self.n

    def stats(self, dC, *, warn: float = DISTORTION_WARN_STRETCH,
              broken: float = DISTORTION_BROKEN_STRETCH) -> DistortionStats:
        """Distortion of the support splats for displacements ``dC`` (K, 3)."""
        d = np.asarray(dC, dtype=np.float32)
        if d.shape != (self.n_columns, 3):
            raise ParameterError("dC", f"expected shape ({self.n_columns}, 3), got {d.shape}")
        dt = np.ascontiguousarray(d.T)
        n = len(self)
        stretch, area = np.empty(n), np.empty(n)
        s = 0
        for uh, vh, au, av, g0 in self.chunks:
            e = s + uh.shape[1]
            a = uh + dt @ au
            b = vh + dt @ av
            _stretch_area(*_stretches_from_gram(*g0, *_gram(a, b)), stretch[s:e], area[s:e])
            s = e
        return _finish(stretch, area, warn, broken)


def basis_distortion(basis, cloud, dC, **kw) -> DistortionStats:
    """Distortion of ``basis``' support splats (in ``basis.indices`` order)
    under ``dC`` (K, 3) or a RotationDisplacement, exact float64: the
    Jacobians ``basis.jacobians(dC)`` applied to the cloud's axes, chunked."""
    from splatedit.deform.rotation import blend_terms, split_displacement
    d, rot = split_displacement(dC)
    d = basis._check_dc(d)
    blocks = [basis.columns_for_group(g) for g, k in enumerate(basis.group_kinds) if k == "handle"]
    idx = basis.indices
    chunk = kw.pop("chunk", DISTORTION_CHUNK)
    n = len(idx)
    u1, v1 = np.empty((n, 3)), np.empty((n, 3))
    for s in range(0, n, chunk):
        e = min(n, s + chunk)
        u0, v0 = cloud.u[idx[s:e]], cloud.v[idx[s:e]]
        for src, dst in ((u0, u1), (v0, v1)):
            w = sum(src[:, j:j + 1] * g[s:e] for j, g in enumerate((basis.Bx, basis.By, basis.Bz)))
            dst[s:e] = src + w @ d
        if rot is not None:
            extra = blend_terms(rot, basis._pack[s:e], blocks, (u0, v0))[1]
            u1[s:e] += extra[0]
            v1[s:e] += extra[1]
    return distortion_from_axes(cloud.u[idx], cloud.v[idx], u1, v1, chunk=chunk, **kw)


def count_tears(positions0: np.ndarray, positions1: np.ndarray, spacing: float,
                pairs: np.ndarray | None = None) -> int:
    """Tears of a deformation: pairs of splats closer than
    ``TEAR_NEIGHBOUR_SPACINGS`` point spacings before it (neighbours on the
    surface) that end up more than ``TEAR_APART_SPACINGS`` spacings apart.

    Args:
        positions0, positions1: (n, 3) float64 before / after (model units).
        spacing: the point spacing (model units), e.g. the median
            nearest-neighbour distance.
        pairs: optional precomputed (p, 2) neighbour pairs of ``positions0``.
    """
    from scipy.spatial import cKDTree
    if pairs is None:
        pairs = cKDTree(positions0).query_pairs(TEAR_NEIGHBOUR_SPACINGS * spacing, output_type="ndarray")
    gap = np.linalg.norm(positions1[pairs[:, 0]] - positions1[pairs[:, 1]], axis=1)
    return int((gap > TEAR_APART_SPACINGS * spacing).sum())
