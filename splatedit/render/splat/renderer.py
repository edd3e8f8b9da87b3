"""EWA surface-splat renderer with GPU deformation (Botsch & Kobbelt 2005, Sect. 7).

Three passes per frame (Botsch, Hornung, Zwicker, Kobbelt 2005):

1. visibility: depth only, splats pushed back by epsilon along the view ray;
2. attributes: depth test against pass 1 without depth writes, additive
   blending of weight*colour, weight*normal, weight*depth and weight into
   float targets;
3. shading: full-screen normalisation, deferred Phong with a headlight,
   background, gamma; it writes a :class:`RenderTarget` (an offscreen RGBA8
   image here; a swapchain image for the editor).

The frame is a list of pass objects (:mod:`splatedit.render.splat.passes`).
Passes 1 and 2 run on one of two paths over the same accumulators and the
same shading pass: raster (the pre-pass records drawn as quads and points)
or compute (:mod:`splatedit.render.splat.compute_raster`: the records rasterized
by compute shaders, visibility by 64-bit atomicMin); ``raster_path`` and
:meth:`Renderer.frame_path` choose.  Picking is always drawn by the raster
path; the distortion heat map and the selection tints are in the records
(both paths).

One vertex shader (``shaders_glsl/splat_vs.glsl``) serves both splat passes
and the picking pass; it applies the deformation p' = p + B dC, u' = J u,
v' = J v of splats that carry a basis row.

:class:`Renderer` coordinates the frame and owns its parts: the scene's
buffers (:class:`~splatedit.render.splat.uploads.SceneUploads`, ``renderer.uploads``:
cloud, selection, basis, detail and dC uploads), the compute pre-pass
(:class:`~splatedit.render.splat.prepass.Prepass`, ``renderer.prepass_part``: its
buffers, windows and recording); it uses :mod:`~splatedit.render.targets` (render targets and per-size
images, shared with the Gaussian renderer), :mod:`~splatedit.render.splat.layout`
(descriptor sets, render passes, pipeline descriptions) and
:mod:`~splatedit.render.gpu_units` (model units to GPU units).

Only :mod:`splatedit.render.vk` calls Vulkan.
"""

from __future__ import annotations

import numpy as np

from splatedit.errors import ParameterError
from splatedit.render import vk as V
from splatedit.render.camera import Camera
from splatedit.render.splat.compute_raster import ComputeRaster, choose_path, probe_key, requested_path
from splatedit.render.splat.passes import Frame, FrameContext, pick_frame, splat_frame
from splatedit.render.gpu_units import gpu_camera
from splatedit.render.splat.prepass import Prepass, PrepObjects
from splatedit.render.splat.layout import (GEOM_STRIDE, PREP_MAX_SIZE, RESOLVE_SET, RP_POINTS, SPLAT_SET,
                                           UBO_BYTES, rp_attr, rp_window, splat_desc)
