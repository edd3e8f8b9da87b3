"""Uploads of the splat renderer's scene: the cloud (geometry and colours in
chunks), the selection flags, the deformation basis rows, the detail rows
and the per-frame displacement dC.

:class:`SceneUploads` is owned by :class:`splatedit.render.splat.renderer.Renderer`
(``renderer.uploads``): it holds these buffers on the renderer's device and
calls back when buffers the pre-pass binds are replaced (``on_rebind``).

Only :mod:`splatedit.render.vk` calls Vulkan.
"""

from __future__ import annotations

import numpy as np

from splatedit.errors import ParameterError
from splatedit.model.cloud import SplatCloud
from splatedit.render import vk as V
from splatedit.render.gpu_units import (MAX_GROUPS, displacement_bound, pack_basis_rows, pack_deform_block,
                                        selection_flags, unit_scale)
from splatedit.render.splat.layout import FLAG_DEFORMED, GEOM_STRIDE
from splatedit.render.uniforms import DETAIL_ROW, SPLAT_GEOM
from splatedit.tolerances import (RENDER_DEFAULT_COLOR, RENDER_GPU_BODY_RATIO, RENDER_GPU_BODY_SAMPLE, RENDER_MAX_BASIS_COLUMNS, RENDER_UPLOAD_CHUNK_SPLATS,
                                  RENDER_VISIBILITY_EPS_RADII)



