"""Vulkan renderer of 3D Gaussian Splatting scenes (issue 13), deformable on the GPU.

Per frame:

1. compute pre-pass (``gs_prepare.comp``), once per Gaussian: deformation
   of the Gaussians that carry a basis row (centre p + B dC, covariance
   J Sigma J^T with J = I + sum_k dC_k grad B_k^T, plus the blended arcs of
   rotating handles in the rotation-aware mode (``rotation.glsl``, as the
   splat renderer), and the polar rotation R of J), EWA projection to a screen conic (Jacobian of the perspective
   projection + GS_LOWPASS_PX2), colour from the SH at the view direction
   (R^T times it for a deformed Gaussian: its SH live in its original frame),
   culling, and the view depth as the sort key;
2. depth sort of the keys: ``sort="cpu"`` reads the keys back and sorts them
   with numpy; ``sort="gpu"`` appends the visible Gaussians' keys in the
   pre-pass and sorts only those with the GPU radix sort
   (:mod:`splatedit.render.gaussian.gpu_sort`, the count read on the GPU);
   ``sort="bitonic"``: the bitonic sort it replaced (comparisons only);
   ``sort="auto"``: :func:`choose_sort`;
3. ``path="raster"``: one screen-aligned quad per visible Gaussian in depth order, spanning the
   ellipse where its alpha reaches GS_ALPHA_MIN, with the conic evaluated in
   the fragment shader and blended *front to back* ("under" operator on
   premultiplied colour into an RGBA16F target whose alpha is 1 - T).  Front
   to back sums the same terms as the reference rasteriser in the same order
   (C = sum T_i alpha_i c_i), and once T is used up the blend adds exactly 0
   (1 - alpha rounds to 1 in half float below T ~ 2.4e-4): the
   fixed-function blend cannot skip the fragment, but it stops changing the
   pixel, the equivalent of the reference's early stop;
   ``path="compute"``: the compute tile rasterizer (:mod:`splatedit.render.gaussian.tiles`)
   sums the same terms per 16x16 tile in a workgroup and stops at
   GS_MIN_TRANSMITTANCE; ``path="auto"``: :func:`choose_path`;
4. a full-screen resolve writes C + T * background to the target.

The pick pass draws the Gaussians of opacity >= GS_PICK_MIN_OPACITY as
their GS_PICK_SIGMAS ellipses with a depth test: the same ``pick`` API as
:class:`splatedit.render.splat.renderer.Renderer`.

Only :mod:`splatedit.render.vk` calls Vulkan.
"""

from __future__ import annotations

import math
import time

import numpy as np

from splatedit.deform.rotation import split_displacement
from splatedit.errors import ParameterError
from splatedit.model.gaussians import GaussianCloud
from splatedit.render import vk as V
from splatedit.render.camera import Camera
from splatedit.render.gpu_units import (MAX_GROUPS, displacement_bound, gpu_camera,
                                        pack_basis_rows, pack_deform_block, selection_flags, unit_scale)
from splatedit.render.frame import Frame, FrameContext
from splatedit.render.gaussian.gpu_sort import BitonicSort, RadixSort
from splatedit.render.gaussian.passes import draw_frame as gs_draw_frame
from splatedit.render.gaussian.passes import pick_frame as gs_pick_frame
from splatedit.render.gaussian.passes import prepare_frame as gs_prepare_frame
from splatedit.render.gaussian.resources import (GS_PREP_WG, GS_REC_BYTES, GS_RESOLVE_SET, GS_SET, GS_UBO_BYTES,
                                           NO_BASIS_ROW, PATHS, SORTS, GaussianTargets, gaussian_bounds,
                                           pack_geometry, rp_accum)
