"""Detail-preserving (multiresolution) deformation (paper Sect. 8 and beyond).

The support is split into a smooth *base* surface plus scalar normal offsets

    p = b + lambda n_b                    (per splat: b, lambda, n_b)

(:func:`decompose`: umbrella smoothing over the neighbour graph, each splat
moving along its own normal line; ``n_b`` from PCA of the smoothed surface).
The base is deformed by any evaluator giving the displacement ``d(b)`` and
Jacobian ``J(b)`` at the base points (the fitted RBF is a space function: it
is *fitted and evaluated at b*, so handle splats stay exactly rigid and the
fixed band stays put), and the detail is re-attached with one local map per
splat:

    n'  = normalize(J^-T n_b) = normalize(J t1 x J t2)     (t1, t2, n_b orthonormal)
    M   = J P + n' n_b^T                                   (P = I - n_b n_b^T)
    p'  = b + d(b) + M (lambda n_b) = b + d(b) + lambda n'
    u'  = M u,   v' = M v

Tangent axes (what the paper left open).  ``M`` is the polar product
``R S`` of the rotation ``R`` (taking n_b to n', the rotation part of J on the
base's tangent plane) and the stretch ``S`` = the base's tangential stretch
(``sqrt(P J^T J P)``) plus 1 along the normal.  ``FrameMode.STRETCH`` (the
default) applies all of ``M``: splats grow with the base exactly as the linear
mode's ``J u`` grows them on a flat surface (hole-free where the base is
stretched), while their normal component and the bump heights keep their
length (``S n_b = n_b``; the linear mode scales them with J).
``FrameMode.RIGID`` applies only ``R`` (splat shapes kept): it opens holes
wherever the base is stretched (measured in tests/deform/test_detail.py and
docs/PERFORMANCE.md), so it is offered for measurements only.

Per frame the CPU needs, like the linear mode, three chunked GEMMs
(``b' = [B | b] [dC; I]``, ``J t1 = [W1 | t1] [dC; I]``, ``J t2`` likewise,
``Wk = tk_x Bx + tk_y By + tk_z Bz``; the rotation terms come out of the same
GEMMs, :mod:`splatedit.deform.detail_apply`) and element-wise products; the GPU
pre-pass (shaders_glsl/prepare_detail*.comp) reads the same basis rows at b
and one vec4 (n_b, lambda) per splat.
"""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass, field
from enum import Enum

import numpy as np
from scipy import sparse
from scipy.spatial import cKDTree

from splatedit.deform.basis import DeformationBasis
from splatedit.deform.constraints import as_mask
from splatedit.deform.distortion import distortion_from_axes
from splatedit.deform.modes import DeformationMode
from splatedit.deform.rotation import RotationDisplacement, split_displacement
from splatedit.errors import ParameterError
from splatedit.model.estimate import estimate_normals
from splatedit.model.tangents import tangent_frame
from splatedit.progress import report
from splatedit.select.graph import NeighbourGraph
from splatedit.tolerances import (BAND_RINGS, DETAIL_MAX_ITERATIONS,
                                  DETAIL_NORMAL_NEIGHBOURS, DETAIL_SCALE_SPACINGS, DETAIL_STEP,
                                  IQR_DEFAULT_TOL)

#: progress stage of the base-surface smoothing
DECOMPOSE_STAGE = "smoothing the base surface"


class FrameMode(str, Enum):
    """How the splats' tangent axes follow the deformed base (see module doc)."""

    STRETCH = "stretch"   # u' = R S u: rotation and the base's tangential stretch
    RIGID = "rigid"       # u' = R u: rotation only (opens holes where the base stretches)