def gpu_body_box(positions: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The box the GPU's float32 units are centred and scaled on: the full box
    (``lo``, ``hi``: (3,) model units) unless a few far points make it more
    than ``RENDER_GPU_BODY_RATIO`` times the main body across; then the main
    body's box (:func:`splatedit.model.extent.framing_extent`).  One glitch
    point 1e9 away from a 1-unit scan centred the GPU coordinates 5e8 from
    the body, where float32 steps are 32 units: the body rendered as a
    vertical strip.  The test is a strided sample's 1-99% box (a few ms at
    10M splats); the main body is computed only when it fires."""
    n = len(positions)
    full = float(np.linalg.norm(hi - lo))
    if n < 2 or full == 0.0:
        return lo, hi
    sample = positions[::max(1, n // RENDER_GPU_BODY_SAMPLE)]
    q_lo, q_hi = np.percentile(sample, [1.0, 99.0], axis=0)
    if full <= RENDER_GPU_BODY_RATIO * float(np.linalg.norm(q_hi - q_lo)):
        return lo, hi
    from splatedit.model.extent import framing_extent
    ext = framing_extent(positions)
    return (ext.lo, ext.hi) if ext.robust else (lo, hi)

class SceneUploads:
    """The scene a :class:`~splatedit.render.splat.renderer.Renderer` draws: the
    buffers filled by ``set_cloud``, ``set_selection``, ``set_basis``,
    ``set_detail``, ``clear_basis`` and ``set_displacement`` and the numbers
    that place them (origin, scale, bounds, the basis' reach).

    Args:
        dev: the :class:`splatedit.render.vk.Device` the buffers live on.
        on_rebind: called (no arguments) before a buffer that descriptor
            sets may bind (geometry, colours, flags, basis, detail) is
            destroyed or replaced; the renderer drops its pre-pass sets there.
    """

    def __init__(self, dev, on_rebind):
        self.dev = dev
        self._on_rebind = on_rebind
        #: the uploaded cloud (None before set_cloud), its splat count
        self.cloud = None
        self.n = 0
        #: model-space centre (3,) and model units per GPU unit (a power of two)
        self.origin = np.zeros(3)
        self.scale = 1.0
        #: (lo, hi) undeformed bounds padded by the largest splat radius (set_cloud)
        self.bounds = None
        #: device buffers: geometry (GEOM_STRIDE bytes per splat), colours and
        #: flags (4 bytes per splat), basis rows (64 bytes per group of 4
        #: columns per splat, or None), detail rows (DETAIL_ROW, or None)
        self.geom = self.color = self.flags = None
        self.basis_buf = None
        self.detail_buf = None
        self._cloud_bufs = []
        self._dummy_basis = {}
        self.detail_reach = 0.0
        #: basis columns K (1..16), the splats with basis rows, and the bound
        #: of _reach over them
        self.basis_cols = 4
        self.basis_rows = np.zeros(0, dtype=np.int64)
        self.basis_reach = 0.0
        #: this frame's displacement (K, 3) and handle rotations (or None);
        #: dC_dirty: not yet written to the renderer's dC uniform buffer
        self.dC = np.zeros((4, 3))
        self.rot = None
        self.dC_dirty = True

    def free(self):
        """Destroy every buffer (the scene is empty afterwards); idempotent."""
        self._on_rebind()
        for b in self._cloud_bufs:
            b.destroy()
        self._cloud_bufs = []
        self.geom = self.color = self.flags = None
        if self.basis_buf is not None:
            self.basis_buf.destroy()
            self.basis_buf = None
        self._drop_detail()
        for b in self._dummy_basis.values():
            b.destroy()
        self._dummy_basis = {}
        self.cloud = None
        self.n = 0

    def set_cloud(self, cloud: SplatCloud) -> None:
        """Upload a cloud (float32 relative to its bounding-box centre, in units
        of :attr:`scale`, a power of two near its size, so that a model of
        any size from 1e-15 to 1e15 renders the same; a model whose box a few
        glitch points blow up is centred and scaled on its main body,
        :func:`gpu_body_box`); clears selection and basis."""
        if not isinstance(cloud, SplatCloud):
            raise ParameterError("cloud", f"must be a SplatCloud, got {type(cloud).__name__}")
        self.free()
        n = cloud.n
        lo, hi = cloud.bounds()
        body_lo, body_hi = gpu_body_box(cloud.positions, lo, hi)
        self.origin = 0.5 * (body_lo + body_hi)
        # the largest semi-axis without the (n,) radii array (per-splat radii
        # are computed for the basis rows only, in _basis_radii)
        rmax = float(np.sqrt(max(np.einsum("ij,ij->i", cloud.u, cloud.u).max(),
                                 np.einsum("ij,ij->i", cloud.v, cloud.v).max())))
        #: undeformed bounds padded by the largest splat radius; near/far come
        #: from these grown by the deformation's reach (``Renderer.clip_bounds``)
        self.bounds = (lo - rmax, hi + rmax)
        #: model units per GPU unit: eye space, positions, axes and dC are
        #: divided by it (an exact power of two), depths multiplied back
        self.scale = unit_scale(float(np.linalg.norm(body_hi - body_lo)), rmax)
        self.geom = V.Buffer(self.dev, n * GEOM_STRIDE, ("vertex", "storage"))
        self._cloud_bufs.append(self.geom)
        self.color = V.Buffer(self.dev, 4 * n, ("vertex", "storage"))
        self._cloud_bufs.append(self.color)
        self._upload_cloud(cloud)
        self.flags = V.Buffer(self.dev, 4 * n, ("vertex", "storage"), host_visible=True)
        self._cloud_bufs.append(self.flags)
        self.flags.view(np.uint32)[:] = 0
        self.cloud = cloud
        self.n = n
        self.basis_rows = np.zeros(0, dtype=np.int64)
        self.basis_reach = 0.0
        self.basis_cols = 4
        self.dC = np.zeros((4, 3))
        self.rot = None
        self.dC_dirty = True

    def _upload_cloud(self, cloud: SplatCloud) -> None:
        """Geometry (float32 centre - origin, u, v in GPU units) and colours
        through one staging buffer of ``RENDER_UPLOAD_CHUNK_SPLATS`` splats:
        no whole-cloud float32 copy and no whole-cloud staging buffer (at 10M
        splats they were 360 MB each on top of the 360 MB device buffer)."""
        n = cloud.n
        chunk = min(n, RENDER_UPLOAD_CHUNK_SPLATS)
        staging = V.Buffer(self.dev, chunk * GEOM_STRIDE, ("transfer_src",), host_visible=True)
        try:
            inv = 1.0 / self.scale                   # an exact power of two
            default = np.asarray(RENDER_DEFAULT_COLOR, np.uint8)
            for lo in range(0, n, chunk):
                m = min(chunk, n - lo)
                geom = staging.view(np.uint8)[:m * GEOM_STRIDE].view(SPLAT_GEOM)   # m records
                np.multiply(cloud.positions[lo:lo + m] - self.origin, inv, out=geom["center"],
                            casting="same_kind")
                np.multiply(cloud.u[lo:lo + m], inv, out=geom["u"], casting="same_kind")
                np.multiply(cloud.v[lo:lo + m], inv, out=geom["v"], casting="same_kind")
                self.dev.submit(lambda cb: cb.copy_buffer(staging, self.geom, m * GEOM_STRIDE, 0,
                                                          lo * GEOM_STRIDE))
                col = staging.view(np.uint8)[:4 * m].reshape(m, 4)
                col[:] = default if cloud.colors is None else cloud.colors[lo:lo + m]
                self.dev.submit(lambda cb: cb.copy_buffer(staging, self.color, 4 * m, 0, 4 * lo))
        finally:
            staging.destroy()

    def _basis_radii(self, idx: np.ndarray) -> np.ndarray:
        """(N,) float64 larger semi-axis of the splats ``idx`` (model units)."""
        u, v = self.cloud.u[idx], self.cloud.v[idx]
        return np.sqrt(np.maximum(np.einsum("ij,ij->i", u, u), np.einsum("ij,ij->i", v, v)))

    @property
    def basis_groups(self) -> int:
        """Groups of 4 columns of the (zero-padded) basis."""
        return (self.basis_cols + 3) // 4

    def require_cloud(self):
        """Raise ParameterError when no cloud is set."""
        if self.cloud is None:
            raise ParameterError("cloud", "no cloud set (call set_cloud first)")

    def set_selection(self, support_mask=None, handle_mask=None, inactive_mask=None) -> None:
        """Tint the support region (blue) and handle (green); boolean masks of
        shape (n,) or index arrays; None clears.  ``inactive_mask``: splats
        of inactive handles, tinted green and drawn darker."""
        self.require_cloud()
        tint = selection_flags(self.n, support_mask, handle_mask, inactive_mask)
        f = self.flags.view(np.uint32)
        f &= np.uint32(FLAG_DEFORMED)
        f |= tint

    def set_basis(self, indices, B, Bx, By, Bz) -> None:
        """Deformation basis rows for the splats ``indices`` (N,); B, Bx, By, Bz
        are (N, K) with any K in 1..``RENDER_MAX_BASIS_COLUMNS`` (16), e.g.
        4 per rigid handle or k+1 spline control points; they are zero-padded
        to a multiple of 4 columns internally.  Other splats are not deformed.
        Only the given rows (and the rows of the previous basis, which are
        cleared) are written to the GPU.  A new K resets the displacement to
        zeros (K, 3).  Drops a :meth:`set_detail` (set it again after this)."""
        self.require_cloud()
        self._drop_detail()
        idx = np.asarray(indices, dtype=np.int64).reshape(-1)
        mats = []
        for name, m in (("B", B), ("Bx", Bx), ("By", By), ("Bz", Bz)):
            a = np.asarray(m, dtype=np.float64)
            if a.ndim != 2 or a.shape[0] != len(idx):
                raise ParameterError(name, f"must have shape ({len(idx)}, K), got {a.shape}")
            mats.append(a)
        k = mats[0].shape[1]
        if any(a.shape[1] != k for a in mats):
            raise ParameterError("B", "B, Bx, By, Bz must have the same number of columns")
        if not 1 <= k <= RENDER_MAX_BASIS_COLUMNS:
            raise ParameterError("B", f"basis must have 1..{RENDER_MAX_BASIS_COLUMNS} columns "
                                      f"(RENDER_MAX_BASIS_COLUMNS), got {k}")
        if len(idx) and (idx.min() < 0 or idx.max() >= self.n):
            raise ParameterError("indices", f"must be in 0..{self.n - 1}")
        if len(np.unique(idx)) != len(idx):
            raise ParameterError("indices", "must not repeat")
        if not all(np.isfinite(a).all() for a in mats):
            raise ParameterError("B", "basis rows must be finite")
        g = (k + 3) // 4
        row_bytes = 64 * g
        if self.basis_buf is None or self.basis_groups != g:
            if self.basis_buf is not None:
                self.basis_buf.destroy()
                self.basis_buf = None
            self._on_rebind()
            self.basis_buf = V.Buffer(self.dev, self.n * row_bytes, ("vertex", "storage"), host_visible=True)
            self.basis_buf.view(np.float32)[:] = 0.0
            self.basis_rows = np.zeros(0, dtype=np.int64)
        if self.basis_cols != k:
            self.basis_cols = k
        if self.dC.shape[0] != k:
            self.dC = np.zeros((k, 3))
            self.rot = None
            self.dC_dirty = True
        # gradients per GPU unit (positions are divided by scale); B is unitless
        rows = pack_basis_rows(mats, self.scale)[:len(idx)]
        view = self.basis_buf.view(np.float32).reshape(self.n, 16 * g)
        flags = self.flags.view(np.uint32)
        stale = np.setdiff1d(self.basis_rows, idx, assume_unique=True)
        if len(stale):
            view[stale] = 0.0
            flags[stale] &= np.uint32(~FLAG_DEFORMED & 0xFFFFFFFF)
        view[idx] = rows.reshape(len(idx), 16 * g)
        flags[idx] |= np.uint32(FLAG_DEFORMED)
        self.basis_rows = idx
        self.basis_reach = self._reach(idx, *mats)

    def _reach(self, idx, B, Bx, By, Bz) -> float:
        """max over the rows i of sum_k |B_ik| + (1 + RENDER_VISIBILITY_EPS_RADII)
        r_i sum_k |grad B_ik|: times max_k |dC_k| it bounds how far any part of
        a deformed splat (or its visibility-pass copy) can move.

        Splat i's centre moves by |sum_k B_ik dC_k| <= sum_k |B_ik| |dC_k|.  Its
        axes become J u, J v with J = I + sum_k dC_k (grad B_ik)^T, so its
        radius grows by at most r_i ||J - I|| <= r_i sum_k |dC_k| |grad B_ik|;
        the visibility pass pushes the splat back by RENDER_VISIBILITY_EPS_RADII
        of its new radius, which grows by the same factor."""
        if not len(idx):
            return 0.0
        grad = np.sqrt(Bx * Bx + By * By + Bz * Bz).sum(axis=1)
        per_row = np.abs(B).sum(axis=1) + (1.0 + RENDER_VISIBILITY_EPS_RADII) * self._basis_radii(idx) * grad
        return float(per_row.max())

    def set_detail(self, indices, detail) -> None:
        """Detail-preserving mode (splatedit.deform.detail): ``detail`` (N, 4)
        = (base normal n_b, offset lambda in model units) of the splats
        ``indices``, whose :meth:`set_basis` rows were evaluated at their base
        points b = p - lambda n_b.  Uploaded once; per frame only dC changes.
        Drawn by the compute pre-pass (images up to 4095 pixels); cleared by
        :meth:`clear_basis` and :meth:`set_cloud`."""
        self.require_cloud()
        idx = np.asarray(indices, dtype=np.int64).reshape(-1)
        d = np.asarray(detail, dtype=np.float64)
        if d.shape != (len(idx), 4):
            raise ParameterError("detail", f"must have shape ({len(idx)}, 4), got {d.shape}")
        if not np.isfinite(d).all():
            raise ParameterError("detail", "must be finite")
        if len(idx) and (idx.min() < 0 or idx.max() >= self.n):
            raise ParameterError("indices", f"must be in 0..{self.n - 1}")
        if self.detail_buf is None:
            self._on_rebind()
            self.detail_buf = V.Buffer(self.dev, self.n * DETAIL_ROW.itemsize, ("storage",), host_visible=True)
        view = self.detail_buf.view(np.uint8)[:self.n * DETAIL_ROW.itemsize].view(DETAIL_ROW)
        view.view(np.float32)[:] = 0.0
        view["normal"][idx] = d[:, :3]
        view["lam"][idx] = d[:, 3] / self.scale
        # an offset swings by at most 2 |lambda| when its normal turns (clip bounds)
        self.detail_reach = 2.0 * float(np.abs(d[:, 3]).max(initial=0.0))

    def _drop_detail(self):
        if self.detail_buf is not None:
            self._on_rebind()
            self.detail_buf.destroy()
            self.detail_buf = None
        self.detail_reach = 0.0

    def clear_basis(self) -> None:
        """Drop the deformation basis (every splat undeformed)."""
        self._drop_detail()
        if self.cloud is None or self.basis_buf is None:
            return
        flags = self.flags.view(np.uint32)
        flags[self.basis_rows] &= np.uint32(~FLAG_DEFORMED & 0xFFFFFFFF)
        self.basis_buf.view(np.float32).reshape(self.n, -1)[self.basis_rows] = 0.0
        self.basis_rows = np.zeros(0, dtype=np.int64)
        self.basis_reach = 0.0

    def set_displacement(self, dC) -> None:
        """Control-frame displacement dC (K, 3), K = the basis' column count
        (K = 4 before any :meth:`set_basis`).  Only dC (192 bytes) is uploaded
        to the GPU, when the next frame is recorded; that frame's near/far
        planes are chosen from the model bounds grown by the largest possible
        splat displacement (``Renderer.clip_bounds``), so geometry moved outside
        the undeformed model is not clipped."""
        # imported here: the deform package (scipy.linalg) costs a one-shot
        # `splatedit render` 0.4-0.9 s of start-up it does not need undeformed
        from splatedit.deform.rotation import split_displacement
        a, rot = split_displacement(dC)
        if rot is not None and len(rot.rotations) > MAX_GROUPS:
            raise ParameterError("dC", f"the renderer blends at most {MAX_GROUPS} handle rotations")
        a = np.asarray(a, dtype=np.float64)
        if a.ndim != 2 or a.shape[1] != 3 or a.shape[0] != self.basis_cols:
            raise ParameterError("dC", f"must have shape ({self.basis_cols}, 3) (the basis has "
                                       f"{self.basis_cols} columns), got {a.shape}")
        if not np.isfinite(a).all():
            raise ParameterError("dC", "must be finite")
        self.dC = a.copy()
        self.rot = rot
        self.dC_dirty = True

    def displacement_reach(self) -> float:
        """A bound (model units) on how far any splat is moved from its uploaded
        position by the current basis and displacement (0 without a basis)."""
        if not len(self.basis_rows):
            return 0.0
        move = displacement_bound(self.dC, self.rot)
        return self.basis_reach * move + (self.detail_reach if move > 0 else 0.0)

    @property
    def deformed(self) -> bool:
        """Whether some splat carries a basis row (the vertex path binds the basis)."""
        return self.basis_buf is not None and len(self.basis_rows) > 0

    def deform_block(self) -> np.ndarray:
        """deform.glsl's block of this frame's dC and handle rotations in GPU
        units (:func:`splatedit.render.gpu_units.pack_deform_block`)."""
        return pack_deform_block(self.dC, self.rot, self.scale)

    def basis_binding(self):
        """The buffer bound as the basis rows: the basis, or (nothing deformed)
        a zero dummy of one row of the current column groups."""
        if self.deformed:
            return self.basis_buf
        g = self.basis_groups
        buf = self._dummy_basis.get(g)
        if buf is None:
            buf = self._dummy_basis[g] = V.Buffer(self.dev, 64 * g, ("vertex", "storage"), host_visible=True)
            buf.view(np.float32)[:] = 0.0
        return buf
