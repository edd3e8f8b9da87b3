"""EWA surface-splat renderer with GPU deformation (Botsch & Kobbelt 2005, Sect. 7).

Three passes per frame (Botsch, Hornung, Zwicker, Kobbelt 2005):

1. visibility: depth only, splats pushed back by epsilon along the view ray;
2. attributes: depth test against pass 1 without depth writes, additive
   blending of weight*colour, weight*normal, weight*depth and weight into
   float targets;
3. shading: full-screen normalisation, deferred Phong with a headlight,
   background, gamma; it writes a :class:`RenderTarget` (an offscreen RGBA8
   image here; a swapchain image for the editor).

One vertex shader (``shaders_glsl/splat_vs.glsl``) serves both splat passes
and the picking pass; it applies the deformation p' = p + B dC, u' = J u,
v' = J v of splats that carry a basis row.

Only :mod:`splatedit.render.vk` calls Vulkan.
"""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np

from splatedit.deform.rotation import split_displacement
from splatedit.errors import ParameterError
from splatedit.model.cloud import SplatCloud
from splatedit.render import vk as V
from splatedit.render.camera import Camera
from splatedit.render.uniforms import FRAME_UBO
from splatedit.tolerances import (RENDER_BACKGROUND, RENDER_DEFAULT_COLOR, RENDER_GAMMA, RENDER_GAUSS_SHARPNESS,
                                  RENDER_GREY_ALBEDO,
                                  RENDER_LIGHT, RENDER_LOWPASS_RADIUS_PX, RENDER_MAX_BASIS_COLUMNS,
                                  RENDER_MIN_WEIGHT, RENDER_POINT_SPLAT_MAX_PX, RENDER_PREPASS_WINDOW_SPLATS,
                                  RENDER_TINT_HANDLE, RENDER_TINT_SUPPORT,
                                  RENDER_UPLOAD_CHUNK_SPLATS, RENDER_VISIBILITY_EPS_RADII)

#: per-splat flag bits (shaders_glsl/frame.glsl)
FLAG_SUPPORT = 1
FLAG_HANDLE = 2
FLAG_DEFORMED = 4
FLAG_INACTIVE = 8            # an inactive handle (the editor's several handles): darker

_UBO_BYTES = FRAME_UBO.itemsize   # splatedit/render/uniforms.py, checked against frame.glsl
_GEOM_STRIDE = 36           # centre, u, v as float32
_MAX_SIZE = 16384

#: dC of up to 16 columns as 3 vec4 per group of 4, then per group the handle
#: rotation as 4 vec4 (axis + angle, frame offsets; shaders_glsl/deform.glsl)
_MAX_GROUPS = (RENDER_MAX_BASIS_COLUMNS + 3) // 4
_DEFORM_UBO_BYTES = 48 * _MAX_GROUPS + 64 * _MAX_GROUPS
#: vertex path: frame UBO, deformation UBO
_SPLAT_SET = (V.Binding(0, "uniform", "vert|frag"), V.Binding(1, "uniform", "vert"))
#: compute pre-pass + prepared draws: frame UBO, cloud (geometry, colours,
#: flags, basis), records A/B, indirect draw commands, deformation UBO
_PREP_SET = (V.Binding(0, "uniform", "vert|frag|comp"), V.Binding(1, "storage", "comp"),
             V.Binding(2, "storage", "comp"), V.Binding(3, "storage", "comp"), V.Binding(4, "storage", "comp"),
             V.Binding(5, "storage", "vert|comp"), V.Binding(6, "storage", "vert|comp"),
             V.Binding(7, "storage", "comp"), V.Binding(8, "uniform", "comp"))
#: the detail mode's pre-pass adds (n_b, lambda) per splat (shaders_glsl/detail.glsl)
_PREP_SET_DETAIL = _PREP_SET + (V.Binding(9, "storage", "comp"),)
_REC_A_BYTES = 48
_REC_B_BYTES = 32
_WORKGROUP = 64
#: the pre-pass packs quad bounds as 12.4 fixed-point pixels
_PREP_MAX_SIZE = 4095
_RESOLVE_SET = (V.Binding(0, "uniform", "frag"), V.Binding(1, "sampled", "frag"),
                V.Binding(2, "sampled", "frag"))

_RP_DEPTH = V.RenderPassDesc(depth=V.Attachment("d32f", "clear", final="depth"))
_RP_POINTS = V.RenderPassDesc(colors=(V.Attachment("rgba8", "clear", final="color"),),
                              depth=V.Attachment("d32f", "clear", final="depth"))
_RP_PICK = V.RenderPassDesc(colors=(V.Attachment("r32ui", "clear", final="transfer_src"),),
                            depth=V.Attachment("d32f", "clear", final="transfer_src"))


def _rp_window(desc: V.RenderPassDesc, first: bool, last: bool) -> V.RenderPassDesc:
    """``desc`` for one splat window of a windowed pre-pass frame: windows after
    the first load what the previous one left instead of clearing it, and all
    but the last leave the attachments in attachment layouts."""
    def att(a: V.Attachment, layout: str) -> V.Attachment:
        if not first and a.load == "clear":
            a = replace(a, load="load", initial=layout)
        return a if last else replace(a, final=layout)
    return replace(desc, colors=tuple(att(a, "color") for a in desc.colors),
                   depth=None if desc.depth is None else att(desc.depth, "depth"))


def _rp_attr(fmt: str, final: str) -> V.RenderPassDesc:
    return V.RenderPassDesc(colors=(V.Attachment(fmt, "clear", final=final),
                                    V.Attachment(fmt, "clear", final=final)),
                            depth=V.Attachment("d32f", "load", initial="depth", final="depth"))


class RenderTarget:
    """Where the shading pass writes: anything with ``view``, ``layout``,
    ``width``, ``height``, a format name and the layout to leave it in
    (``final``: ``"transfer_src"`` for readback, ``"present"`` for a swapchain)."""

    _serials = itertools.count(1)

    def __init__(self, attachment, fmt: str, final: str, apply_gamma: bool = True):
        #: never reused (unlike id()): the key of the framebuffers cached for it
        self.serial = next(RenderTarget._serials)
        self.attachment = attachment
        self.format = fmt
        self.final = final
        self.apply_gamma = apply_gamma

    @property
    def width(self):
        return self.attachment.width

    @property
    def height(self):
        return self.attachment.height