from splatedit.render.targets import RenderTarget, SplatTargets, create_frame_objects, resolve_desc, reusable_targets
from splatedit.render.uniforms import FRAME_UBO, PREPARED_PUSH, SPLAT_GEOM
from splatedit.render.splat.uploads import SceneUploads
from splatedit.tolerances import (RENDER_BACKGROUND, RENDER_GAMMA, RENDER_EDL_RADIUS_PX,
                                  RENDER_EDL_STRENGTH, RENDER_GAUSS_SHARPNESS, RENDER_GREY_ALBEDO,
                                  RENDER_LIGHT, RENDER_LOWPASS_RADIUS_PX, RENDER_MIN_WEIGHT,
                                  RENDER_POINT_SPLAT_MAX_PX, RENDER_TINT_HANDLE, RENDER_TINT_SUPPORT,
                                  RENDER_VISIBILITY_EPS_RADII)


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
        raster_path: ``"auto"``, ``"raster"`` or ``"compute"``: how the splat
            frame is rasterized (:mod:`splatedit.render.splat.compute_raster`; the
            attribute :attr:`raster_path`).  Default: env var
            ``SPLATEDIT_RASTER`` (``compute`` / ``raster``), else ``"auto"``
            (:func:`~splatedit.render.splat.compute_raster.choose_path`: compute
            wherever the device and frame allow it).  A frame the compute
            path cannot draw (no 64-bit / float atomics, the vertex path, an
            image over the storage-buffer range) is drawn by the raster path
            even when ``"compute"`` is asked for; :meth:`frame_path` says which.
    """

    def __init__(self, *, device_name: str | None = None, validation: bool | None = None,
                 accum_format: str = "rgba16f", backface_culling: bool = True,
                 background=RENDER_BACKGROUND, point_splats: bool = True, prepass: bool = True,
                 device: V.Device | None = None, raster_path: str | None = None):
        if accum_format not in ("rgba16f", "rgba32f"):
            raise ParameterError("accum_format", f"must be 'rgba16f' or 'rgba32f', got {accum_format!r}")
        self.accum_format = accum_format
        #: requested rasterization path, "auto" | "raster" | "compute" (see raster_path)
        self.raster_path = requested_path(raster_path)
        self._crast = None            # ComputeRaster of the current size and pre-pass
        #: the "auto" path's measured choice per probe_key(width, height, splat
        #: count): {"path", "ms_raster", "ms_compute"} (one probe frame of each path)
        self.path_probes: dict = {}
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
        #: eye-dome lighting (frame_passes.EyeDomeResolve): darken each pixel
        #: by the log-depth steps to its neighbours at ``edl_radius_px``
        #: pixels, ``exp(-300 * edl_strength * mean step)``; off by default
        self.edl = False
        self.edl_strength = float(RENDER_EDL_STRENGTH)
        self.edl_radius_px = float(RENDER_EDL_RADIUS_PX)
        self.background = tuple(float(x) for x in background)
        #: alpha of background pixels in the output (0: uncovered pixels are
        #: told apart, as :mod:`splatedit.render.splat.progressive` does)
        self.background_alpha = 1.0
        #: frames recorded so far (a progressive frame restarts when another
        #: frame has used the shared targets in between)
        self.frames_recorded = 0
        self._own_device = device is None
        self.dev = device if device is not None else V.Device(device_name=device_name, validation=validation)
        self._closed = False
        self.cache = self.sampler = self.ubo = self.splat_set = None
        self._targets = None
        #: the compute pre-pass (:class:`~splatedit.render.splat.prepass.Prepass`; None
        #: until the frame objects exist).  Not ``prepass``: that is the on/off switch.
        self.prepass_part: Prepass | None = None
        #: the scene's buffers (:class:`~splatedit.render.splat.uploads.SceneUploads`)
        self.uploads = SceneUploads(self.dev, self._free_prep)
        self.dC_ubo = None
        self.last_timings_ms: dict[str, float] = {}
        self._query = None
        self._max_point_size = float(self.dev.limits.pointSizeRange[1]) if self.dev.features.largePoints else 1.0
        try:
            create_frame_objects(self, UBO_BYTES)
            self.splat_set = V.DescriptorSet(self.dev, self.cache.set_layout(SPLAT_SET))
            self.splat_set.write({0: self.ubo, 1: self.dC_ubo})
            self._query = V.QueryPool(self.dev, 16)
            self.prepass_part = Prepass(self.dev, self.cache, self.uploads, self.ubo, self.dC_ubo)
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
        step(lambda: self._free_compute_raster(wait=False))     # waited above
        step(self.uploads.free)
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

    def check_open(self):
        """Raise ParameterError when the renderer is closed."""
        if self._closed:
            raise ParameterError("renderer", "is closed")

    # -------------------------------------------------------------- scene
    # The scene's buffers live in self.uploads (SceneUploads); these are the
    # renderer's public face of them (and of the SceneRenderer protocol).
    @property
    def cloud(self):
        """The uploaded :class:`~splatedit.model.cloud.SplatCloud` (None before :meth:`set_cloud`)."""
        return self.uploads.cloud

    @property
    def n(self) -> int:
        """Splats of the uploaded cloud (0 without one)."""
        return self.uploads.n

    @property
    def origin(self) -> np.ndarray:
        """(3,) model-space point that GPU coordinates are relative to (the cloud's box centre)."""
        return self.uploads.origin

    @property
    def scale(self) -> float:
        """Model units per GPU unit (an exact power of two, see :meth:`set_cloud`)."""
        return self.uploads.scale

    @property
    def bounds(self):
        """(lo, hi) undeformed bounds padded by the largest splat radius; near/far
        come from these grown by the deformation's reach (:meth:`clip_bounds`)."""
        return self.uploads.bounds

    def set_cloud(self, cloud) -> None:
        """Upload a cloud (float32 relative to its bounding-box centre, in units
        of :attr:`scale`, a power of two near its size, so that a model of
        any size from 1e-15 to 1e15 renders the same); clears selection and
        basis (:meth:`SceneUploads.set_cloud <splatedit.render.splat.uploads.SceneUploads.set_cloud>`)."""
        self.check_open()
        self.uploads.set_cloud(cloud)

    def require_cloud(self):
        """Raise ParameterError when no cloud is set."""
        self.uploads.require_cloud()

    def set_selection(self, support_mask=None, handle_mask=None, inactive_mask=None) -> None:
        """Tint the support region (blue) and handle (green); boolean masks of
        shape (n,) or index arrays; None clears.  ``inactive_mask``: splats
        of inactive handles, tinted green and drawn darker."""
        self.check_open()
        self.uploads.set_selection(support_mask, handle_mask, inactive_mask)

    def set_basis(self, indices, B, Bx, By, Bz) -> None:
        """Deformation basis rows for the splats ``indices`` (N,); B, Bx, By, Bz
        are (N, K) with any K in 1..``RENDER_MAX_BASIS_COLUMNS`` (16); other
        splats are not deformed; a new K resets the displacement; drops a
        :meth:`set_detail` (:meth:`SceneUploads.set_basis
        <splatedit.render.splat.uploads.SceneUploads.set_basis>` says more)."""
        self.check_open()
        self.uploads.set_basis(indices, B, Bx, By, Bz)

    def set_detail(self, indices, detail) -> None:
        """Detail-preserving mode: ``detail`` (N, 4) = (base normal n_b, offset
        lambda in model units) of the splats ``indices`` (:meth:`SceneUploads.set_detail
        <splatedit.render.splat.uploads.SceneUploads.set_detail>`); drawn by the
        compute pre-pass (images up to 4095 pixels)."""
        self.check_open()
        self.uploads.set_detail(indices, detail)

    def clear_basis(self) -> None:
        """Drop the deformation basis (every splat undeformed)."""
        self.check_open()
        self.uploads.clear_basis()

    def set_displacement(self, dC) -> None:
        """Control-frame displacement dC (K, 3), K = the basis' column count
        (K = 4 before any :meth:`set_basis`); uploaded when the next frame is
        recorded, whose near/far planes allow for the largest possible splat
        displacement (:meth:`clip_bounds`)."""
        self.check_open()
        self.uploads.set_displacement(dC)

    def clip_bounds(self):
        """The box that near/far are chosen from: the undeformed bounds grown
        by a bound on any splat's displacement (:meth:`displacement_reach`), so
        that geometry moved outside the model (a handle dragged towards the eye)
        is not clipped."""
        lo, hi = self.bounds
        grow = self.displacement_reach()
        return lo - grow, hi + grow

    def displacement_reach(self) -> float:
        """A bound (model units) on how far any splat is moved from its uploaded
        position by the current basis and displacement (0 without a basis)."""
        return self.uploads.displacement_reach()

    # ------------------------------------------------------------ pre-pass
    def _free_prep(self):
        if self.prepass_part is not None:
            self.prepass_part.free()

    def use_prepass(self) -> bool:
        """Whether this frame's splat passes draw compute pre-pass records (see
        the ``prepass`` argument; the detail mode always does)."""
        t = self._targets
        if self.uploads.detail_buf is not None:   # the detail mode has no vertex-path variant
            if t is not None and max(t.width, t.height) > PREP_MAX_SIZE:
                raise ParameterError("size", f"the detail mode renders images up to {PREP_MAX_SIZE} "
                                             f"pixels wide and high, got {t.width}x{t.height}")
            return True
        if not self.prepass:
            return False
        # any size: clouds whose records (48 bytes per splat) or geometry do
        # not fit one storage binding are drawn in splat windows
        return not (t is not None and max(t.width, t.height) > PREP_MAX_SIZE)

    @property
    def prepass_windows(self) -> int:
        """Splat windows the compute pre-pass prepares and draws the cloud in at
        the current image size: 1 when the cloud fits one storage binding, 0 for
        the vertex path (pre-pass off, images above 4095 pixels, no cloud)."""
        if self.cloud is None or not self.use_prepass():
            return 0
        return len(self.prepass_part.spans())

    def prep_objects(self) -> PrepObjects:
        """The pre-pass buffers and sets (:meth:`Prepass.objects
        <splatedit.render.splat.prepass.Prepass.objects>`)."""
        return self.prepass_part.objects()

    def prep_range(self, first: int, count: int) -> tuple[int, list, list]:
        """Sets that prepare only splats ``first`` .. ``first + count - 1``
        (:meth:`Prepass.range_sets <splatedit.render.splat.prepass.Prepass.range_sets>`)."""
        return self.prepass_part.range_sets(first, count)

    def record_prepass(self, cb, window: int = 0, sets: list | None = None):
        """The compute pre-pass of splat window ``window`` (:meth:`Prepass.record
        <splatedit.render.splat.prepass.Prepass.record>`)."""
        self.prepass_part.record(cb, window, sets)

    def record_splat_pass(self, cb, kind: str, desc: V.RenderPassDesc, fb, clears, prepared: bool):
        """One splat pass (``kind`` depth, attr or pick) into ``fb``. With several
        pre-pass windows: per window, its pre-pass then its draws (in a render
        pass that keeps the previous windows' results)."""
        count = self.prepass_part.window_count(prepared)
        if count == 1:
            cb.begin_render_pass(self.cache.render_pass(desc), fb, clears)
            self.record_splats(cb, kind, prepared)
            cb.end_render_pass()
            return
        for k in range(count):
            self.record_prepass(cb, k)
            cb.begin_render_pass(self.cache.render_pass(rp_window(desc, k == 0, k == count - 1)), fb, clears)
            self.record_splats(cb, kind, True, k)
            cb.end_render_pass()

    # ---------------------------------------------------------- pipelines
    def _vertex_layout(self, basis_stride: int):
        g = self.uploads.basis_groups
        bindings = (V.VertexBinding(0, GEOM_STRIDE), V.VertexBinding(1, 4), V.VertexBinding(2, 4),
                    V.VertexBinding(3, basis_stride))
        off = {f: SPLAT_GEOM.fields[f][1] for f in ("center", "u", "v")}    # splatedit/render/uniforms.py
        attrs = [V.VertexAttribute(0, 0, "vec3", off["center"]), V.VertexAttribute(1, 0, "vec3", off["u"]),
                 V.VertexAttribute(2, 0, "vec3", off["v"]), V.VertexAttribute(3, 1, "unorm8x4", 0),
                 V.VertexAttribute(4, 2, "uint", 0)]
        attrs += [V.VertexAttribute(5 + i, 3, "vec4", 16 * i) for i in range(4 * g)]
        return bindings, tuple(attrs)

    def _splat_pipeline(self, kind: str, mode: int = 0):
        g = self.uploads.basis_groups
        bindings, attrs = self._vertex_layout(64 * g if self.uploads.deformed else 0)
        layout = V.LayoutDesc(sets=(SPLAT_SET,))
        vert = "splat.vert" if g == 1 else f"splat_k{4 * g}.vert"
        return self.cache.pipeline(splat_desc(vert, kind, self.accum_format, layout, bindings=bindings,
                                               attributes=attrs, spec=((0, mode),),
                                               topology="point_list" if mode == 2 else "triangle_strip"))

    def _resolve_pipeline(self, target: RenderTarget):
        return self.cache.pipeline(resolve_desc(target, "resolve.frag", RESOLVE_SET))

    def _record_resolve(self, cb, t: SplatTargets, target: RenderTarget) -> None:
        """The shading pass: normalise the accumulators of ``t``, shade, write ``target``."""
        t.record_resolve(cb, target, "resolve.frag", RESOLVE_SET)

    # ------------------------------------------------------------- frames
    def targets_for(self, width: int, height: int) -> SplatTargets:
        t = reusable_targets(self, self._targets, width, height)
        if t is None:
            self._targets = None                # a failure below leaves no destroyed targets behind
            t = self._targets = SplatTargets(self, int(width), int(height))
        return t

    def write_ubo(self, camera: Camera, width: int, height: int, apply_gamma: bool = True):
        # everything on the GPU is in model units relative to origin, divided
        # by scale: so is the camera (a similarity: the image is the same)
        o, sc = self.origin, self.scale
        gpu_cam = gpu_camera(camera, o, sc)
        lo, hi = self.clip_bounds()
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
        u["display"] = (self.splat_scale, RENDER_GREY_ALBEDO if self.grey_shading else -1.0,
                        *((self.edl_strength, self.edl_radius_px) if self.edl else (0.0, 0.0)))
        self.ubo.write(u)
        up = self.uploads
        if up.dC_dirty:
            self.dC_ubo.write(up.deform_block())
            up.dC_dirty = False
        self.near_far = (near * sc, far * sc)     # model units

    def record_splats(self, cb, kind: str, prepared: bool = False, window: int = 0):
        """Draw every splat: as quads, or (point_splats) tiny ones as points +
        the others as quads; ``prepared``: the records of pre-pass window ``window``."""
        if prepared:
            prep = self.prep_objects()
            dset, draws = prep.dset, prep.draws
            n = np.array((prep.windows[window][1],), PREPARED_PUSH)
            for mode, offset in ((1, 0), (2, 16)):
                pipeline = self.prepass_part.draw_pipeline(kind, mode, self.accum_format)
                cb.bind_pipeline(pipeline)
                cb.bind_descriptor_set(pipeline, dset)
                cb.push_constants(pipeline, n)
                cb.draw_indirect(draws, offset)
            return
        self.record_vertex_splats(cb, kind, 0, self.n)

    def record_vertex_splats(self, cb, kind: str, first: int, count: int) -> None:
        """Vertex path: draw splats ``first`` .. ``first + count - 1`` (one
        instance each) as quads, or (point_splats) tiny ones as points + the
        others as quads (:mod:`splatedit.render.splat.progressive` draws its chunks so)."""
        modes = ((1, 4), (2, 1)) if self.point_splats else ((0, 4),)
        up = self.uploads
        bufs = [up.geom, up.color, up.flags, up.basis_binding()]
        for mode, verts in modes:
            pipeline = self._splat_pipeline(kind, mode)
            cb.bind_pipeline(pipeline)
            cb.bind_descriptor_set(pipeline, self.splat_set)
            cb.bind_vertex_buffers(0, bufs)
            cb.draw(verts, count, 0, first)

    def fb_attr_readback(self, t: SplatTargets):
        if getattr(t, "fb_attr_rb", None) is None:
            rp = self.cache.render_pass(rp_attr(self.accum_format, "transfer_src"))
            t.fb_attr_rb = t.framebuffer(rp, [t.accum_color, t.accum_normal, t.depth])
        return t.fb_attr_rb

    # ------------------------------------------------- frames as pass lists
    #: the :class:`~splatedit.render.scene.SceneRenderer` capabilities: the detail
    #: mode's rows (set_detail) and frames the presenter blits (render_resident)
    supports_detail = True
    resident_frames = True
    supports_edl = True

    @property
    def targets(self):
        """The per-size images of the last frame size (None before a frame)."""
        return self._targets

    #: the resolve pass's shader and descriptor-set layout (frame.Resolve)
    resolve_shader = "resolve.frag"
    resolve_set_layout = RESOLVE_SET

    def frame_path(self, width: int, height: int) -> str:
        """``"compute"`` or ``"raster"``: the path a frame of this size takes
        now (:attr:`raster_path` and what the device and frame allow,
        :func:`~splatedit.render.splat.compute_raster.choose_path`)."""
        self.targets_for(width, height)
        path = choose_path(self.raster_path, self.dev, width, height, self.use_prepass())
        if path == "compute" and self.raster_path == "auto":
            key = probe_key(width, height, self.n)
            if key not in self.path_probes:
                near = [k for k, v in self.path_probes.items()
                        if k[0] == key[0] and abs(k[1] - key[1]) == 1 and "reused" not in v]
                # a count one half-octave from a measured one (a scan growing as its view
                # refines): that measurement's choice, not two more full frames per growth
                self.path_probes[key] = (dict(self.path_probes[near[0]], reused=near[0]) if near
                                         else self._probe_paths(width, height))
            path = self.path_probes[key]["path"]
        return path

    def _probe_paths(self, width: int, height: int) -> dict:
        """The measured choice of ``"auto"``: one frame of each path (the
        current frame uniforms, no shading pass), the faster by GPU time wins
        (:attr:`path_probes`)."""
        t = self.targets_for(width, height)
        ms = {}
        for path in ("raster", "compute"):
            self.dev.submit(lambda cb, p=path: self._record(cb, splat_frame(p, resolve=False), t))
            ms[path] = self._last_frame.read_timings(self._query)["total"]
        return {"path": min(ms, key=ms.get), **{f"ms_{p}": round(v, 3) for p, v in ms.items()}}

    def compute_rasterizer(self, t: SplatTargets) -> ComputeRaster:
        """The compute rasterizer's buffers for targets ``t`` and the current pre-pass."""
        prep = self.prep_objects()
        c = self._crast
        if c is None or c.t is not t or c.prep is not prep:
            self._free_compute_raster()
            self._crast = ComputeRaster(self, t, prep)
        return self._crast

    def _free_compute_raster(self, wait: bool = True) -> None:
        if self._crast is not None:
            c, self._crast = self._crast, None
            if wait:
                self.dev.wait_idle()
            c.destroy()

    def _record(self, cb, frame: Frame, t: SplatTargets, target=None) -> Frame:
        """Record ``frame`` (timestamps in the query pool) against targets ``t``."""
        if frame.outputs & {"depth", "accum", "vis_buffer", "accum_buffers"}:
            self.frames_recorded += 1      # the shared targets a progressive frame draws into
        prepared = self.use_prepass()
        ctx = FrameContext(self, t, target, prepared, self.prepass_part.window_count(prepared))
        cb.reset_queries(self._query)
        frame.record(cb, ctx, self._query)
        self._last_frame = frame
        return frame

    def splat_frame(self, width: int, height: int, attr_final: str = "shader_read", resolve: bool = True) -> Frame:
        """The pass list of a frame of this size on :meth:`frame_path`
        (:func:`splatedit.render.splat.passes.splat_frame`)."""
        return splat_frame(self.frame_path(width, height), attr_final, resolve, self.edl)

    def record_frame(self, cb, camera: Camera, target: RenderTarget):
        """Record the frame (:meth:`splat_frame`) into ``cb`` writing ``target``
        (used by :meth:`render`; the editor calls it with a swapchain target)."""
        self.require_cloud()
        t = self.targets_for(target.width, target.height)
        self.write_ubo(camera, target.width, target.height, target.apply_gamma)
        self._record(cb, self.splat_frame(target.width, target.height), t, target)

    def _read_timings(self):
        """Per-pass GPU times of the last recorded frame into :attr:`last_timings_ms`
        (``prepass``, ``visibility``, ``attributes``, ``shading``, ``total`` as
        the frame has them; ms)."""
        self.last_timings_ms = self._last_frame.read_timings(self._query)

    # ---------------------------------------------------------- public API
    def render(self, camera: Camera, width: int, height: int) -> np.ndarray:
        """Render offscreen; returns (height, width, 4) uint8 RGBA (sRGB)."""
        self.check_open()
        self.require_cloud()
        t = self.targets_for(width, height)
        out = t.read_output(lambda cb: self.record_frame(cb, camera, t.offscreen))
        self._read_timings()
        return out

    def render_resident(self, camera: Camera, width: int, height: int):
        """Render without reading back: the frame stays on the device in an
        ``rgba8`` image (TRANSFER_SRC layout, sRGB values) that is returned and
        valid until the next frame of this renderer (the editor blits it into
        the swapchain image, :meth:`SwapchainPresenter.render_frame`).  The
        caller must not re-render while a submitted frame still reads it."""
        self.check_open()
        self.require_cloud()
        t = self.targets_for(width, height)
        self.dev.submit(lambda cb: self.record_frame(cb, camera, t.offscreen))
        self._read_timings()
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
        self.check_open()
        self.require_cloud()
        t = self.targets_for(width, height)
        texel = 8 if self.accum_format == "rgba16f" else 16
        plane = width * height * texel
        rb = V.Buffer(self.dev, 2 * plane, ("transfer_dst",), host_visible=True)
        try:
            def rec(cb):
                self.write_ubo(camera, width, height)
                self._record(cb, self.splat_frame(width, height, "transfer_src", resolve=False), t)
                cb.copy_image_to_buffer(t.accum_color, rb)
                cb.copy_image_to_buffer(t.accum_normal, rb, buf_offset=plane)
                cb.host_read_barrier()
            self.dev.submit(rec)
            raw = rb.read()
        finally:
            rb.destroy()
        self._read_timings()
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
        self.check_open()
        self.require_cloud()
        t = self.targets_for(width, height)
        if getattr(t, "fb_points", None) is None:
            t.points_color = t.add(V.Image(self.dev, width, height, "rgba8", ("color",)))
            t.points_depth = t.add(V.Image(self.dev, width, height, "d32f", ("depth",)))
            t.fb_points = t.framebuffer(self.cache.render_pass(RP_POINTS), [t.points_color, t.points_depth])
        desc = V.GraphicsDesc("points.vert", "points.frag", RP_POINTS, V.LayoutDesc(sets=(SPLAT_SET,)),
                              topology="point_list", bindings=(V.VertexBinding(0, GEOM_STRIDE, per_instance=False),),
                              attributes=(V.VertexAttribute(0, 0, "vec3", SPLAT_GEOM.fields["center"][1]),),
                              depth_test=True, depth_write=True)
        pipe = self.cache.pipeline(desc)

        def rec(cb):
            self.write_ubo(camera, width, height)
            cb.reset_queries(self._query)
            cb.timestamp(self._query, 0, bottom=False)
            cb.begin_render_pass(self.cache.render_pass(RP_POINTS), t.fb_points, [(1.0, 1.0, 1.0, 1.0), 1.0])
            cb.bind_pipeline(pipe)
            cb.bind_descriptor_set(pipe, self.splat_set)
            cb.bind_vertex_buffers(0, [self.uploads.geom])
            cb.draw(self.n)
            cb.end_render_pass()
            cb.timestamp(self._query, 1)
        self.dev.submit(rec)
        ts = self._query.results_ns(2)
        self.last_timings_ms = {"points": float(ts[1] - ts[0]) * 1e-6, "total": float(ts[1] - ts[0]) * 1e-6}
        return self.last_timings_ms["points"]

    def pick(self, camera: Camera, width: int, height: int, rect=None):
        """Splat index per pixel (-1 background) and eye-space depth along the
        view axis (NaN background) of the nearest splat, for the whole image
        or ``rect`` = (x, y, w, h) in pixels (clipped to the image)."""
        self.check_open()
        self.require_cloud()
        t = self.targets_for(width, height)

        def rec(cb):
            self.write_ubo(camera, width, height)
            self._record(cb, pick_frame(), t)
        out = t.read_pick(rect, rec)
        self._read_timings()
        return out
