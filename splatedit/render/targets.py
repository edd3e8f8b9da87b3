"""Render targets and per-size images shared by the splat renderer
(:mod:`splatedit.render.splat.renderer`) and the Gaussian renderer
(:mod:`splatedit.render.gaussian.renderer`): the :class:`RenderTarget` the final pass
writes, the base of both renderers' per-size image sets (framebuffers per
target, the pick images), and the decoding of a pick readback.

Only :mod:`splatedit.render.vk` calls Vulkan.
"""

from __future__ import annotations

import itertools

import numpy as np

from splatedit.errors import ParameterError
from splatedit.render import vk as V
from splatedit.render.gpu_units import DEFORM_UBO_BYTES
from splatedit.render.splat.layout import RP_PICK, RESOLVE_SET, RP_DEPTH, rp_attr

#: largest image side (pixels) either renderer accepts
MAX_SIZE = 16384



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


def rp_resolve(target: RenderTarget) -> V.RenderPassDesc:
    """The render pass of a full-screen pass writing ``target`` (contents discarded first)."""
    return V.RenderPassDesc(colors=(V.Attachment(target.format, "dont_care", final=target.final),))


def resolve_desc(target: RenderTarget, frag: str, set_layout: tuple) -> V.GraphicsDesc:
    """The full-screen pass (``fullscreen.vert`` + ``frag``, descriptor set
    ``set_layout``) writing ``target``."""
    return V.GraphicsDesc("fullscreen.vert", frag, rp_resolve(target), V.LayoutDesc(sets=(set_layout,)),
                          topology="triangle_list")


class SizedTargets:
    """Images and framebuffers of one image size, owned by renderer ``r``
    (anything with ``dev`` and ``cache``).  Subclasses create theirs in
    :meth:`_create`; a failure part-way (an image too large for the device)
    destroys what was already created."""

    def __init__(self, r, width: int, height: int):
        self.width, self.height = width, height
        self.objects = []
        self.target_fbs = {}      # target.serial -> (target, framebuffer)
        self.pick_index = self.pick_depth = self.fb_pick = None
        self._r = r
        try:
            self._create(r)
        except BaseException:
            self.destroy()
            raise

    def _create(self, r) -> None:
        raise NotImplementedError

    def add(self, obj):
        self.objects.append(obj)
        return obj

    def framebuffer(self, rp, atts):
        """A framebuffer of this size on render pass ``rp`` with attachments ``atts``."""
        return self.add(V.Framebuffer(self._r.dev, rp, atts, self.width, self.height))

    def target_fb(self, target: RenderTarget):
        """The (cached) framebuffer of :func:`rp_resolve` writing ``target``."""
        hit = self.target_fbs.get(target.serial)
        if hit is None:
            fb = self.framebuffer(self._r.cache.render_pass(rp_resolve(target)), [target.attachment])
            hit = self.target_fbs[target.serial] = (target, fb)
        return hit[1]

    def record_resolve(self, cb, target: RenderTarget, frag: str, set_layout: tuple) -> None:
        """Record the full-screen pass :func:`resolve_desc` reading
        ``self.resolve_set`` (layout ``set_layout``) into ``target``."""
        cache = self._r.cache
        pipe = cache.pipeline(resolve_desc(target, frag, set_layout))
        cb.begin_render_pass(cache.render_pass(rp_resolve(target)), self.target_fb(target), [None])
        cb.bind_pipeline(pipe)
        cb.bind_descriptor_set(pipe, self.resolve_set)
        cb.draw(3)
        cb.end_render_pass()

    def ensure_pick(self):
        """Create the pick images and framebuffer on first use (none left on failure)."""
        if self.fb_pick is None:
            dev = self._r.dev
            first = len(self.objects)
            try:
                self.pick_index = self.add(V.Image(dev, self.width, self.height, "r32ui",
                                                    ("color", "transfer_src")))
                self.pick_depth = self.add(V.Image(dev, self.width, self.height, "d32f",
                                                    ("depth", "transfer_src")))
                self.fb_pick = self.framebuffer(self._r.cache.render_pass(RP_PICK), [self.pick_index, self.pick_depth])
            except BaseException:
                for o in reversed(self.objects[first:]):
                    o.destroy()
                del self.objects[first:]
                self.pick_index = self.pick_depth = self.fb_pick = None
                raise

    def read_output(self, record) -> np.ndarray:
        """Submit ``record(cb)`` (a frame writing :attr:`offscreen`) and read
        the output image back: (height, width, 4) uint8 RGBA."""
        dev = self._r.dev
        rb = V.Buffer(dev, self.width * self.height * 4, ("transfer_dst",), host_visible=True)
        try:
            def rec(cb):
                record(cb)
                cb.copy_image_to_buffer(self.out, rb)
                cb.host_read_barrier()
            dev.submit(rec)
            return rb.read().reshape(self.height, self.width, 4)
        finally:
            rb.destroy()

    def read_pick(self, rect, record):
        """Index (h, w) int64 (-1 background) and view-axis depth (h, w)
        float64 (model units, NaN background) of the pixels ``rect`` (see
        :func:`clip_rect`): submits ``record(cb)`` (the renderer's pick pass
        into :attr:`fb_pick`, which sets its ``near_far``) and reads back."""
        self.ensure_pick()
        x, y, w, h = clip_rect(rect, self.width, self.height)
        nbytes = w * h * 4
        dev = self._r.dev
        rb = V.Buffer(dev, 2 * nbytes, ("transfer_dst",), host_visible=True)
        try:
            def rec(cb):
                record(cb)
                cb.copy_image_to_buffer(self.pick_index, rb, (x, y, w, h))
                cb.copy_image_to_buffer(self.pick_depth, rb, (x, y, w, h), buf_offset=nbytes)
                cb.host_read_barrier()
            dev.submit(rec)
            raw = rb.read()
        finally:
            rb.destroy()
        return decode_pick(raw, w, h, self._r.near_far)

    def destroy(self):
        for o in reversed(self.objects):
            o.destroy()
        self.objects.clear()
        self.target_fbs.clear()