class _Targets:
    """Per-size images and framebuffers.  A failure part-way (an image too
    large for the device) destroys what was already created."""

    def __init__(self, r: "Renderer", width: int, height: int):
        self.width, self.height = width, height
        self.objects = []
        self.target_fbs = {}      # target.serial -> (target, framebuffer)
        try:
            self._create(r)
        except BaseException:
            self.destroy()
            raise

    def _create(self, r: "Renderer"):
        dev = r.dev
        width, height = self.width, self.height

        def img(fmt, usage):
            im = V.Image(dev, width, height, fmt, usage)
            self.objects.append(im)
            return im

        self.depth = img("d32f", ("depth", "transfer_src"))
        self.accum_color = img(r.accum_format, ("color", "sampled", "transfer_src"))
        self.accum_normal = img(r.accum_format, ("color", "sampled", "transfer_src"))
        self.out = img("rgba8", ("color", "transfer_src"))
        self.offscreen = RenderTarget(self.out, "rgba8", "transfer_src")
        rp_depth = r.cache.render_pass(_RP_DEPTH)
        rp_attr = r.cache.render_pass(_rp_attr(r.accum_format, "shader_read"))
        self.fb_depth = self._fb(dev, rp_depth, [self.depth])
        self.fb_attr = self._fb(dev, rp_attr, [self.accum_color, self.accum_normal, self.depth])
        self.resolve_set = V.DescriptorSet(dev, r.cache.set_layout(_RESOLVE_SET))
        self.objects.append(self.resolve_set)
        self.resolve_set.write({0: r.ubo, 1: (self.accum_color, r.sampler), 2: (self.accum_normal, r.sampler)})
        self.pick_index = self.pick_depth = self.fb_pick = None
        self._r = r

    def _fb(self, dev, rp, atts):
        fb = V.Framebuffer(dev, rp, atts, self.width, self.height)
        self.objects.append(fb)
        return fb

    def target_fb(self, target: RenderTarget):
        hit = self.target_fbs.get(target.serial)
        if hit is None:
            rp = self._r.cache.render_pass(_rp_resolve(target))
            fb = self._fb(self._r.dev, rp, [target.attachment])
            hit = self.target_fbs[target.serial] = (target, fb)
        return hit[1]

    def ensure_pick(self):
        if self.fb_pick is None:
            dev = self._r.dev
            first = len(self.objects)
            try:
                self.pick_index = V.Image(dev, self.width, self.height, "r32ui", ("color", "transfer_src"))
                self.objects.append(self.pick_index)
                self.pick_depth = V.Image(dev, self.width, self.height, "d32f", ("depth", "transfer_src"))
                self.objects.append(self.pick_depth)
                self.fb_pick = self._fb(dev, self._r.cache.render_pass(_RP_PICK),
                                        [self.pick_index, self.pick_depth])
            except BaseException:
                for o in reversed(self.objects[first:]):
                    o.destroy()
                del self.objects[first:]
                self.pick_index = self.pick_depth = self.fb_pick = None
                raise

    def destroy(self):
        for o in reversed(self.objects):
            o.destroy()
        self.objects.clear()
        self.target_fbs.clear()


class _Prep:
    """Buffers and descriptor sets of the compute pre-pass: one set per basis
    window inside each splat window (one splat window when the cloud fits one
    storage binding)."""

    def __init__(self, objects, dset, rec_a, rec_b, draws, windows):
        self.objects = objects
        self.dset, self.rec_a, self.rec_b, self.draws = dset, rec_a, rec_b, draws
        #: per splat window: (first splat, count, [(descriptor set, first splat, count)])
        self.windows = windows


def _rp_resolve(target: RenderTarget) -> V.RenderPassDesc:
    return V.RenderPassDesc(colors=(V.Attachment(target.format, "dont_care", final=target.final),))