from splatedit.render.gaussian.tiles import TileRasterizer
from splatedit.render.targets import RP_PICK, RenderTarget, create_frame_objects, reusable_targets
from splatedit.render.uniforms import GS_FRAME_UBO, GS_PREP_PUSH
from splatedit.tolerances import (GS_ALPHA_MAX, GS_ALPHA_MIN, GS_FRUSTUM_CLAMP, GS_LOWPASS_PX2, GS_NEAR_CULL_REL,
                                  GS_PICK_MIN_OPACITY, GS_PICK_SIGMAS, GS_POLAR_ITERATIONS, GS_TILE_PAIRS_PER_GAUSSIAN,
                                  RENDER_BACKGROUND, RENDER_MAX_BASIS_COLUMNS, RENDER_TINT_HANDLE, RENDER_TINT_SUPPORT)


def choose_path(dev: V.Device) -> str:
    """The draw path of ``path="auto"``, a documented rule: on a CPU device
    (lavapipe) the path measured faster there (:data:`CPU_DEVICE_PATH`,
    docs/PERFORMANCE.md, "Gaussian splatting: radix sort and tile
    rasterizer"); "compute" on every GPU, by argument, not yet measured:
    compute shaders use the whole chip (on an H100/H200 only 2 of 66 TPCs run
    vertex and fragment shaders) and the tile rasterizer stops blending a
    pixel once its transmittance is used up, where the quad path still
    shades and blends every fragment behind it."""
    return CPU_DEVICE_PATH if V.is_cpu_device(dev) else "compute"


def choose_sort(dev: V.Device) -> str:
    """The depth sort of ``sort="auto"``: on a CPU device the sort measured
    faster there (:data:`CPU_DEVICE_SORT`), on a GPU the GPU radix sort (the
    keys never leave the GPU and the CPU waits for no sort between the
    pre-pass and the draw)."""
    return CPU_DEVICE_SORT if V.is_cpu_device(dev) else "gpu"


#: lavapipe's faster path and sort (bench gaussian-render, docs/PERFORMANCE.md)
CPU_DEVICE_PATH = "raster"
CPU_DEVICE_SORT = "cpu"