class SplatTargets(SizedTargets):
    """Per-size images and framebuffers of the splat renderer ``r``
    (:class:`splatedit.render.splat.renderer.Renderer`): depth, the two attribute
    accumulators, the RGBA8 output and the resolve pass's descriptor set."""

    def _create(self, r):
        dev = r.dev
        width, height = self.width, self.height

        def img(fmt, usage):
            return self.add(V.Image(dev, width, height, fmt, usage))

        self.depth = img("d32f", ("depth", "transfer_src"))
        # storage: the compute rasterizer's copy pass writes them (splatedit.render.splat.compute_raster)
        accum_usage = ("color", "sampled", "transfer_src") + (("storage",) if r.dev.compute_raster else ())
        self.accum_color = img(r.accum_format, accum_usage)
        self.accum_normal = img(r.accum_format, accum_usage)
        self.out = img("rgba8", ("color", "transfer_src"))
        self.offscreen = RenderTarget(self.out, "rgba8", "transfer_src")
        rp_depth = r.cache.render_pass(RP_DEPTH)
        rp_attr_pass = r.cache.render_pass(rp_attr(r.accum_format, "shader_read"))
        self.fb_depth = self.framebuffer(rp_depth, [self.depth])
        self.fb_attr = self.framebuffer(rp_attr_pass, [self.accum_color, self.accum_normal, self.depth])
        self.resolve_set = self.add(V.DescriptorSet(dev, r.cache.set_layout(RESOLVE_SET)))
        self.resolve_set.write({0: r.ubo, 1: (self.accum_color, r.sampler), 2: (self.accum_normal, r.sampler)})


def create_frame_objects(r, ubo_bytes: int) -> None:
    """The objects of a renderer ``r`` (with ``dev``) shared by all its frame
    sizes, as attributes of ``r``: ``cache`` (pipeline cache), ``sampler``,
    ``ubo`` (the frame uniforms, ``ubo_bytes``) and ``dC_ubo`` (deform.glsl's
    block, zeros: nothing deformed).  On failure those created stay set for
    the caller's ``close``."""
    r.cache = V.PipelineCache(r.dev)
    r.sampler = V.Sampler(r.dev)
    r.ubo = V.Buffer(r.dev, ubo_bytes, ("uniform",), host_visible=True)
    r.dC_ubo = V.Buffer(r.dev, DEFORM_UBO_BYTES, ("uniform",), host_visible=True)
    r.dC_ubo.view(np.float32)[:] = 0.0


def reusable_targets(r, current, width: int, height: int):
    """``current`` (renderer ``r``'s per-size targets, or None) when it has
    this image size; else None, after destroying ``current`` (once the device
    is idle): the caller makes new ones.  Raises ParameterError for a size
    outside 1..MAX_SIZE (``current`` is then kept)."""
    for name, v in (("width", width), ("height", height)):
        if not isinstance(v, (int, np.integer)) or not 1 <= v <= MAX_SIZE:
            raise ParameterError(name, f"must be an integer in 1..{MAX_SIZE}, got {v!r}")
    if current is not None and (current.width, current.height) == (width, height):
        return current
    if current is not None:
        r.dev.wait_idle()
        current.destroy()
    return None


def clip_rect(rect, width: int, height: int) -> tuple[int, int, int, int]:
    """(x, y, w, h) pixels of a pick: the whole image for ``rect`` None, else
    ``rect`` clipped to the image; ParameterError when nothing is left."""
    if rect is None:
        return 0, 0, width, height
    x, y, w, h = (int(v) for v in rect)
    x0, y0, x1, y1 = max(x, 0), max(y, 0), min(x + w, width), min(y + h, height)
    if x1 <= x0 or y1 <= y0:
        raise ParameterError("rect", f"{tuple(rect)} does not overlap the {width}x{height} image")
    return x0, y0, x1 - x0, y1 - y0


def decode_pick(raw: np.ndarray, w: int, h: int, near_far: tuple[float, float]):
    """Index (h, w) int64 (-1 background) and view-axis depth (h, w) float64
    (model units, NaN background) from a pick readback: ``raw`` holds the
    r32ui index + 1 plane, then the d32f depth plane (near/far in model units)."""
    nbytes = w * h * 4
    idx = raw[:nbytes].view(np.uint32).reshape(h, w).astype(np.int64) - 1
    d = raw[nbytes:2 * nbytes].view(np.float32).reshape(h, w).astype(np.float64)
    near, far = near_far
    with np.errstate(divide="ignore", invalid="ignore"):
        depth = near / (1.0 - d * (far - near) / far)
    depth[idx < 0] = np.nan
    return idx, depth