class Renderer:
    """Offscreen EWA splat renderer owning its Vulkan device.

    Use as a context manager or call :meth:`close`.  Typical use::

        with Renderer() as r:
            r.set_cloud(cloud)
            img = r.render(Camera.frame(*cloud.bounds(), 1.0), 256, 256)

    Args:
        device_name: substring of the Vulkan device name (default: env var
            ``SPLATEDIT_DEVICE`` or the first GPU / lavapipe).
        validation: Vulkan validation layer on/off (default: env var
            ``SPLATEDIT_VALIDATION``).
        accum_format: ``"rgba16f"`` or ``"rgba32f"`` attribute accumulators.
        backface_culling: skip splats whose normal faces away from the eye.
        background: sRGB background colour (3 floats in 0..1).
        point_splats: draw small splats (footprint within
            ``RENDER_POINT_SPLAT_MAX_PX`` pixels of the projected centre, see
            splatedit.tolerances; the threshold is the attribute
            ``point_max_px``) as one square POINT_LIST point each, of side
            twice that extent, centred at the projected centre: one vertex
            instead of a 4-vertex strip, the same fragment shader and the
            same covered pixels as the quad (hole-free), the others as quads.
        prepass: do the per-splat work (deformation, culling, screen setup)
            once per frame in a compute pre-pass that writes compact records;
            both splat passes then draw them indirectly with a fetch-only
            vertex shader (``prepared.vert``).  Off: every vertex of both
            passes runs ``splat.vert``.  A cloud whose records or geometry
            exceed the device's storage-buffer range (2.8M splats on
            lavapipe) is prepared and drawn in windows of
            ``RENDER_PREPASS_WINDOW_SPLATS`` splats:
            each pass runs the pre-pass of a window, then draws it.
        device: share an existing :class:`splatedit.render.vk.Device` (then
            the renderer does not close it).
    """

    def __init__(self, *, device_name: str | None = None, validation: bool | None = None,
                 accum_format: str = "rgba16f", backface_culling: bool = True,
                 background=RENDER_BACKGROUND, point_splats: bool = True, prepass: bool = True,
                 device: V.Device | None = None):
        if accum_format not in ("rgba16f", "rgba32f"):
            raise ParameterError("accum_format", f"must be 'rgba16f' or 'rgba32f', got {accum_format!r}")
        self.accum_format = accum_format
        self.backface_culling = bool(backface_culling)
        self.point_splats = bool(point_splats)
        #: point path threshold (pixels), see ``point_splats``
        self.point_max_px = float(RENDER_POINT_SPLAT_MAX_PX)
        self.prepass = bool(prepass)
        #: display mode: False shaded colours; True the distortion heat map
        #: (stretch of every deformed splat from the same Jacobian the pass
        #: applies, shaders_glsl/distortion.glsl; 1x neutral grey, 1.5x yellow,
        #: 2x orange, 3x red, 4x+ dark red; splats outside the support grey)
        self.distortion_map = False
        #: multiply every splat's axes by this (display only; the editor's splat size)
        self.splat_scale = 1.0
        #: shade a uniform grey instead of the file's colours (RENDER_GREY_ALBEDO)
        self.grey_shading = False
        self._prep = None             # _Prep of the compute pre-pass
        self.background = tuple(float(x) for x in background)
        #: alpha of background pixels in the output (0: uncovered pixels are
        #: told apart, as :mod:`splatedit.render.progressive` does)
        self.background_alpha = 1.0
        #: frames recorded so far (a progressive frame restarts when another
        #: frame has used the shared targets in between)
        self.frames_recorded = 0
        self._own_device = device is None
        self.dev = device if device is not None else V.Device(device_name=device_name, validation=validation)
        self._closed = False
        self.cache = self.sampler = self.ubo = self.splat_set = None
        self._targets = None
        self._cloud_bufs = []
        self._basis_buf = None
        self._detail_buf = None       # (n_b, lambda / scale) per splat, see set_detail
        self._detail_reach = 0.0
        self._dummy_basis = {}
        self.cloud = None
        self.origin = np.zeros(3)
        self.scale = 1.0
        self.n = 0
        self._basis_cols = 4
        self._basis_rows = np.zeros(0, dtype=np.int64)
        self._basis_reach = 0.0       # see _clip_bounds
        self._dC = np.zeros((4, 3))
        self._rot = None            # RotationDisplacement of the frame, or None
        self._dC_dirty = True
        self.dC_ubo = None
        self.last_timings_ms: dict[str, float] = {}
        self._query = None
        self._max_point_size = float(self.dev.limits.pointSizeRange[1]) if self.dev.features.largePoints else 1.0
        try:
            self.cache = V.PipelineCache(self.dev)
            self.sampler = V.Sampler(self.dev)
            self.ubo = V.Buffer(self.dev, _UBO_BYTES, ("uniform",), host_visible=True)
            self.dC_ubo = V.Buffer(self.dev, _DEFORM_UBO_BYTES, ("uniform",), host_visible=True)
            self.dC_ubo.view(np.float32)[:] = 0.0
            self.splat_set = V.DescriptorSet(self.dev, self.cache.set_layout(_SPLAT_SET))
            self.splat_set.write({0: self.ubo, 1: self.dC_ubo})
            self._query = V.QueryPool(self.dev, 8)
        except BaseException:
            try:
                self.close()
            except Exception:    # noqa: BLE001 - the construction error is the one to report
                pass
            raise

    # ------------------------------------------------------------ lifecycle
    def close(self) -> None:
        """Destroy every Vulkan object (reverse creation order); idempotent.

        Teardown runs to the end even when a step fails (``wait_idle`` after a
        device loss: destroying objects of a lost device is still valid); the
        first error is raised afterwards."""
        if self._closed:
            return
        self._closed = True
        errors = []

        def step(fn):
            try:
                fn()
            except Exception as e:   # noqa: BLE001 - re-raised below, after the whole teardown
                errors.append(e)

        if self.dev.device is not None:
            step(self.dev.wait_idle)
        step(self._free_cloud)
        if self._targets is not None:
            step(self._targets.destroy)
            self._targets = None
        for obj in (self._query, self.splat_set, self.dC_ubo, self.ubo, self.sampler):
            if obj is not None:
                step(obj.destroy)
        if self.cache is not None:
            step(self.cache.destroy)
        if self._own_device:
            step(self.dev.close)
        if errors:
            raise errors[0]

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        try:
            self.close()
        except Exception:
            if exc_type is None:
                raise            # else: let the exception of the with-block propagate

    def _check_open(self):
        if self._closed:
            raise ParameterError("renderer", "is closed")

    # -------------------------------------------------------------- scene
    def _free_prep(self):
        if self._prep is not None:
            for obj in reversed(self._prep.objects):
                obj.destroy()
            self._prep = None

    def _free_cloud(self):
        self._free_prep()
        for b in self._cloud_bufs:
            b.destroy()
        self._cloud_bufs = []
        if self._basis_buf is not None:
            self._basis_buf.destroy()
            self._basis_buf = None
        self._drop_detail()
        for b in self._dummy_basis.values():
            b.destroy()
        self._dummy_basis = {}
        self.cloud = None
        self.n = 0

    def set_cloud(self, cloud: SplatCloud) -> None:
        """Upload a cloud (float32 relative to its bounding-box centre, in units
        of :attr:`scale`, a power of two near its size, so that a model of
        any size from 1e-15 to 1e15 renders the same); clears selection and
        basis."""
        self._check_open()
        if not isinstance(cloud, SplatCloud):
            raise ParameterError("cloud", f"must be a SplatCloud, got {type(cloud).__name__}")
        self._free_cloud()
        n = cloud.n
        lo, hi = cloud.bounds()
        self.origin = 0.5 * (lo + hi)
        # the largest semi-axis without the (n,) radii array (per-splat radii
        # are computed for the basis rows only, in _basis_radii)
        rmax = float(np.sqrt(max(np.einsum("ij,ij->i", cloud.u, cloud.u).max(),
                                 np.einsum("ij,ij->i", cloud.v, cloud.v).max())))
        #: undeformed bounds padded by the largest splat radius; near/far come
        #: from these grown by the deformation's reach (:meth:`_clip_bounds`)
        self.bounds = (lo - rmax, hi + rmax)
        #: model units per GPU unit: eye space, positions, axes and dC are
        #: divided by it (an exact power of two), depths multiplied back
        self.scale = _unit_scale(float(np.linalg.norm(hi - lo)), rmax)
        self._geom = V.Buffer(self.dev, n * _GEOM_STRIDE, ("vertex", "storage"))
        self._cloud_bufs.append(self._geom)
        self._color = V.Buffer(self.dev, 4 * n, ("vertex", "storage"))
        self._cloud_bufs.append(self._color)
        self._upload_cloud(cloud)
        self._flags = V.Buffer(self.dev, 4 * n, ("vertex", "storage"), host_visible=True)
        self._cloud_bufs.append(self._flags)
        self._flags.view(np.uint32)[:] = 0
        self.cloud = cloud
        self.n = n
        self._basis_rows = np.zeros(0, dtype=np.int64)
        self._basis_reach = 0.0
        self._basis_cols = 4
        self._dC = np.zeros((4, 3))
        self._rot = None
        self._dC_dirty = True

    def _upload_cloud(self, cloud: SplatCloud) -> None:
        """Geometry (float32 centre - origin, u, v in GPU units) and colours
        through one staging buffer of ``RENDER_UPLOAD_CHUNK_SPLATS`` splats:
        no whole-cloud float32 copy and no whole-cloud staging buffer (at 10M
        splats they were 360 MB each on top of the 360 MB device buffer)."""
        n = cloud.n
        chunk = min(n, RENDER_UPLOAD_CHUNK_SPLATS)
        staging = V.Buffer(self.dev, chunk * _GEOM_STRIDE, ("transfer_src",), host_visible=True)
        try:
            inv = 1.0 / self.scale                   # an exact power of two
            default = np.asarray(RENDER_DEFAULT_COLOR, np.uint8)
            for lo in range(0, n, chunk):
                m = min(chunk, n - lo)
                geom = staging.view(np.float32)[:9 * m].reshape(m, 9)
                np.multiply(cloud.positions[lo:lo + m] - self.origin, inv, out=geom[:, 0:3],
                            casting="same_kind")
                np.multiply(cloud.u[lo:lo + m], inv, out=geom[:, 3:6], casting="same_kind")
                np.multiply(cloud.v[lo:lo + m], inv, out=geom[:, 6:9], casting="same_kind")
                self.dev.submit(lambda cb: cb.copy_buffer(staging, self._geom, m * _GEOM_STRIDE, 0,
                                                          lo * _GEOM_STRIDE))
                col = staging.view(np.uint8)[:4 * m].reshape(m, 4)
                col[:] = default if cloud.colors is None else cloud.colors[lo:lo + m]
                self.dev.submit(lambda cb: cb.copy_buffer(staging, self._color, 4 * m, 0, 4 * lo))
        finally:
            staging.destroy()

    def _basis_radii(self, idx: np.ndarray) -> np.ndarray:
        """(N,) float64 larger semi-axis of the splats ``idx`` (model units)."""
        u, v = self.cloud.u[idx], self.cloud.v[idx]
        return np.sqrt(np.maximum(np.einsum("ij,ij->i", u, u), np.einsum("ij,ij->i", v, v)))

    @property
    def _basis_groups(self) -> int:
        """Groups of 4 columns of the (zero-padded) basis."""
        return (self._basis_cols + 3) // 4

    def _require_cloud(self):
        if self.cloud is None:
            raise ParameterError("cloud", "no cloud set (call set_cloud first)")

    def _mask(self, name, mask):
        if mask is None:
            return np.zeros(self.n, dtype=bool)
        m = np.asarray(mask)
        if m.dtype == bool:
            if m.shape != (self.n,):
                raise ParameterError(name, f"boolean mask must have shape ({self.n},), got {m.shape}")
            return m
        idx = m.astype(np.int64).reshape(-1)
        if len(idx) and (idx.min() < 0 or idx.max() >= self.n):
            raise ParameterError(name, f"indices must be in 0..{self.n - 1}")
        out = np.zeros(self.n, dtype=bool)
        out[idx] = True
        return out

    def set_selection(self, support_mask=None, handle_mask=None, inactive_mask=None) -> None:
        """Tint the support region (blue) and handle (green); boolean masks of
        shape (n,) or index arrays; None clears.  ``inactive_mask``: splats
        of inactive handles, tinted green and drawn darker."""
        self._check_open()
        self._require_cloud()
        s = self._mask("support_mask", support_mask)
        h = self._mask("handle_mask", handle_mask)
        i = self._mask("inactive_mask", inactive_mask)
        f = self._flags.view(np.uint32)
        f &= np.uint32(FLAG_DEFORMED)
        f |= ((s.astype(np.uint32) * FLAG_SUPPORT) | ((h | i).astype(np.uint32) * FLAG_HANDLE)
              | (i.astype(np.uint32) * FLAG_INACTIVE))

    def set_basis(self, indices, B, Bx, By, Bz) -> None:
        """Deformation basis rows for the splats ``indices`` (N,); B, Bx, By, Bz
        are (N, K) with any K in 1..``RENDER_MAX_BASIS_COLUMNS`` (16), e.g.
        4 per rigid handle or k+1 spline control points; they are zero-padded
        to a multiple of 4 columns internally.  Other splats are not deformed.
        Only the given rows (and the rows of the previous basis, which are
        cleared) are written to the GPU.  A new K resets the displacement to
        zeros (K, 3).  Drops a :meth:`set_detail` (set it again after this)."""
        self._check_open()
        self._require_cloud()
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
        if self._basis_buf is None or self._basis_groups != g:
            if self._basis_buf is not None:
                self._basis_buf.destroy()
                self._basis_buf = None
            self._free_prep()
            self._basis_buf = V.Buffer(self.dev, self.n * row_bytes, ("vertex", "storage"), host_visible=True)
            self._basis_buf.view(np.float32)[:] = 0.0
            self._basis_rows = np.zeros(0, dtype=np.int64)
        if self._basis_cols != k:
            self._basis_cols = k
        if self._dC.shape[0] != k:
            self._dC = np.zeros((k, 3))
            self._rot = None
            self._dC_dirty = True
        rows = np.zeros((len(idx), g, 4, 4), dtype=np.float32)
        # gradients per GPU unit (positions are divided by scale); B is unitless
        gpu_mats = [mats[0]] + [a * self.scale for a in mats[1:]]
        for j, a in enumerate(gpu_mats):
            padded = np.zeros((len(idx), 4 * g))
            padded[:, :k] = a
            rows[:, :, j, :] = padded.reshape(len(idx), g, 4)
        view = self._basis_buf.view(np.float32).reshape(self.n, 16 * g)
        flags = self._flags.view(np.uint32)
        stale = np.setdiff1d(self._basis_rows, idx, assume_unique=True)
        if len(stale):
            view[stale] = 0.0
            flags[stale] &= np.uint32(~FLAG_DEFORMED & 0xFFFFFFFF)
        view[idx] = rows.reshape(len(idx), 16 * g)
        flags[idx] |= np.uint32(FLAG_DEFORMED)
        self._basis_rows = idx
        self._basis_reach = self._reach(idx, *mats)

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

    def _clip_bounds(self):
        """The box that near/far are chosen from: the undeformed bounds grown
        by a bound on any splat's displacement (see :meth:`_reach`), so that
        geometry moved outside the model (a handle dragged towards the eye)
        is not clipped."""
        lo, hi = self.bounds
        if not len(self._basis_rows):
            return lo, hi
        move = float(np.linalg.norm(self._dC, axis=1).max(initial=0.0))
        if self._rot is not None:   # |F(s) v| <= (|sin x / x| + |(1 - cos x) / x|) angle |v| <= 2 angle |v|
            move += max(2.0 * r.angle * float(np.linalg.norm(r.offsets, axis=1).max())
                        for r in self._rot.rotations)
        grow = self._basis_reach * move + (self._detail_reach if move > 0 else 0.0)
        return lo - grow, hi + grow

    def set_detail(self, indices, detail) -> None:
        """Detail-preserving mode (splatedit.deform.detail): ``detail`` (N, 4)
        = (base normal n_b, offset lambda in model units) of the splats
        ``indices``, whose :meth:`set_basis` rows were evaluated at their base
        points b = p - lambda n_b.  Uploaded once; per frame only dC changes.
        Drawn by the compute pre-pass (images up to 4095 pixels); cleared by
        :meth:`clear_basis` and :meth:`set_cloud`."""
        self._check_open()
        self._require_cloud()
        idx = np.asarray(indices, dtype=np.int64).reshape(-1)
        d = np.asarray(detail, dtype=np.float64)
        if d.shape != (len(idx), 4):
            raise ParameterError("detail", f"must have shape ({len(idx)}, 4), got {d.shape}")
        if not np.isfinite(d).all():
            raise ParameterError("detail", "must be finite")
        if len(idx) and (idx.min() < 0 or idx.max() >= self.n):
            raise ParameterError("indices", f"must be in 0..{self.n - 1}")
        if self._detail_buf is None:
            self._free_prep()
            self._detail_buf = V.Buffer(self.dev, self.n * 16, ("storage",), host_visible=True)
        view = self._detail_buf.view(np.float32).reshape(self.n, 4)
        view[:] = 0.0
        view[idx, :3] = d[:, :3]
        view[idx, 3] = d[:, 3] / self.scale
        # an offset swings by at most 2 |lambda| when its normal turns (clip bounds)
        self._detail_reach = 2.0 * float(np.abs(d[:, 3]).max(initial=0.0))

    def _drop_detail(self):
        if self._detail_buf is not None:
            self._free_prep()
            self._detail_buf.destroy()
            self._detail_buf = None
        self._detail_reach = 0.0

    def clear_basis(self) -> None:
        """Drop the deformation basis (every splat undeformed)."""
        self._check_open()
        self._drop_detail()
        if self.cloud is None or self._basis_buf is None:
            return
        flags = self._flags.view(np.uint32)
        flags[self._basis_rows] &= np.uint32(~FLAG_DEFORMED & 0xFFFFFFFF)
        self._basis_buf.view(np.float32).reshape(self.n, -1)[self._basis_rows] = 0.0
        self._basis_rows = np.zeros(0, dtype=np.int64)
        self._basis_reach = 0.0

    def set_displacement(self, dC) -> None:
        """Control-frame displacement dC (K, 3), K = the basis' column count
        (K = 4 before any :meth:`set_basis`).  Only dC (192 bytes) is uploaded
        to the GPU, when the next frame is recorded; that frame's near/far
        planes are chosen from the model bounds grown by the largest possible
        splat displacement (:meth:`_clip_bounds`), so geometry moved outside
        the undeformed model is not clipped."""
        self._check_open()
        a, rot = split_displacement(dC)
        if rot is not None and len(rot.rotations) > _MAX_GROUPS:
            raise ParameterError("dC", f"the renderer blends at most {_MAX_GROUPS} handle rotations")
        a = np.asarray(a, dtype=np.float64)
        if a.ndim != 2 or a.shape[1] != 3 or a.shape[0] != self._basis_cols:
            raise ParameterError("dC", f"must have shape ({self._basis_cols}, 3) (the basis has "
                                       f"{self._basis_cols} columns), got {a.shape}")
        if not np.isfinite(a).all():
            raise ParameterError("dC", "must be finite")
        self._dC = a.copy()
        self._rot = rot
        self._dC_dirty = True

    def _dC_block(self) -> np.ndarray:
        """dC zero-padded to 16 columns, as rows dC[3g + i] = (dC_{4g..4g+3})[i],
        then per group g the rotation of handle g: rot[4g] = (axis, angle)
        (angle 0: none), rot[4g + 1 + i] = (offsets_{0..3})[i] (deform.glsl)."""
        pad = np.zeros((4 * _MAX_GROUPS, 3))
        pad[:len(self._dC)] = self._dC / self.scale
        dc = pad.reshape(_MAX_GROUPS, 4, 3).transpose(0, 2, 1).reshape(-1)
        rot = np.zeros((_MAX_GROUPS, 4, 4))
        if self._rot is not None:
            for g in self._rot.rotating:
                r = self._rot.rotations[g]
                rot[g, 0, :3] = r.w / r.angle
                rot[g, 0, 3] = r.angle
                rot[g, 1:, :] = (r.offsets / self.scale).T   # translation-free: no origin shift
        return np.ascontiguousarray(np.concatenate([dc, rot.reshape(-1)]), dtype=np.float32)

    # ---------------------------------------------------------- pipelines
    def _vertex_layout(self, basis_stride: int):
        g = self._basis_groups
        bindings = (V.VertexBinding(0, _GEOM_STRIDE), V.VertexBinding(1, 4), V.VertexBinding(2, 4),
                    V.VertexBinding(3, basis_stride))
        attrs = [V.VertexAttribute(0, 0, "vec3", 0), V.VertexAttribute(1, 0, "vec3", 12),
                 V.VertexAttribute(2, 0, "vec3", 24), V.VertexAttribute(3, 1, "unorm8x4", 0),
                 V.VertexAttribute(4, 2, "uint", 0)]
        attrs += [V.VertexAttribute(5 + i, 3, "vec4", 16 * i) for i in range(4 * g)]
        return bindings, tuple(attrs)

    def _splat_pipeline(self, kind: str, mode: int = 0):
        g = self._basis_groups
        deformed = self._basis_buf is not None and len(self._basis_rows) > 0
        bindings, attrs = self._vertex_layout(64 * g if deformed else 0)
        layout = V.LayoutDesc(sets=(_SPLAT_SET,))
        vert = "splat.vert" if g == 1 else f"splat_k{4 * g}.vert"
        common = dict(bindings=bindings, attributes=attrs, depth_test=True, spec=((0, mode),),
                      topology="point_list" if mode == 2 else "triangle_strip")
        if kind == "depth":
            desc = V.GraphicsDesc(vert, "splat_depth.frag", _RP_DEPTH, layout, depth_write=True,
                                  depth_compare="less", **common)
        elif kind == "attr":
            desc = V.GraphicsDesc(vert, "splat_attr.frag", _rp_attr(self.accum_format, "shader_read"), layout,
                                  depth_write=False, depth_compare="less_equal", blend_add=(True, True), **common)
        else:
            desc = V.GraphicsDesc(vert, "splat_pick.frag", _RP_PICK, layout, depth_write=True,
                                  depth_compare="less", **common)
        return self.cache.pipeline(desc)

    def _basis_binding(self):
        if self._basis_buf is not None and len(self._basis_rows) > 0:
            return self._basis_buf
        g = self._basis_groups
        buf = self._dummy_basis.get(g)
        if buf is None:
            buf = self._dummy_basis[g] = V.Buffer(self.dev, 64 * g, ("vertex", "storage"), host_visible=True)
            buf.view(np.float32)[:] = 0.0
        return buf

    def _resolve_pipeline(self, target: RenderTarget):
        layout = V.LayoutDesc(sets=(_RESOLVE_SET,))
        desc = V.GraphicsDesc("fullscreen.vert", "resolve.frag", _rp_resolve(target), layout,
                              topology="triangle_list")
        return self.cache.pipeline(desc)

    # ------------------------------------------------------------- frames
    def _targets_for(self, width: int, height: int) -> _Targets:
        for name, v in (("width", width), ("height", height)):
            if not isinstance(v, (int, np.integer)) or not 1 <= v <= _MAX_SIZE:
                raise ParameterError(name, f"must be an integer in 1..{_MAX_SIZE}, got {v!r}")
        t = self._targets
        if t is None or (t.width, t.height) != (width, height):
            if t is not None:
                self.dev.wait_idle()
                t.destroy()
                self._targets = None
            self._targets = _Targets(self, int(width), int(height))
        return self._targets

    def _write_ubo(self, camera: Camera, width: int, height: int, apply_gamma: bool = True):
        if not isinstance(camera, Camera):
            raise ParameterError("camera", f"must be a Camera, got {type(camera).__name__}")
        # everything on the GPU is in model units relative to origin, divided
        # by scale: so is the camera (a similarity: the image is the same)
        o, sc = self.origin, self.scale
        gpu_cam = Camera((camera.eye - o) / sc, (camera.target - o) / sc, up=camera.up,
                         fov_deg=camera.fov_deg, near=None if camera.near is None else camera.near / sc,
                         far=None if camera.far is None else camera.far / sc)
        lo, hi = self._clip_bounds()
        near, far = gpu_cam.clip_range((lo - o) / sc, (hi - o) / sc)
        view = gpu_cam.view_matrix()
        proj = gpu_cam.projection_matrix(width / height, near, far)
        p00, p11 = proj[0, 0], proj[1, 1]
        u = np.zeros((), FRAME_UBO)
        u["view"] = view.T                    # GLSL mat4 is column-major
        u["proj"] = proj.T
        u["viewport"] = (width, height, 1.0 / width, 1.0 / height)
        u["pix_to_ray"] = (2.0 / (width * p00), -1.0 / p00, 2.0 / (height * p11), -1.0 / p11)
        u["depth_params"] = (near, far, RENDER_VISIBILITY_EPS_RADII, RENDER_LOWPASS_RADIUS_PX)
        u["tint_support"] = RENDER_TINT_SUPPORT
        u["tint_handle"] = RENDER_TINT_HANDLE
        u["background"] = (*self.background[:3], self.background_alpha)
        u["light"] = RENDER_LIGHT
        u["misc"] = (RENDER_GAUSS_SHARPNESS, 1.0 / RENDER_GAMMA, RENDER_MIN_WEIGHT,
                     min(float(self.point_max_px), 0.5 * self._max_point_size - 0.25) if self.point_splats else -1.0)
        u["options"] = (1 if self.backface_culling else 0, 1 if apply_gamma else 0, 1 if self.distortion_map else 0, 0)
        u["display"] = (self.splat_scale, RENDER_GREY_ALBEDO if self.grey_shading else -1.0, 0.0, 0.0)
        self.ubo.write(u)
        if self._dC_dirty:
            self.dC_ubo.write(self._dC_block())
            self._dC_dirty = False
        self._near_far = (near * sc, far * sc)     # model units

    def _use_prepass(self) -> bool:
        t = self._targets
        if self._detail_buf is not None:   # the detail mode has no vertex-path variant
            if t is not None and max(t.width, t.height) > _PREP_MAX_SIZE:
                raise ParameterError("size", f"the detail mode renders images up to {_PREP_MAX_SIZE} "
                                             f"pixels wide and high, got {t.width}x{t.height}")
            return True
        if not self.prepass:
            return False
        # any size: clouds whose records (48 bytes per splat) or geometry do
        # not fit one storage binding are drawn in splat windows
        return not (t is not None and max(t.width, t.height) > _PREP_MAX_SIZE)

    @property
    def prepass_windows(self) -> int:
        """Splat windows the compute pre-pass prepares and draws the cloud in at
        the current image size: 1 when the cloud fits one storage binding, 0 for
        the vertex path (pre-pass off, images above 4095 pixels, no cloud)."""
        if self.cloud is None or not self._use_prepass():
            return 0
        return len(self._prep_windows())

    def _prep_windows(self) -> list[tuple[int, int]]:
        """(first splat, splat count) windows of the pre-pass: the whole cloud
        when its records and per-splat arrays fit one storage binding (up to
        2,796,202 splats with lavapipe's 128 MiB), else windows of
        RENDER_PREPASS_WINDOW_SPLATS (or fewer where the device limit is
        smaller), each prepared and drawn in turn."""
        limit = int(self.dev.limits.maxStorageBufferRange)
        per_splat = max(_REC_A_BYTES, _GEOM_STRIDE, 16 if self._detail_buf is not None else 0)
        if self.n * per_splat <= limit:
            return [(0, self.n)]
        align = max(int(self.dev.limits.minStorageBufferOffsetAlignment), 1)
        per = min(RENDER_PREPASS_WINDOW_SPLATS, limit // per_splat) // _WORKGROUP * _WORKGROUP
        while per > _WORKGROUP and (per * 4) % align:       # 4: the smallest per-splat stride
            per -= _WORKGROUP
        per = max(per, _WORKGROUP)
        return [(b, min(per, self.n - b)) for b in range(0, self.n, per)]

    def _basis_chunks(self, basis, first: int = 0, count: int | None = None) -> list[tuple[int, int, int, int]]:
        """(first splat, splat count, byte offset, byte range) windows of the
        basis buffer that each fit one storage binding, covering splats
        first .. first + count - 1 (all by default)."""
        count = self.n - first if count is None else count
        row_bytes = 64 * self._basis_groups
        if basis.size < self.n * row_bytes:          # the dummy (nothing deformed): one window
            return [(first, count, 0, basis.size)]
        limit = int(self.dev.limits.maxStorageBufferRange)
        align = max(int(self.dev.limits.minStorageBufferOffsetAlignment), 1)
        per = max(limit // row_bytes // _WORKGROUP * _WORKGROUP, _WORKGROUP)
        while (per * row_bytes) % align:
            per -= _WORKGROUP
        out = []
        for base in range(first, first + count, per):
            cnt = min(per, first + count - base)
            out.append((base, cnt, base * row_bytes, cnt * row_bytes))
        return out

    def _prep_objects(self):
        if self._prep is None:
            objs = []
            try:
                spans = self._prep_windows()
                slots = max(cnt for _, cnt in spans)
                rec_a = V.Buffer(self.dev, slots * _REC_A_BYTES, ("storage",))
                objs.append(rec_a)
                rec_b = V.Buffer(self.dev, slots * _REC_B_BYTES, ("storage",))
                objs.append(rec_b)
                draws = V.Buffer(self.dev, 32, ("storage", "indirect"))
                objs.append(draws)
                basis = self._basis_binding()
                detail = self._detail_buf
                windowed = len(spans) > 1
                windows = []
                for w0, wn in spans:
                    def span(buf, stride):
                        return (buf, w0 * stride, wn * stride) if windowed else buf
                    chunks = []
                    for base, cnt, off, rng in self._basis_chunks(basis, w0, wn):
                        dset = V.DescriptorSet(self.dev, self.cache.set_layout(
                            _PREP_SET if detail is None else _PREP_SET_DETAIL))
                        objs.append(dset)
                        writes = {0: self.ubo, 1: span(self._geom, _GEOM_STRIDE), 2: span(self._color, 4),
                                  3: span(self._flags, 4), 4: (basis, off, rng),
                                  5: rec_a, 6: rec_b, 7: draws, 8: self.dC_ubo}
                        if detail is not None:
                            writes[9] = span(detail, 16)
                        dset.write(writes)
                        chunks.append((dset, base, cnt))
                    windows.append((w0, wn, chunks))
            except BaseException:
                for o in reversed(objs):
                    o.destroy()
                raise
            self._prep = _Prep(objs, windows[0][2][0][0], rec_a, rec_b, draws, windows)
        return self._prep

    def _record_prepass(self, cb, window: int = 0):
        """Compute pre-pass of splat window ``window``: records + indirect draw
        counts for this frame's camera (one dispatch per basis window). Before
        any window but the first of a frame, it waits for the draws that read
        the previous window's records."""
        prep = self._prep_objects()
        w0, wn, chunks = prep.windows[window]
        g = self._basis_groups
        detail = self._detail_buf is not None
        stem = "prepare_detail" if detail else "prepare"
        comp = f"{stem}.comp" if g == 1 else f"{stem}_k{4 * g}.comp"
        layout = V.LayoutDesc(sets=(_PREP_SET_DETAIL if detail else _PREP_SET,), push_bytes=16,
                              push_stages="comp")
        pipe = self.cache.pipeline(V.ComputeDesc(comp, layout))
        if len(prep.windows) > 1:        # the previous window's draws read records and counts
            cb.memory_barrier("draw_indirect|vertex", "indirect_read|shader_read", "transfer|compute",
                              "transfer_write|shader_write")
        cb.fill_buffer(prep.draws, 0)
        cb.memory_barrier("transfer", "transfer_write", "compute", "shader_read|shader_write")
        cb.bind_pipeline(pipe)
        for j, (dset, base, cnt) in enumerate(chunks):
            if j:
                cb.memory_barrier("compute", "shader_write", "compute", "shader_read|shader_write")
            cb.bind_descriptor_set(pipe, dset)
            cb.push_constants(pipe, np.array([base, cnt, wn, w0], np.uint32))
            cb.dispatch((cnt + _WORKGROUP - 1) // _WORKGROUP)
        cb.memory_barrier("compute", "shader_write", "draw_indirect|vertex",
                          "indirect_read|shader_read")

    def _prepared_pipeline(self, kind: str, mode: int):
        layout = V.LayoutDesc(sets=(_PREP_SET if self._detail_buf is None else _PREP_SET_DETAIL,),
                              push_bytes=4, push_stages="vert")
        common = dict(depth_test=True, spec=((0, mode),),
                      topology="point_list" if mode == 2 else "triangle_strip")
        if kind == "depth":
            desc = V.GraphicsDesc("prepared.vert", "splat_depth.frag", _RP_DEPTH, layout, depth_write=True,
                                  depth_compare="less", **common)
        elif kind == "attr":
            desc = V.GraphicsDesc("prepared.vert", "splat_attr.frag", _rp_attr(self.accum_format, "shader_read"),
                                  layout, depth_write=False, depth_compare="less_equal", blend_add=(True, True),
                                  **common)
        else:
            desc = V.GraphicsDesc("prepared.vert", "splat_pick.frag", _RP_PICK, layout, depth_write=True,
                                  depth_compare="less", **common)
        return self.cache.pipeline(desc)

    def _record_splats(self, cb, kind: str, prepared: bool = False, window: int = 0):
        """Draw every splat: as quads, or (point_splats) tiny ones as points +
        the others as quads; ``prepared``: the records of pre-pass window ``window``."""
        if prepared:
            prep = self._prep_objects()
            dset, draws = prep.dset, prep.draws
            n = np.array([prep.windows[window][1]], np.uint32)
            for mode, offset in ((1, 0), (2, 16)):
                pipeline = self._prepared_pipeline(kind, mode)
                cb.bind_pipeline(pipeline)
                cb.bind_descriptor_set(pipeline, dset)
                cb.push_constants(pipeline, n)
                cb.draw_indirect(draws, offset)
            return
        modes = ((1, 4), (2, 1)) if self.point_splats else ((0, 4),)
        bufs = [self._geom, self._color, self._flags, self._basis_binding()]
        for mode, verts in modes:
            pipeline = self._splat_pipeline(kind, mode)
            cb.bind_pipeline(pipeline)
            cb.bind_descriptor_set(pipeline, self.splat_set)
            cb.bind_vertex_buffers(0, bufs)
            if verts == 4:
                cb.draw(4, self.n)
            else:
                cb.draw(1, self.n)

    def _prep_window_count(self, prepared: bool) -> int:
        """Pre-pass windows of this frame (1 for the vertex path)."""
        return len(self._prep_objects().windows) if prepared else 1

    def _record_splat_pass(self, cb, kind: str, desc: V.RenderPassDesc, fb, clears, prepared: bool):
        """One splat pass (``kind`` depth, attr or pick) into ``fb``. With several
        pre-pass windows: per window, its pre-pass then its draws (in a render
        pass that keeps the previous windows' results)."""
        count = self._prep_window_count(prepared)
        if count == 1:
            cb.begin_render_pass(self.cache.render_pass(desc), fb, clears)
            self._record_splats(cb, kind, prepared)
            cb.end_render_pass()
            return
        for k in range(count):
            self._record_prepass(cb, k)
            cb.begin_render_pass(self.cache.render_pass(_rp_window(desc, k == 0, k == count - 1)), fb, clears)
            self._record_splats(cb, kind, True, k)
            cb.end_render_pass()

    def _record_passes_12(self, cb, t: _Targets, attr_final: str):
        """Visibility and attribute passes. Timings: with several pre-pass
        windows the pre-pass runs inside each pass (once per window and pass),
        so its time is part of the visibility and attribute times."""
        self.frames_recorded += 1
        cb.timestamp(self._query, 0, bottom=False)
        prepared = self._use_prepass()
        if prepared and self._prep_window_count(prepared) == 1:
            self._record_prepass(cb)
        cb.timestamp(self._query, 1)
        self._record_splat_pass(cb, "depth", _RP_DEPTH, t.fb_depth, [1.0], prepared)
        cb.timestamp(self._query, 2)
        self._record_splat_pass(cb, "attr", _rp_attr(self.accum_format, attr_final),
                                t.fb_attr if attr_final == "shader_read" else self._fb_attr_readback(t),
                                [(0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0), None], prepared)
        cb.timestamp(self._query, 3)

    def _fb_attr_readback(self, t: _Targets):
        if getattr(t, "fb_attr_rb", None) is None:
            rp = self.cache.render_pass(_rp_attr(self.accum_format, "transfer_src"))
            t.fb_attr_rb = t._fb(self.dev, rp, [t.accum_color, t.accum_normal, t.depth])
        return t.fb_attr_rb

    def record_frame(self, cb, camera: Camera, target: RenderTarget):
        """Record the three passes into ``cb`` writing ``target`` (used by
        :meth:`render`; the editor calls it with a swapchain target)."""
        self._require_cloud()
        t = self._targets_for(target.width, target.height)
        self._write_ubo(camera, target.width, target.height, target.apply_gamma)
        cb.reset_queries(self._query)
        self._record_passes_12(cb, t, "shader_read")
        pipe = self._resolve_pipeline(target)
        cb.begin_render_pass(self.cache.render_pass(_rp_resolve(target)), t.target_fb(target), [None])
        cb.bind_pipeline(pipe)
        cb.bind_descriptor_set(pipe, t.resolve_set)
        cb.draw(3)
        cb.end_render_pass()
        cb.timestamp(self._query, 4)

    def _read_timings(self, names):
        ts = self._query.results_ns(len(names) + 1)
        self.last_timings_ms = {n: float(ts[i + 1] - ts[i]) * 1e-6 for i, n in enumerate(names)}
        self.last_timings_ms["total"] = float(ts[len(names)] - ts[0]) * 1e-6

    # ---------------------------------------------------------- public API
    def render(self, camera: Camera, width: int, height: int) -> np.ndarray:
        """Render offscreen; returns (height, width, 4) uint8 RGBA (sRGB)."""
        self._check_open()
        self._require_cloud()
        t = self._targets_for(width, height)
        rb = V.Buffer(self.dev, width * height * 4, ("transfer_dst",), host_visible=True)
        try:
            def rec(cb):
                self.record_frame(cb, camera, t.offscreen)
                cb.copy_image_to_buffer(t.out, rb)
                cb.host_read_barrier()
            self.dev.submit(rec)
            out = rb.read().reshape(height, width, 4)
        finally:
            rb.destroy()
        self._read_timings(("prepass", "visibility", "attributes", "shading"))
        return out

    def render_resident(self, camera: Camera, width: int, height: int):
        """Render without reading back: the frame stays on the device in an
        ``rgba8`` image (TRANSFER_SRC layout, sRGB values) that is returned and
        valid until the next frame of this renderer (the editor blits it into
        the swapchain image, :meth:`SwapchainPresenter.render_frame`).  The
        caller must not re-render while a submitted frame still reads it."""
        self._check_open()
        self._require_cloud()
        t = self._targets_for(width, height)
        self.dev.submit(lambda cb: self.record_frame(cb, camera, t.offscreen))
        self._read_timings(("prepass", "visibility", "attributes", "shading"))
        return t.out

    def render_buffers(self, camera: Camera, width: int, height: int) -> dict[str, np.ndarray]:
        """Float buffers of one frame, (height, width[, c]) float32:

        * ``depth``: eye-space distance along the view axis, NaN for background;
        * ``normal``: unit eye-space normal (x right, y up, z towards the eye), NaN background;
        * ``weight``: accumulated splat weight (0 for background);
        * ``color``: normalised linear RGB (selection tint included), NaN background;
          with :attr:`distortion_map` on, the encoded heat map instead
          (shaders_glsl/distortion.glsl): r = support-weighted
          log(stretch) / log(DISTORTION_HEAT_MAX_STRETCH), g = support share,
          b = luminance.
        """
        self._check_open()
        self._require_cloud()
        t = self._targets_for(width, height)
        texel = 8 if self.accum_format == "rgba16f" else 16
        plane = width * height * texel
        rb = V.Buffer(self.dev, 2 * plane, ("transfer_dst",), host_visible=True)
        try:
            def rec(cb):
                self._write_ubo(camera, width, height)
                cb.reset_queries(self._query)
                self._record_passes_12(cb, t, "transfer_src")
                cb.copy_image_to_buffer(t.accum_color, rb)
                cb.copy_image_to_buffer(t.accum_normal, rb, buf_offset=plane)
                cb.host_read_barrier()
            self.dev.submit(rec)
            raw = rb.read()
        finally:
            rb.destroy()
        self._read_timings(("prepass", "visibility", "attributes"))
        a = V.readback_array(raw[:plane], self.accum_format, width, height).astype(np.float32)
        b = V.readback_array(raw[plane:], self.accum_format, width, height).astype(np.float32)
        w = a[..., 3]
        fg = w >= RENDER_MIN_WEIGHT
        with np.errstate(invalid="ignore", divide="ignore"):
            color = np.where(fg[..., None], a[..., :3] / w[..., None], np.nan)
            depth = np.where(fg, b[..., 3] / w * self.scale, np.nan)
            nrm = b[..., :3] / np.linalg.norm(b[..., :3], axis=-1, keepdims=True)
            nrm = np.where(fg[..., None], nrm, np.nan)
        return {"depth": depth.astype(np.float32), "normal": nrm.astype(np.float32),
                "weight": np.where(fg, w, 0.0).astype(np.float32), "color": color.astype(np.float32)}

    def render_points_floor(self, camera: Camera, width: int, height: int) -> float:
        """Benchmark floor: draw the splat centres as one-pixel POINT_LIST points
        (colour + depth test, no splatting); returns the GPU time in ms."""
        self._check_open()
        self._require_cloud()
        t = self._targets_for(width, height)
        if getattr(t, "fb_points", None) is None:
            t.points_color = V.Image(self.dev, width, height, "rgba8", ("color",))
            t.objects.append(t.points_color)
            t.points_depth = V.Image(self.dev, width, height, "d32f", ("depth",))
            t.objects.append(t.points_depth)
            t.fb_points = t._fb(self.dev, self.cache.render_pass(_RP_POINTS), [t.points_color, t.points_depth])
        desc = V.GraphicsDesc("points.vert", "points.frag", _RP_POINTS, V.LayoutDesc(sets=(_SPLAT_SET,)),
                              topology="point_list", bindings=(V.VertexBinding(0, _GEOM_STRIDE, per_instance=False),),
                              attributes=(V.VertexAttribute(0, 0, "vec3", 0),), depth_test=True, depth_write=True)
        pipe = self.cache.pipeline(desc)

        def rec(cb):
            self._write_ubo(camera, width, height)
            cb.reset_queries(self._query)
            cb.timestamp(self._query, 0, bottom=False)
            cb.begin_render_pass(self.cache.render_pass(_RP_POINTS), t.fb_points, [(1.0, 1.0, 1.0, 1.0), 1.0])
            cb.bind_pipeline(pipe)
            cb.bind_descriptor_set(pipe, self.splat_set)
            cb.bind_vertex_buffers(0, [self._geom])
            cb.draw(self.n)
            cb.end_render_pass()
            cb.timestamp(self._query, 1)
        self.dev.submit(rec)
        self._read_timings(("points",))
        return self.last_timings_ms["points"]

    def pick(self, camera: Camera, width: int, height: int, rect=None):
        """Splat index per pixel (-1 background) and eye-space depth along the
        view axis (NaN background) of the nearest splat, for the whole image
        or ``rect`` = (x, y, w, h) in pixels (clipped to the image)."""
        self._check_open()
        self._require_cloud()
        t = self._targets_for(width, height)
        t.ensure_pick()
        if rect is None:
            x, y, w, h = 0, 0, width, height
        else:
            x, y, w, h = (int(v) for v in rect)
            x0, y0 = max(x, 0), max(y, 0)
            x1, y1 = min(x + w, width), min(y + h, height)
            if x1 <= x0 or y1 <= y0:
                raise ParameterError("rect", f"{tuple(rect)} does not overlap the {width}x{height} image")
            x, y, w, h = x0, y0, x1 - x0, y1 - y0
        nbytes = w * h * 4
        rb = V.Buffer(self.dev, 2 * nbytes, ("transfer_dst",), host_visible=True)
        try:
            def rec(cb):
                self._write_ubo(camera, width, height)
                cb.reset_queries(self._query)
                cb.timestamp(self._query, 0, bottom=False)
                prepared = self._use_prepass()
                if prepared and self._prep_window_count(prepared) == 1:
                    self._record_prepass(cb)
                self._record_splat_pass(cb, "pick", _RP_PICK, t.fb_pick, [(0, 0, 0, 0), 1.0], prepared)
                cb.timestamp(self._query, 1)
                cb.copy_image_to_buffer(t.pick_index, rb, (x, y, w, h))
                cb.copy_image_to_buffer(t.pick_depth, rb, (x, y, w, h), buf_offset=nbytes)
                cb.host_read_barrier()
            self.dev.submit(rec)
            raw = rb.read()
        finally:
            rb.destroy()
        self._read_timings(("pick",))
        idx = raw[:nbytes].view(np.uint32).reshape(h, w).astype(np.int64) - 1
        d = raw[nbytes:].view(np.float32).reshape(h, w).astype(np.float64)
        near, far = self._near_far
        with np.errstate(divide="ignore", invalid="ignore"):
            depth = near / (1.0 - d * (far - near) / far)
        depth[idx < 0] = np.nan
        return idx, depth


def _unit_scale(diagonal: float, max_radius: float) -> float:
    """The power of two nearest the model's size (its bounding-box diagonal,
    or its largest splat for a single point): dividing by it is exact, and
    it brings every model to about unit size for the float32 GPU side."""
    size = max(diagonal, max_radius)
    if not (size > 0 and np.isfinite(size)):
        return 1.0
    return float(2.0 ** round(float(np.log2(size))))