class GaussianRenderer:
    """Offscreen (and editor) renderer of a :class:`GaussianCloud`.

    Use as a context manager or call :meth:`close`::

        with GaussianRenderer() as r:
            r.set_gaussians(cloud)
            img = r.render(camera, 256, 256)        # (256, 256, 4) uint8

    Args:
        sort: ``"cpu"`` (numpy argsort of the read-back depth keys, two
            submissions per frame), ``"gpu"`` (GPU radix sort of the visible
            Gaussians' keys), ``"bitonic"`` (the former GPU sort, of every
            key) or ``"auto"`` (:func:`choose_sort`).
        path: ``"raster"`` (a quad per Gaussian), ``"compute"`` (the tile
            rasterizer, :mod:`splatedit.render.gaussian.tiles`) or ``"auto"``
            (:func:`choose_path`).
        background: display-referred RGB (3 floats in 0..1) behind the scene.
        accum_format: ``"rgba16f"`` or ``"rgba32f"`` blend target.
        device: share an existing :class:`splatedit.render.vk.Device` (the
            editor's); otherwise one is created (``device_name``, ``validation``
            as for :class:`~splatedit.render.splat.renderer.Renderer`).
    """

    def __init__(self, *, sort: str = "auto", path: str = "auto", background=RENDER_BACKGROUND,
                 accum_format: str = "rgba16f", device: V.Device | None = None, device_name: str | None = None,
                 validation: bool | None = None):
        if sort not in SORTS:
            raise ParameterError("sort", f"must be one of {SORTS}, got {sort!r}")
        if path not in PATHS:
            raise ParameterError("path", f"must be one of {PATHS}, got {path!r}")
        if accum_format not in ("rgba16f", "rgba32f"):
            raise ParameterError("accum_format", f"must be 'rgba16f' or 'rgba32f', got {accum_format!r}")
        self.accum_format = accum_format
        self.background = tuple(float(x) for x in background)[:3]
        self._own_device = device is None
        self.dev = device if device is not None else V.Device(device_name=device_name, validation=validation)
        #: the draw path and depth sort in use (``"auto"`` resolved for this device)
        self.path = choose_path(self.dev) if path == "auto" else path
        self.sort = choose_sort(self.dev) if sort == "auto" else sort
        self._radix = self._bitonic = self._tiles = None
        self._closed = False
        self.cache = self.sampler = self.ubo = self.dC_ubo = self._query = None
        self._targets = None
        self._bufs = []
        self._basis_buf = None
        self._dset = None
        self.cloud = None
        self.n = 0
        #: Gaussians drawn: the first ``count`` of the scene (:meth:`set_draw_count`)
        self.count = 0
        #: counts the pre-passes (frames and picks): chunked frames check their records are current
        self.epoch = 0
        self._dC = np.zeros((4, 3))
        self._rot = None            # RotationDisplacement of the frame, or None
        self._cols = 4
        self._basis_idx = np.zeros(0, np.int64)
        self._reach = 0.0
        self.near_far = (1.0, 2.0)
        self._n_visible = 0
        self.last_timings_ms: dict[str, float] = {}
        #: the editor's distortion heat map: support Gaussians coloured by the principal
        #: stretch of J on their own plane (the splat renderer's ramp), the others dark grey
        self.distortion_map = False
        #: display options of the editor (as Renderer's): every standard deviation
        #: drawn this many times larger, and colours as their luminance (grey)
        self.splat_scale = 1.0
        self.grey_shading = False
        try:
            create_frame_objects(self, GS_UBO_BYTES)
            self._query = V.QueryPool(self.dev, 8)
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------ lifecycle
    def close(self) -> None:
        """Destroy every Vulkan object; idempotent."""
        if self._closed:
            return
        self._closed = True
        if self.dev.device is not None:
            self.dev.wait_idle()
        self._free_scene()
        if self._targets is not None:
            self._targets.destroy()
            self._targets = None
        for obj in (self._query, self.dC_ubo, self.ubo, self.sampler):
            if obj is not None:
                obj.destroy()
        if self.cache is not None:
            self.cache.destroy()
        if self._own_device:
            self.dev.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def require_scene(self):
        """Raise ParameterError when closed or without a scene."""
        if self._closed:
            raise ParameterError("renderer", "is closed")
        if self.cloud is None:
            raise ParameterError("cloud", "no Gaussians set (call set_gaussians first)")

    # --------------------------------------------------------------- scene
    def _free_scene(self):
        for name in ("_tiles", "_radix", "_bitonic"):
            obj = getattr(self, name)
            if obj is not None:
                obj.destroy()
                setattr(self, name, None)
        for b in reversed(self._bufs):
            b.destroy()
        self._bufs = []
        if self._basis_buf is not None:
            self._basis_buf.destroy()
            self._basis_buf = None
        self._dset = None
        self.cloud = None
        self.n = self.count = 0

    def _buf(self, size, usage=("storage",), host_visible=False):
        b = V.Buffer(self.dev, max(int(size), 16), usage, host_visible=host_visible)
        self._bufs.append(b)
        return b

    def set_gaussians(self, cloud: GaussianCloud) -> None:
        """Upload a scene (float32 relative to its box centre, divided by a
        power of two near its size); clears any deformation basis.

        Raises ParameterError when a per-Gaussian buffer would exceed the
        device's storage-buffer range (lavapipe: 128 MiB = 2,097,152 Gaussians)."""
        if self._closed:
            raise ParameterError("renderer", "is closed")
        if not isinstance(cloud, GaussianCloud):
            raise ParameterError("cloud", f"must be a GaussianCloud, got {type(cloud).__name__}")
        n = len(cloud)
        if n == 0:
            raise ParameterError("cloud", "has no Gaussians")
        limit = int(self.dev.limits.maxStorageBufferRange)
        n2 = 1 << max(int(math.ceil(math.log2(n))), 0)
        if n * GS_REC_BYTES > limit or n2 * 4 > limit:
            raise ParameterError("cloud", f"{n} Gaussians exceed the device's storage-buffer range "
                                          f"({limit // GS_REC_BYTES} at most)")
        self.dev.wait_idle()
        self._free_scene()
        lo, hi = gaussian_bounds(cloud)
        self.origin = 0.5 * (cloud.positions.min(axis=0) + cloud.positions.max(axis=0))
        self.scale = unit_scale(float(np.linalg.norm(hi - lo)), 0.0)
        self.bounds = (lo, hi)
        self._sigma_max = cloud.scales().max(axis=1)
        geom, rest = pack_geometry(cloud, self.origin, self.scale)
        self._rest_uints = rest.shape[1]
        self.degree = cloud.sh_degree
        self._n2 = n2
        self._geom = self._buf(geom.nbytes, ("storage",))
        self._geom.upload(geom)
        self._rest = self._buf(max(rest.nbytes, 4), ("storage",))
        if rest.nbytes:
            self._rest.upload(rest)
        self._flags = self._buf(4 * n, ("storage",), host_visible=True)
        self._flags.view(np.uint32)[:] = 0
        self._brow = self._buf(4 * n, ("storage",), host_visible=True)
        self._brow.view(np.uint32)[:] = NO_BASIS_ROW
        self._rec = self._buf(n * GS_REC_BYTES)
        self._keys = self._buf(4 * n2, host_visible=True)
        self._order = self._buf(4 * n2, host_visible=True)
        self._draws = self._buf(16, ("storage", "indirect"), host_visible=True)
        self._dummy_basis = self._buf(64, host_visible=True)
        self._dummy_basis.view(np.float32)[:] = 0.0
        self.cloud = cloud
        self.n = self.count = n
        self._cols, self._dC, self._basis_idx, self._reach = 4, np.zeros((4, 3)), np.zeros(0, np.int64), 0.0
        self._rot = None
        self._write_dset()
        if self.sort == "gpu":
            self._radix = RadixSort(self.dev, self.cache, self._keys, self._order, self._draws, capacity=n,
                                    count_index=1)
        elif self.sort == "bitonic":
            self._bitonic = BitonicSort(self.dev, self.cache, self._keys, self._order)
        if self.path == "compute":
            self._tiles = TileRasterizer(self.dev, self.cache, self._dset, GS_SET, n,
                                         int(GS_TILE_PAIRS_PER_GAUSSIAN * n) + 4096, self.accum_format)

    def _write_dset(self):
        if self._dset is None:
            self._dset = V.DescriptorSet(self.dev, self.cache.set_layout(GS_SET))
            self._bufs.append(self._dset)
        basis = self._basis_buf if self._basis_buf is not None else self._dummy_basis
        self._dset.write({0: self.ubo, 1: self._geom, 2: self._rest, 3: self._brow, 4: basis, 5: self._rec,
                          6: self._keys, 7: self._order, 8: self._draws, 9: self.dC_ubo, 11: self._flags})

    def set_cloud(self, cloud: GaussianCloud) -> None:
        """:meth:`set_gaussians` under the splat renderer's name (the editor's viewport calls it)."""
        self.set_gaussians(cloud)

    def _sort_length(self) -> int:
        """Length of the GPU's bitonic sort: the power of two at or above the
        Gaussians drawn (``count``), not the scene's: a level of detail of 2,000
        Gaussians out of a 250k upload sorted 262,144 keys every frame."""
        return min(self._n2, 1 << max(int(math.ceil(math.log2(max(self.count, 1)))), 0))

    def set_draw_count(self, count: int | None) -> None:
        """Draw (and pick) only the first ``count`` Gaussians of the scene (a
        budgeted level of detail uploaded in importance order,
        :mod:`splatedit.model.gaussian_lod`); None or >= n: all of them."""
        self.require_scene()
        c = self.n if count is None else int(count)
        if c < 1:
            raise ParameterError("count", f"must be >= 1, got {count!r}")
        self.count = min(c, self.n)

    def set_selection(self, support_mask=None, handle_mask=None, inactive_mask=None) -> None:
        """Tint the support (blue) and handle (green) Gaussians as the splat
        renderer does; boolean masks (n,) or index arrays; None clears."""
        self.require_scene()
        flags = selection_flags(self.n, support_mask, handle_mask, inactive_mask)
        self._flags.view(np.uint32)[:] = flags

    # --------------------------------------------------------- deformation
    def set_basis(self, indices, B, Bx, By, Bz) -> None:
        """Deformation basis rows for the Gaussians ``indices`` (N,): B, Bx, By,
        Bz (N, K), K in 1..RENDER_MAX_BASIS_COLUMNS, as
        :meth:`Renderer.set_basis`.  Other Gaussians are not deformed.  A new
        K resets the displacement to zeros (K, 3)."""
        self.require_scene()
        idx = np.asarray(indices, dtype=np.int64).reshape(-1)
        mats = [np.asarray(m, dtype=np.float64) for m in (B, Bx, By, Bz)]
        for name, a in zip(("B", "Bx", "By", "Bz"), mats):
            if a.ndim != 2 or a.shape[0] != len(idx) or a.shape[1] != mats[0].shape[1]:
                raise ParameterError(name, f"must have shape ({len(idx)}, K) like B, got {a.shape}")
            if not np.isfinite(a).all():
                raise ParameterError(name, "basis rows must be finite")
        k = mats[0].shape[1]
        if not 1 <= k <= RENDER_MAX_BASIS_COLUMNS:
            raise ParameterError("B", f"basis must have 1..{RENDER_MAX_BASIS_COLUMNS} columns, got {k}")
        if len(idx) and (idx.min() < 0 or idx.max() >= self.n or len(np.unique(idx)) != len(idx)):
            raise ParameterError("indices", f"must be distinct and in 0..{self.n - 1}")
        g = (k + 3) // 4
        rows = pack_basis_rows(mats, self.scale)
        if rows.nbytes > int(self.dev.limits.maxStorageBufferRange):
            raise ParameterError("indices", f"{len(idx)} deformed Gaussians with {k} columns exceed the "
                                            "device's storage-buffer range")
        self.dev.wait_idle()
        if self._basis_buf is not None:
            self._basis_buf.destroy()
            self._basis_buf = None
        self._basis_buf = V.Buffer(self.dev, rows.nbytes, ("storage",), host_visible=True)
        self._basis_buf.write(rows)
        brow = self._brow.view(np.uint32)
        brow[:] = NO_BASIS_ROW
        brow[idx] = np.arange(len(idx), dtype=np.uint32)
        self._groups = g
        if k != self._cols:
            self._cols, self._dC, self._rot = k, np.zeros((k, 3)), None
        self._basis_idx = idx
        grad = np.sqrt(mats[1] ** 2 + mats[2] ** 2 + mats[3] ** 2).sum(axis=1)
        self._reach = float((np.abs(mats[0]).sum(axis=1) + 3.0 * self._sigma_max[idx] * grad).max(initial=0.0))
        self._write_dset()

    def set_detail(self, indices, detail) -> None:
        """Gaussians have no detail mode (``supports_detail`` is False): raises ParameterError."""
        raise ParameterError("detail", "the Gaussian renderer has no detail mode")

    def clear_basis(self) -> None:
        """Every Gaussian undeformed."""
        self.require_scene()
        self._brow.view(np.uint32)[:] = NO_BASIS_ROW
        self._basis_idx = np.zeros(0, np.int64)
        self._reach = 0.0

    def set_displacement(self, dC) -> None:
        """Control-frame displacement dC (K, 3), K = the basis' column count
        (model units), or a :class:`~splatedit.deform.rotation.RotationDisplacement`
        (rotation-aware handles: its residual dC plus each handle's rotation,
        blended on the GPU as by :class:`~splatedit.render.splat.renderer.Renderer`)."""
        self.require_scene()
        a, rot = split_displacement(dC)
        if rot is not None and len(rot.rotations) > MAX_GROUPS:
            raise ParameterError("dC", f"the renderer blends at most {MAX_GROUPS} handle rotations")
        a = np.asarray(a, dtype=np.float64)
        if a.shape != (self._cols, 3) or not np.isfinite(a).all():
            raise ParameterError("dC", f"must be finite with shape ({self._cols}, 3), got {a.shape}")
        self._dC = a.copy()
        self._rot = rot

    # -------------------------------------------------------------- frame
    def targets_for(self, width: int, height: int) -> GaussianTargets:
        """The per-size images for width x height (re-created when the size changes)."""
        t = reusable_targets(self, self._targets, width, height)
        if t is None:
            self._targets = None                # a failure below leaves no destroyed targets behind
            t = self._targets = GaussianTargets(self, int(width), int(height))
        return t

    def write_ubo(self, camera: Camera, width: int, height: int, srgb_target: bool = False):
        o, sc = self.origin, self.scale
        gpu_cam = gpu_camera(camera, o, sc)
        lo, hi = self.bounds
        grown = 3.0 * max(float(self.splat_scale) - 1.0, 0.0) * float(self._sigma_max.max())
        lo, hi = lo - grown, hi + grown
        if len(self._basis_idx):
            grow = self._reach * displacement_bound(self._dC, self._rot)
            lo, hi = lo - grow, hi + grow
        near, far = gpu_cam.clip_range((lo - o) / sc, (hi - o) / sc)
        f = 1.0 / math.tan(math.radians(camera.fov_deg) / 2.0)
        fpx = 0.5 * f * height
        u = np.zeros((), GS_FRAME_UBO)           # gs_common.glsl GsFrame
        u["view"] = gpu_cam.view_matrix().T
        u["focal"] = (fpx, fpx, 0.5 * width, 0.5 * height)
        u["viewport"] = (width, height, near, far)
        u["eye"] = (*gpu_cam.eye, self.degree)
        u["limits"] = (GS_FRUSTUM_CLAMP * 0.5 * width / fpx, GS_FRUSTUM_CLAMP * 0.5 * height / fpx, GS_LOWPASS_PX2,
                       GS_ALPHA_MIN)
        u["params"] = (GS_ALPHA_MAX, GS_PICK_MIN_OPACITY, GS_PICK_SIGMAS ** 2, near * GS_NEAR_CULL_REL)
        u["background"] = (*self.background, 1.0)
        u["counts"] = (self.count, self._rest_uints, self._sort_length() if self.sort == "bitonic" else self.count,
                       1 if srgb_target else 0)
        u["tint_support"] = RENDER_TINT_SUPPORT
        u["tint_handle"] = RENDER_TINT_HANDLE
        u["display"] = (float(self.splat_scale), 1.0 if self.grey_shading else 0.0,
                        1.0 if self.distortion_map else 0.0, 0.0)
        self.ubo.write(u.reshape(1).view(np.float32))
        self.dC_ubo.write(pack_deform_block(self._dC, self._rot, sc))
        self.near_far = (near * sc, far * sc)

    #: the :class:`~splatedit.render.scene.SceneRenderer` capabilities: no detail
    #: mode rows; the viewport reads Gaussian frames back (no resident presentation yet)
    supports_detail = False
    resident_frames = False
    #: eye-dome lighting is a splat pass (render --edl): never drawn for Gaussians
    supports_edl = False
    edl = False

    # ------------------------------------------------ pieces the passes record
    #: the resolve pass's shader and descriptor-set layout (frame.Resolve)
    resolve_shader = "gs_resolve.frag"
    resolve_set_layout = GS_RESOLVE_SET

    @property
    def targets(self) -> GaussianTargets | None:
        """The per-size images of the last frame (None before one)."""
        return self._targets

    @property
    def scene_set(self):
        """The scene's descriptor set 0 (``GS_SET``: frame block, geometry, records, keys, order, draws...)."""
        return self._dset

    @property
    def draws(self):
        """The indirect draw arguments (instance count = visible Gaussians after the pre-pass)."""
        return self._draws

    @property
    def tiles(self):
        """The compute tile rasterizer (``path="compute"``), else None."""
        return self._tiles

    def _bind_compute(self, cb, shader: str, push: np.dtype):
        """Bind compute shader ``shader`` with the scene's set (``GS_SET``) and
        push constants of layout ``push``; returns the pipeline."""
        layout = V.LayoutDesc(sets=(GS_SET,), push_bytes=push.itemsize, push_stages="comp")
        pipe = self.cache.pipeline(V.ComputeDesc(shader, layout))
        cb.bind_pipeline(pipe)
        cb.bind_descriptor_set(pipe, self._dset)
        return pipe

    def record_prepass(self, cb, compact: bool = False):
        """Record the pre-pass (:class:`~splatedit.render.gaussian.passes.GsPrepare`);
        ``compact``: append the visible keys (the radix sort's input)."""
        pipe = self._bind_compute(cb, "gs_prepare.comp", GS_PREP_PUSH)
        groups = self._groups if len(self._basis_idx) else 1
        cb.push_constants(pipe, np.array((groups, GS_POLAR_ITERATIONS, int(compact)), GS_PREP_PUSH))
        count = self._sort_length() if self.sort == "bitonic" else self.count
        cb.dispatch((count + GS_PREP_WG - 1) // GS_PREP_WG)

    def record_sort(self, cb):
        """Record the GPU depth sort (:class:`~splatedit.render.gaussian.passes.GsSort`)."""
        if self.sort == "gpu":
            self._radix.record(cb, bits=32)
        else:
            self._bitonic.record(cb, self._sort_length())

    def draw_pipeline(self):
        """The quad pass's pipeline (front-to-back blending into the accumulator)."""
        layout = V.LayoutDesc(sets=(GS_SET,))
        return self.cache.pipeline(V.GraphicsDesc("gs.vert", "gs.frag", rp_accum(self.accum_format), layout,
                                                  blend_under=(True,), spec=((0, 0),)))

    def pick_pipeline(self):
        """The pick pass's pipeline (index + depth, depth test)."""
        layout = V.LayoutDesc(sets=(GS_SET,))
        return self.cache.pipeline(V.GraphicsDesc("gs.vert", "gs_pick.frag", RP_PICK, layout, depth_test=True,
                                                  depth_write=True, depth_compare="less", spec=((0, 1),)))

    @property
    def visible(self) -> int:
        """Gaussians the last :meth:`prepare_frame` kept (its sorted order's length)."""
        return self._n_visible

    def prepare_frame(self, camera: Camera, width: int, height: int, *, srgb_target: bool = False) -> None:
        """Pre-pass and sort for this camera and image size (submits and waits;
        :func:`~splatedit.render.gaussian.passes.prepare_frame`).  Then
        :meth:`record_draw` records the draw into any command buffer (the
        editor's frame); :meth:`render` does both."""
        self.require_scene()
        if self.path == "compute" and self._tiles.pairs_wanted() > self._tiles.capacity:
            # the last frame (e.g. the editor's, drawn by record_draw) dropped pairs: room for this one
            self._tiles.grow(self._tiles.pairs_wanted())
        t = self.targets_for(width, height)
        self.write_ubo(camera, width, height, srgb_target)
        self.epoch += 1
        dv = self._draws.view(np.uint32)
        dv[:] = (4, 0, 0, 0)
        frame = gs_prepare_frame(self.sort)
        ctx = FrameContext(self, t)
        t0 = time.perf_counter()

        def rec(cb):
            cb.reset_queries(self._query)
            frame.record(cb, ctx, self._query)
        self.dev.submit(rec)
        gpu_sort = self.sort != "cpu"
        ts = frame.read_timings(self._query)
        # lavapipe's timestamps around a lone dispatch read ~0 after the first
        # frame: the CPU-sort path reports the pre-pass submission's wall time
        timings = {"prepass": ts["prepass"] if gpu_sort else (time.perf_counter() - t0) * 1e3}
        nvis = int(dv[1])
        if gpu_sort:
            timings["sort"] = ts["sort"]
            timings["prepass"] = max((time.perf_counter() - t0) * 1e3 - timings["sort"], 0.0)
        else:
            t1 = time.perf_counter()
            keys = self._keys.view(np.uint32)[:self.count]
            # positive float32 depths sort as their bit patterns; culled keys are 0xFFFFFFFF (last)
            # (numpy's default introsort: SIMD-vectorised, 6-10x faster than kind="stable"
            # on 1M random uint32 keys, 23 vs 136-230 ms; equal depths are left in any order)
            order = np.argsort(keys)[:nvis].astype(np.uint32)
            self._order.view(np.uint32)[:nvis] = order
            timings["sort"] = (time.perf_counter() - t1) * 1e3
        timings["prepare_wall"] = (time.perf_counter() - t0) * 1e3
        self._n_visible = nvis
        self.last_timings_ms = timings

    #: the query slots of the draw submission (after the prepare submission's)
    _DRAW_QUERY = 3

    def draw_frame(self) -> Frame:
        """The draw submission's pass list on :attr:`path`
        (:func:`~splatedit.render.gaussian.passes.draw_frame`)."""
        return gs_draw_frame(self.path)

    def record_draw(self, cb, target: RenderTarget) -> None:
        """Record the Gaussians' draw and the resolve into ``target`` (after
        :meth:`prepare_frame` for the same size), with timestamps."""
        t = self.targets_for(target.width, target.height)
        frame = self.draw_frame()
        cb.reset_queries(self._query, self._DRAW_QUERY, frame.query_count)
        frame.record(cb, FrameContext(self, t, target), self._query, self._DRAW_QUERY)
        self._last_draw = frame

    def _check_tile_pairs(self) -> bool:
        """After a compute-path frame: when it wanted more (tile, Gaussian)
        pairs than the buffers hold, grow them; True when the frame should be
        drawn again."""
        if self.path != "compute":
            return False
        wanted = self._tiles.pairs_wanted()
        return wanted > self._tiles.capacity and self._tiles.grow(wanted)

    def render(self, camera: Camera, width: int, height: int) -> np.ndarray:
        """Render offscreen: (height, width, 4) uint8 RGBA, alpha 255."""
        self.prepare_frame(camera, width, height)
        t = self._targets

        def rec(cb):
            self.record_draw(cb, t.offscreen)
        out = t.read_output(rec)
        if self._check_tile_pairs():
            out = t.read_output(rec)
        ts = self._last_draw.read_timings(self._query, self._DRAW_QUERY)
        self.last_timings_ms["draw"] = ts["draw"]
        self.last_timings_ms["resolve"] = ts["resolve"]
        self.last_timings_ms["visible"] = float(self._n_visible)
        return out

    def render_resident(self, camera: Camera, width: int, height: int):
        """Render without reading back: the rgba8 output image (TRANSFER_SRC
        layout), valid until the next frame of this renderer (the interface of
        :meth:`Renderer.render_resident`)."""
        self.prepare_frame(camera, width, height)
        t = self._targets
        self.dev.submit(lambda cb: self.record_draw(cb, t.offscreen))
        if self._check_tile_pairs():
            self.dev.submit(lambda cb: self.record_draw(cb, t.offscreen))
        ts = self._last_draw.read_timings(self._query, self._DRAW_QUERY)
        self.last_timings_ms.update(draw=ts["draw"], resolve=ts["resolve"], visible=float(self._n_visible))
        return t.out

    def pick(self, camera: Camera, width: int, height: int, rect=None):
        """Gaussian index per pixel (-1 background) and view-axis depth of its
        centre (model units, NaN background) of the nearest pickable Gaussian
        (opacity >= GS_PICK_MIN_OPACITY, within GS_PICK_SIGMAS), for the image
        or ``rect`` = (x, y, w, h) (clipped): the API of Renderer.pick."""
        self.require_scene()
        t = self.targets_for(width, height)
        frame = gs_pick_frame()
        self.epoch += 1

        def rec(cb):
            self.write_ubo(camera, width, height)
            self._draws.view(np.uint32)[:] = (4, 0, 0, 0)
            # records of culled Gaussians are stale: draw in index order those the
            # pre-pass wrote this frame (order = identity, count = all; the
            # vertex shader drops the culled through their zeroed opacity)
            frame.record(cb, FrameContext(self, t))
        return t.read_pick(rect, rec)
