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
from splatedit.tolerances import DISTORTION_BROKEN_STRETCH, DISTORTION_CHUNK, DISTORTION_WARN_STRETCH


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
    def gram(a, b):
        return (np.einsum("ij,ij->i", a, a), np.einsum("ij,ij->i", a, b), np.einsum("ij,ij->i", b, b))

    e0, f0, g0 = gram(u0, v0)
    e1, f1, g1 = gram(u1, v1)
    det0 = e0 * g0 - f0 * f0
    with np.errstate(divide="ignore", invalid="ignore"):
        # M = G0^-1 G1; its eigenvalues are half +- disc (disc from the entries,
        # not from half^2 - det: no cancellation when s1 ~ s2)
        m00 = (g0 * e1 - f0 * f1) / det0
        m01 = (g0 * f1 - f0 * g1) / det0
        m10 = (e0 * f1 - f0 * e1) / det0
        m11 = (e0 * g1 - f0 * f1) / det0
        half = 0.5 * (m00 + m11)
        dd = 0.5 * (m00 - m11)
        disc = np.sqrt(np.maximum(dd * dd + m01 * m10, 0.0))
        area = np.linalg.norm(np.cross(u1, v1), axis=1) / np.linalg.norm(np.cross(u0, v0), axis=1)
        s1 = np.sqrt(half + disc)
        s2 = np.where(s1 > 0.0, area / s1, 0.0)
    return s1, np.minimum(s2, s1)


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


def _stretch_area(u0, v0, u1, v1, stretch_out, area_out):
    s1, s2 = principal_stretches(u0, v0, u1, v1)
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
        _stretch_area(u0[s:e], v0[s:e], u1[s:e], v1[s:e], stretch[s:e], area[s:e])
    return _finish(stretch, area, warn, broken)


class DistortionProbe:
    """Distortion of one basis' support for any displacement ``dC``, without
    deforming the cloud.

    Built once per (basis, base cloud): ``Au = sum_j (u_j/|u|) Bj`` and ``Av``
    likewise ((N, K) float32, Bj in Bx, By, Bz; 8 K bytes per splat each), so
    that the deformed unit axes are ``u/|u| + Au dC`` and ``v/|v| + Av dC``.
    Each :meth:`stats` call is then two (N, K) x (K, 3) products and the 2x2
    singular values, in chunks.  float32 suffices for display figures
    (relative error ~1e-6 on the stretch); the CLI measures the committed
    float64 axes with :func:`distortion_from_axes`.
    """

    def __init__(self, basis, cloud, *, chunk: int = DISTORTION_CHUNK):
        idx = basis.indices
        u = cloud.u[idx]
        v = cloud.v[idx]
        self.uhat = (u / np.linalg.norm(u, axis=1)[:, None]).astype(np.float32)
        self.vhat = (v / np.linalg.norm(v, axis=1)[:, None]).astype(np.float32)
        k = basis.n_columns
        n = len(idx)
        self.au = np.empty((n, k), np.float32)
        self.av = np.empty((n, k), np.float32)
        grads = (basis.Bx, basis.By, basis.Bz)
        for s in range(0, n, chunk):
            e = min(n, s + chunk)
            self.au[s:e] = sum(self.uhat[s:e, j:j + 1] * grads[j][s:e] for j in range(3))
            self.av[s:e] = sum(self.vhat[s:e, j:j + 1] * grads[j][s:e] for j in range(3))
        self.n_columns = k
        self.chunk = chunk

    def __len__(self) -> int:
        return len(self.uhat)

    def stats(self, dC, *, warn: float = DISTORTION_WARN_STRETCH,
              broken: float = DISTORTION_BROKEN_STRETCH) -> DistortionStats:
        """Distortion of the support splats for displacements ``dC`` (K, 3)."""
        d = np.asarray(dC, dtype=np.float32)
        if d.shape != (self.n_columns, 3):
            raise ParameterError("dC", f"expected shape ({self.n_columns}, 3), got {d.shape}")
        n = len(self.uhat)
        stretch, area = np.empty(n), np.empty(n)
        for s in range(0, n, self.chunk):
            e = min(n, s + self.chunk)
            a = (self.uhat[s:e] + self.au[s:e] @ d).astype(np.float64)
            b = (self.vhat[s:e] + self.av[s:e] @ d).astype(np.float64)
            _stretch_area(self.uhat[s:e], self.vhat[s:e], a, b, stretch[s:e], area[s:e])
        return _finish(stretch, area, warn, broken)


def basis_distortion(basis, cloud, dC, **kw) -> DistortionStats:
    """Distortion of ``basis``' support splats (in ``basis.indices`` order)
    under ``dC`` (K, 3), exact float64: the Jacobians ``basis.jacobians(dC)``
    applied to the cloud's axes, chunked."""
    d = basis._check_dc(dC)
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
    return distortion_from_axes(cloud.u[idx], cloud.v[idx], u1, v1, chunk=chunk, **kw)