@dataclass(frozen=True)
class DetailLayer:
    """Base + normal offsets of the splats ``index`` (p = base + offset * normals).

    Attributes:
        index: (N,) sorted int64 cloud indices.
        base: (N, 3) float64 base points b (model units).
        offset: (N,) float64 signed offsets lambda along ``normals`` (model units).
        normals: (N, 3) float64 unit base normals n_b (oriented like the splats').
        scale: smoothing scale sigma (model units): bumps much narrower than
            ~2.5 sigma are detail, broader shapes are base.
        iterations: umbrella iterations used.
        outer_index: (M,) sorted int64 cloud indices of the smoothed splats
            around the support (the rings the smoothing grew into).
        outer_base: (M, 3) float64 their smoothed positions: the fit puts the
            fixed band's constraints there, on the same base surface as the
            support's base points (else a band on the original surface next
            to base points inside it bends the weight fields: -0.4 instead of
            0 next to the band of a bumpy bar, splats there jumping away).
    """

    index: np.ndarray
    base: np.ndarray
    offset: np.ndarray
    normals: np.ndarray
    scale: float
    iterations: int
    outer_index: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    outer_base: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))


def _splat_normals(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    n = np.cross(u, v)
    return n / np.linalg.norm(n, axis=1, keepdims=True)


def decompose(cloud, index, *, graph: NeighbourGraph | None = None,
              scale_spacings: float = DETAIL_SCALE_SPACINGS, progress=None) -> DetailLayer:
    """Split the splats ``index`` of ``cloud`` into base points and normal offsets.

    Smoothing: umbrella iterations x_i += DETAIL_STEP ((mean of graph neighbours
    x_j - x_i) . n_i) n_i, each splat moving only along its own normal n_i (no
    tangential drift, no shrinking of open borders).  The iterations run over
    ``index`` grown by as many graph rings as there are iterations, so the
    support's border sees the surface beyond it (a diffusion moves information
    one ring per iteration).  The count gives a diffusion of standard deviation
    ``sigma = scale_spacings * spacing``: each step adds ``DETAIL_STEP * <|e|^2> / 2``
    of variance per tangent axis (``<|e|^2>`` the mean squared edge length), so
    ``iterations = sigma^2 / (DETAIL_STEP <|e|^2> / 2)``.  The base normal is the
    PCA normal of the smoothed points; lambda = (p - s) . n_b, b = p - lambda n_b.

    Args:
        cloud: the :class:`SplatCloud`.
        index: (N,) cloud indices or (n,) bool mask.
        graph: the cloud's :class:`NeighbourGraph` (built when None).
        scale_spacings: sigma in graph spacings (> 0).
        progress: optional ``progress(stage, fraction)``.
    """
    n = len(cloud.positions)
    mask = as_mask("index", index, n)
    idx = np.flatnonzero(mask)
    if not np.isfinite(scale_spacings) or scale_spacings <= 0:
        raise ParameterError("scale_spacings", f"must be a positive number, got {scale_spacings}")
    graph = NeighbourGraph.build(cloud.positions) if graph is None else graph
    pos = cloud.positions
    # mean squared edge length (a sample of the support's edges)
    sample = idx[:: max(1, len(idx) // 20000)]
    nb = graph.neighbours_of(sample)
    rows = np.repeat(sample, graph.indptr[sample + 1] - graph.indptr[sample])
    msq = float(np.mean(np.sum((pos[nb] - pos[rows]) ** 2, axis=1))) if len(nb) else 0.0
    sigma = float(scale_spacings) * graph.spacing
    if msq > 0 and sigma > 0:
        iters = int(np.ceil(sigma ** 2 / (DETAIL_STEP * msq / 2.0)))
    else:
        iters = 0
    iters = min(iters, DETAIL_MAX_ITERATIONS)
    region = np.flatnonzero(graph.grow(mask, rings=iters)) if iters else idx
    sub = graph.subgraph(region)
    a = sparse.csr_matrix((np.ones(len(sub.indices)), sub.indices, sub.indptr),
                          shape=(sub.n, sub.n))
    deg = np.asarray(a.sum(axis=1)).ravel()
    inv = np.where(deg > 0, 1.0 / np.maximum(deg, 1), 0.0)
    p0 = pos[region]
    nrm = _splat_normals(cloud.u[region], cloud.v[region])
    x = p0.copy()
    report(progress, DECOMPOSE_STAGE, 0.0)
    for it in range(iters):
        mean = (a @ x) * inv[:, None]
        move = np.einsum("ij,ij->i", mean - x, nrm)
        move[deg == 0] = 0.0
        x += (DETAIL_STEP * move)[:, None] * nrm
        # the normal field is diffused alongside (a splat on a bump's flank
        # ends up moving along the smoothed surface's normal, not its own)
        nm = nrm + a @ nrm
        nrm = nm / np.maximum(np.linalg.norm(nm, axis=1, keepdims=True), 1e-300)
        if it % 8 == 7:
            report(progress, DECOMPOSE_STAGE, (it + 1) / iters)
    report(progress, DECOMPOSE_STAGE, 1.0)
    rows = np.searchsorted(region, idx)
    k = min(DETAIL_NORMAL_NEIGHBOURS, len(region))
    nb_ = estimate_normals(x, k=k, tree=cKDTree(x), query=rows) if len(region) >= 3 else nrm[rows]
    flip = np.einsum("ij,ij->i", nb_, nrm[rows]) < 0   # oriented like the smoothed normals
    nb_[flip] *= -1.0
    lam = np.einsum("ij,ij->i", pos[idx] - x[rows], nb_)
    base = pos[idx] - lam[:, None] * nb_
    outer = np.ones(len(region), bool)
    outer[rows] = False
    return DetailLayer(idx, base, lam, nb_, sigma, iters, region[outer], x[outer])


def _cross(a, b, out):
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out


def _attach(moved_base, jt1, jt2, offset, cu, cv, frames: FrameMode):
    """Re-attached (p', u', v') from the deformed base point (c, 3), the images
    J t1, J t2 of the base tangent frame (c, 3) each, lambda (c,) and the axes'
    coordinates ``cu = (u.t1, u.t2, u.n_b)`` (c, 3), ``cv`` likewise."""
    nrm = _cross(jt1, jt2, np.empty_like(jt1))
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    p = moved_base + offset[:, None] * nrm
    if frames is FrameMode.RIGID:   # orthonormalise [J t1, J t2]: (A^T A)^-1/2 by the 2x2 formula
        e = np.einsum("ij,ij->i", jt1, jt1)
        f = np.einsum("ij,ij->i", jt1, jt2)
        g = np.einsum("ij,ij->i", jt2, jt2)
        sd = np.sqrt(e * g - f * f)
        t = np.sqrt(e + g + 2 * sd)
        # sqrt(G) = (G + sd I) / t; its inverse = (adj) / det
        s00, s01, s11 = (e + sd) / t, f / t, (g + sd) / t
        det = s00 * s11 - s01 * s01
        i00, i01, i11 = s11 / det, -s01 / det, s00 / det
        q1 = jt1 * i00[:, None] + jt2 * i01[:, None]
        q2 = jt1 * i01[:, None] + jt2 * i11[:, None]
        jt1, jt2 = q1, q2
    u = jt1 * cu[:, :1] + jt2 * cu[:, 1:2] + nrm * cu[:, 2:]
    v = jt1 * cv[:, :1] + jt2 * cv[:, 1:2] + nrm * cv[:, 2:]
    return p, u, v


def reattach(layer: DetailLayer, u, v, d, J, *, frames: FrameMode = FrameMode.STRETCH):
    """Deformed (p', u', v') (N, 3) of the layer's splats for ANY base
    deformation given at the base points: ``d`` (N, 3) displacements d(b),
    ``J`` (N, 3, 3) Jacobians J(b); ``u``, ``v`` (N, 3) the splats' axes.
    (The linear basis' fast path is :meth:`DetailBasis.apply_arrays`; a
    rotation-aware evaluator plugs in here.)"""
    t1, t2 = tangent_frame(layer.normals)
    cu, cv = _coords(u, v, t1, t2, layer.normals)
    jt1 = np.einsum("nij,nj->ni", J, t1)
    jt2 = np.einsum("nij,nj->ni", J, t2)
    return _attach(layer.base + d, jt1, jt2, layer.offset, cu, cv, FrameMode(frames))


def _coords(u, v, t1, t2, nb):
    cu = np.stack([np.einsum("ij,ij->i", u, t) for t in (t1, t2, nb)], axis=1)
    cv = np.stack([np.einsum("ij,ij->i", v, t) for t in (t1, t2, nb)], axis=1)
    return cu, cv


class DetailBasis:
    """Detail-preserving deformation of one edit: the linear basis fitted and
    evaluated at the base points, plus the detail layer.  Same per-frame API
    as :class:`DeformationBasis` (``displacement``, ``apply``, ``commit``,
    ``indices``, ``stats``, ``constraints``).

    Attributes:
        base_basis: the :class:`DeformationBasis` of the base cloud (rows at b).
        layer: the :class:`DetailLayer` of the support.
        frames: the :class:`FrameMode` of the splat axes.
    """

    mode = "detail"

    def __init__(self, base_basis: DeformationBasis, layer: DetailLayer, cloud_u, cloud_v,
                 frames: FrameMode = FrameMode.STRETCH):
        self.base_basis = base_basis
        self.layer = layer
        self.frames = FrameMode(frames)
        t1, t2 = tangent_frame(layer.normals)
        self._t = (t1, t2)
        idx = layer.index
        self._cu, self._cv = _coords(cloud_u[idx], cloud_v[idx], t1, t2, layer.normals)
        self._cpu = None

    # ------------------------------------------------------------ building
    @classmethod
    def fit(cls, cloud, support, handles=(), *, curves=(), method: str = "auto",
            tol: float = IQR_DEFAULT_TOL, max_centers: int | None = None,
            rings: float = BAND_RINGS, spacing: float | None = None, fill_holes: bool = False,
            graph=None, progress=None, scale_spacings: float = DETAIL_SCALE_SPACINGS,
            frames: FrameMode = FrameMode.STRETCH) -> "DetailBasis":
        """Decompose the support (as given: close a painted selection first,
        :func:`splatedit.select.closure.closed_masks`), fit the linear basis
        on the base cloud (support splats at b), keep the layer.  Arguments
        as :meth:`DeformationBasis.fit` (``graph``: the neighbour graph of the
        decomposition, built when None), plus ``scale_spacings`` (see
        :func:`decompose`) and ``frames``."""
        n = len(cloud.positions)
        graph = NeighbourGraph.build(cloud.positions) if graph is None else graph
        if isinstance(handles, np.ndarray) and handles.ndim == 1:
            handles = [handles]
        sup_mask = as_mask("support", support, n)
        h_masks = [as_mask(f"handles[{i}]", h, n) for i, h in enumerate(handles)]
        if fill_holes:
            raise ParameterError("fill_holes", "the fit takes the selection as given: close it first with "
                                 "splatedit.select.closure.closed_masks (edit scripts and the editor do)")
        t1 = time.perf_counter()
        layer = decompose(cloud, sup_mask, graph=graph, scale_spacings=scale_spacings,
                          progress=progress)
        t2 = time.perf_counter()
        base_cloud = copy.copy(cloud)
        bpos = cloud.positions.copy()
        bpos[layer.outer_index] = layer.outer_base   # the fixed band on the base surface too
        bpos[layer.index] = layer.base
        base_cloud.positions = bpos
        bb = DeformationBasis.fit(base_cloud, sup_mask, h_masks, curves=curves, method=method,
                                  tol=tol, max_centers=max_centers, rings=rings, spacing=spacing,
                                  fill_holes=False, progress=progress)
        out = cls(bb, layer, cloud.u, cloud.v, frames)
        bb.stats["decompose_seconds"] = t2 - t1
        bb.stats["detail_iterations"] = layer.iterations
        bb.stats["detail_scale"] = layer.scale
        return out

    # ------------------------------------------------------------ delegated
    @property
    def indices(self) -> np.ndarray:
        return self.base_basis.indices

    @property
    def stats(self) -> dict:
        return self.base_basis.stats

    @property
    def constraints(self):
        return self.base_basis.constraints

    @property
    def n_columns(self) -> int:
        return self.base_basis.n_columns

    @property
    def n_groups(self) -> int:
        return self.base_basis.n_groups

    @property
    def n_handles(self) -> int:
        return self.base_basis.n_handles

    @property
    def group_kinds(self) -> list[str]:
        return self.base_basis.group_kinds

    @property
    def control_frames(self) -> np.ndarray:
        return self.base_basis.control_frames

    def columns_for_group(self, i: int) -> slice:
        return self.base_basis.columns_for_group(i)

    def displacement(self, transforms, mode: DeformationMode = DeformationMode.DETAIL):
        """The base deformation's per-frame input, see
        :meth:`DeformationBasis.displacement`: the base is deformed
        rotation-aware (``mode`` DETAIL or ROTATION: a RotationDisplacement when a
        handle rotates, else dC (K, 3)) or linearly (``mode`` LINEAR: dC)."""
        mode = DeformationMode(mode)
        base_mode = DeformationMode.LINEAR if mode is DeformationMode.LINEAR else DeformationMode.ROTATION
        d = self.base_basis.displacement(transforms, mode=base_mode)
        if getattr(d, "curves", ()):    # the base keeps the paper's curve edit (no curve frames here)
            return RotationDisplacement(d.dC, d.rotations) if d.rotating else d.dC
        return d

    def rows_for_gpu(self, handle: int | None = None):
        """``(indices, B, Bx, By, Bz)`` at the base points (all groups; the
        detail mode is drawn with the full basis), as the linear basis'."""
        return self.base_basis.rows_for_gpu()

    def detail_for_gpu(self) -> np.ndarray:
        """(N, 4) float64 ``(n_b, lambda)`` per support splat (rows of
        :attr:`indices`): the GPU recovers b = p - lambda n_b."""
        return np.concatenate([self.layer.normals, self.layer.offset[:, None]], axis=1)

    # ----------------------------------------------------------- per frame
    def _hot_path(self, n_points: int):
        if self._cpu is None:
            from splatedit.deform.detail_apply import DetailHotPath
            self._cpu = DetailHotPath(self, n_points)
        return self._cpu

    def release_cpu_cache(self) -> None:
        """Drop the hot-path arrays (about 24 (K + 3) + 80 bytes per support splat)."""
        self._cpu = None

    def apply_arrays(self, cloud, dC, progress=None):
        """Deformed ``(positions, u, v)`` (n, 3) float64 of ``cloud`` (the
        original cloud of :meth:`fit`); splats outside the support are copied
        bitwise, ``dC == 0`` returns bitwise copies.  Three GEMMs per frame in
        the run-plan layout of the linear basis plus element-wise work on
        cache-sized chunks (:mod:`splatedit.deform.detail_apply`).  ``progress``:
        see :meth:`DeformationBasis.apply_arrays`."""
        bb = self.base_basis
        bb._check_cloud(cloud)
        d, rot = split_displacement(dC)
        d = bb._check_dc(d)
        srcs = (cloud.positions, cloud.u, cloud.v)
        if not d.any() and rot is None:
            return tuple(x.copy() for x in srcs)
        return self._hot_path(len(cloud.positions)).apply(srcs, d, rot, self.frames is FrameMode.RIGID,
                                                          progress=progress)

    def distortion(self, cloud, dC, **kw):
        """:class:`DistortionStats` of the support splats' axes under ``dC``
        (keywords as :func:`distortion_from_axes`)."""
        _, u, v = self.apply_arrays(cloud, dC)
        idx = self.indices
        return distortion_from_axes(cloud.u[idx], cloud.v[idx], u[idx], v[idx], **kw)

    def apply(self, cloud, dC, *, validate: bool = False, progress=None):
        """The deformed cloud (see :meth:`DeformationBasis.apply`)."""
        from splatedit.deform.basis import deformed_copy
        return deformed_copy(cloud, self.apply_arrays(cloud, dC, progress=progress), validate, progress)

    def commit(self, cloud, dC, *, validate: bool = True, progress=None):
        """Apply ``dC`` and return the validated deformed cloud."""
        return self.apply(cloud, dC, validate=validate, progress=progress)

    def __repr__(self) -> str:
        return (f"DetailBasis({self.base_basis!r}, sigma={self.layer.scale:.3g}, "
                f"iterations={self.layer.iterations}, frames={self.frames.value})")
