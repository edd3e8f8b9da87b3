"""Progressive full-quality frames: a huge model drawn a chunk of splats at a time.

A full-quality frame of 10M splats takes tens of seconds on lavapipe.  A
:class:`ProgressiveFrame` spreads it over many short steps (one GPU submit
each) so a window stays responsive and the image sharpens while it is drawn:

1. visibility: ``ceil(n / chunk)`` steps draw the splats' depth into the
   renderer's depth target (the first step clears it, the others load it);
2. attributes: the same chunks are accumulated into the colour/normal
   targets against the complete depth buffer; ``step()`` then resolves what
   has been accumulated so far into an image and reads it back, or (without
   readback, below) :meth:`show` composes it on the device when asked.

Each chunk goes through the compute pre-pass when the renderer uses it
(:meth:`Renderer.use_prepass`): a step runs the pre-pass of the chunk's
splats only (a whole number of workgroups inside one pre-pass window, so
``chunk`` is rounded up to a multiple of 64 and a chunk never crosses a
window) and then draws their records, in the same submit.  Otherwise (pre-pass
off, images above 4095 pixels) the chunks are drawn on the vertex path.

Every intermediate image of phase 2 is exact where it is covered: a pixel
shows the normalised blend of the splats drawn so far that pass the final
visibility test, and is transparent (alpha 0) where no splat has arrived
yet, so the caller can composite it over its level-of-detail frame.  The
last image equals :meth:`Renderer.render`: bit for bit on the vertex path
(the chunks are drawn in splat order, as the single draw would); on the
pre-pass path within the pre-pass tolerance (records are blended in the
order the pre-pass's atomics hand out, which differs between runs).  Chunks
are contiguous ranges of the cloud's order, so a spatially sorted cloud
fills in region by region.

The frame belongs to one renderer, camera, size and scene state: when the
renderer draws any other frame in between (or the selection, basis or
displacement change), start a new one; :meth:`step` detects another frame
(:attr:`Renderer.frames_recorded`) and starts over by itself.

Without readback (the editor, :mod:`splatedit.app.view.progressive_refine`):
:meth:`set_under` gives the level-of-detail frame (a device image, scaled by
one blit, or pixels), ``step(readback=False)`` only draws chunks (several per
presented frame, the chunk sized to the frame budget), and :meth:`show`
composes on the device: one shading pass over the rect the new chunks can
reach, blended over the shown image (uncovered pixels keep the frame under),
and once :attr:`done` the renderer's own output image (the one-submit frame).
Drop the frame on any camera or scene change.
"""

from __future__ import annotations

import weakref

import numpy as np

from splatedit.errors import ParameterError
from splatedit.render import vk as V
from splatedit.render.camera import Camera
from splatedit.render.splat.renderer import Renderer
from splatedit.render.splat.passes import EyeDomeResolve, FrameContext, RasterSplats, Resolve
from splatedit.render.splat.layout import RESOLVE_SET, WORKGROUP
from splatedit.tolerances import PROGRESSIVE_SHADE_PAD_PX

#: the chunk boxes of a renderer's cloud: renderer -> (cloud, lo, hi, radius)
_BOXES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()

#: splats per box of the shading rect (:meth:`ProgressiveFrame._chunk_rect`)
_BOX_BLOCK = 4096

#: the shading pass over the shown image: loads it, writes covered pixels ("over":
#: the intermediate uniforms give uncovered pixels alpha 0, so they keep what is there)
_RP_OVER = V.RenderPassDesc(colors=(V.Attachment("rgba8", "load", initial="transfer_src", final="transfer_src"),))
_OVER_DESC = V.GraphicsDesc("fullscreen.vert", "resolve.frag", _RP_OVER, V.LayoutDesc(sets=(RESOLVE_SET,)),
                            topology="triangle_list", blend_alpha=True)
#: the same with eye-dome lighting (Renderer.edl): the shown image is shaded as the one-submit frame is
_OVER_EDL_DESC = V.GraphicsDesc("fullscreen.vert", "resolve_edl.frag", _RP_OVER, V.LayoutDesc(sets=(RESOLVE_SET,)),
                                topology="triangle_list", blend_alpha=True)


def _resolve(r: Renderer) -> Resolve:
    """The renderer's shading pass (:class:`EyeDomeResolve` with ``r.edl``)."""
    return EyeDomeResolve() if r.edl else Resolve()


def _union(a, b):
    """The smallest (x, y, w, h) rect holding rects ``a`` and ``b`` (None: empty)."""
    if a is None or b is None:
        return a if b is None else b
    x0, y0 = min(a[0], b[0]), min(a[1], b[1])
    x1, y1 = max(a[0] + a[2], b[0] + b[2]), max(a[1] + a[3], b[1] + b[3])
    return x0, y0, x1 - x0, y1 - y0


def composite(image: np.ndarray, under: np.ndarray) -> np.ndarray:
    """``image`` (h, w, 4) uint8 from :meth:`ProgressiveFrame.step` over
    ``under`` (same shape): pixels with alpha 0 come from ``under``."""
    return np.where(image[..., 3:4] == 0, under, image)


class ProgressiveFrame:
    """A full-quality frame of ``renderer``'s cloud drawn ``chunk`` splats per step.

    Args:
        renderer: a :class:`Renderer` with a cloud set.
        camera, width, height: the view.
        chunk: splats per step (at least 1).
    """

    def __init__(self, renderer: Renderer, camera: Camera, width: int, height: int, chunk: int):
        renderer.check_open()
        renderer.require_cloud()
        if int(chunk) < 1:
            raise ParameterError("chunk", f"must be at least 1, got {chunk!r}")
        self.r = renderer
        self.camera = camera
        self.width, self.height = width, height
        self.chunk = int(chunk)
        self.n = renderer.n
        self._rb = V.Buffer(renderer.dev, width * height * 4, ("transfer_dst",), host_visible=True)
        self._shown = self._fb_over = None      # the composed image (set_under / show)
        self.shaded_rect = None
        self._under = None
        self._unshown = False                   # attribute chunks drawn since the last shading pass
        self._restart()

    def _restart(self) -> None:
        self.phase = "depth"
        self.next = 0
        self.restarts = getattr(self, "restarts", -1) + 1
        self._pick_next = 0
        self._unshown = False
        self._dirty = None                      # pixel rect (x, y, w, h) the unshown chunks can touch
        self._final = False                     # the last image shaded with the real background
        self._serial = self.r.frames_recorded

    @property
    def done(self) -> bool:
        return self.phase == "done"

    @property
    def fraction(self) -> float:
        """Share of the work done (visibility and attribute chunks alike)."""
        if self.done:
            return 1.0
        return (self.next + (self.n if self.phase == "attr" else 0)) / (2.0 * self.n)

    def _span(self, prepared: bool, first: int | None = None) -> tuple[int, int]:
        """(first splat, count) of the next chunk (from ``first``, default
        :attr:`next`): on the pre-pass path a whole number of workgroups inside
        one pre-pass window."""
        first = self.next if first is None else first
        if not prepared:
            return first, min(self.chunk, self.n - first)
        end = next(w0 + wn for w0, wn, _ in self.r.prep_objects().windows if w0 <= first < w0 + wn)
        size = -(-self.chunk // WORKGROUP) * WORKGROUP
        return first, min(size, end - first)

    def step(self, readback: bool = True) -> np.ndarray | None:
        """Draw the next chunk.  Returns the (height, width, 4) uint8 image
        so far after an attribute chunk (alpha 0 where nothing is drawn yet),
        None after a visibility chunk or when already done.  With
        ``readback=False`` the chunk is only drawn (no shading pass, no
        readback; None): :meth:`show` composes what has been drawn."""
        r = self.r
        r.check_open()
        if self.done:
            return None
        if r.frames_recorded != self._serial or r.n != self.n:
            self.n = r.n
            self._restart()
        t = r.targets_for(self.width, self.height)
        prepared = r.use_prepass()
        #: the path of the last step: True for the compute pre-pass
        self.prepared = prepared
        first, count = self._span(prepared)
        objs, sets, window = [], None, 0
        if prepared:
            window, sets, objs = r.prep_range(first, count)

        ctx = FrameContext(r, t, t.offscreen, prepared)

        def draw(cb, kind: str) -> None:
            RasterSplats(kind, chunk=(first, count, window, sets)).record(cb, ctx)

        try:
            if self.phase == "depth":
                r.write_ubo(self.camera, self.width, self.height)

                def rec(cb):
                    draw(cb, "depth")
                r.dev.submit(rec)
                out = None
            else:
                self.write_ubo(0.0)

                def rec(cb):
                    draw(cb, "attr")
                    if readback:
                        _resolve(r).record(cb, ctx)
                        cb.copy_image_to_buffer(t.out, self._rb)
                        cb.host_read_barrier()
                r.dev.submit(rec)
                out = self._rb.read().reshape(self.height, self.width, 4) if readback else None
                self._unshown = not readback
                self._dirty = None if readback else _union(self._dirty, self._chunk_rect(first, count))
        finally:
            for o in reversed(objs):
                o.destroy()
        self.next += count
        if self.next >= self.n:
            self.next = 0
            self.phase = "attr" if self.phase == "depth" else "done"
        return out

    # ------------------------------------------------------------ pick map
    @property
    def pick_done(self) -> bool:
        """The pick map of the view is complete (:meth:`pick_step`)."""
        return self._pick_next >= self.n

    def pick_step(self) -> None:
        """Once :attr:`done`: draw the next chunk (``chunk`` splats) of the view's
        pick map (splat index and depth of the nearest splat per pixel, as
        :meth:`Renderer.pick` draws it whole); :meth:`pick_result` once
        :attr:`pick_done`."""
        r = self.r
        r.check_open()
        if not self.done or self.pick_done:
            raise ParameterError("pick", "the frame is not done, or its pick map is")
        t = r.targets_for(self.width, self.height)
        t.ensure_pick()
        prepared = r.use_prepass()
        first, count = self._span(prepared, self._pick_next)
        objs, sets, window = [], None, 0
        if prepared:
            window, sets, objs = r.prep_range(first, count)
        try:
            r.write_ubo(self.camera, self.width, self.height)

            def rec(cb):
                RasterSplats("pick", chunk=(first, count, window, sets)).record(cb, FrameContext(r, t, None, prepared))
            r.dev.submit(rec)
        finally:
            for o in reversed(objs):
                o.destroy()
        self._pick_next = first + count

    def pick_result(self):
        """(index (h, w) int64, -1 background; view-axis depth (h, w) float64,
        NaN background) of the complete pick map, as :meth:`Renderer.pick`."""
        if not (self.done and self.pick_done):
            raise ParameterError("pick", "the pick map is not complete")
        self.r.write_ubo(self.camera, self.width, self.height)      # its near/far decode the depth
        return self.r.targets_for(self.width, self.height).read_pick(None, lambda cb: None)

    def write_ubo(self, background_alpha: float) -> None:
        """The frame uniforms with this alpha for background pixels (0: the
        intermediate images, uncovered pixels told apart; the renderer's own
        for the last)."""
        r = self.r
        alpha = r.background_alpha
        r.background_alpha = background_alpha
        try:
            r.write_ubo(self.camera, self.width, self.height)
        finally:
            r.background_alpha = alpha

    # ------------------------------------------------------ on the device
    def set_under(self, under) -> None:
        """What shows where no full-quality splat has arrived yet: an (h, w, 4)
        uint8 frame (uploaded once), or ``(image, (sw, sh))``: the top-left
        ``sw`` x ``sh`` part of an rgba8 device image of this renderer's device
        in TRANSFER_SRC layout (e.g. a level-of-detail frame, a half-resolution
        one included), scaled onto the frame (nearest) by one blit.  It is
        copied at the next :meth:`show`, so ``image`` must stay unchanged until then."""
        self._under = under
        if self._shown is None:
            self._shown = V.Image(self.r.dev, self.width, self.height, "rgba8",
                                  ("color", "transfer_src", "transfer_dst"))
            self._fb_over = V.Framebuffer(self.r.dev, self.r.cache.render_pass(_RP_OVER), [self._shown],
                                          self.width, self.height)

    def show(self, readback: bool = False):
        """The image to show now, composed on the device: the full-quality
        frame once :attr:`done` (the renderer's output image, as
        :meth:`Renderer.render_resident` leaves it: its last image equals the
        one-submit frame), else the attribute chunks drawn so far shaded over
        the :meth:`set_under` image (one shading pass over the pixels they
        cover, only when chunks were drawn since the last call; before the
        first attribute chunk the under image alone).  Returns the device image
        (rgba8, TRANSFER_SRC layout, ``width`` x ``height``; valid until the
        next step or show) or, with ``readback``, its (h, w, 4) uint8 pixels."""
        r = self.r
        r.check_open()
        if self.done:
            t = r.targets_for(self.width, self.height)
            if not self._final:
                self.write_ubo(r.background_alpha)

                def rec(cb):
                    _resolve(r).record(cb, FrameContext(r, t, t.offscreen))
                r.dev.submit(rec)
                self._unshown, self._final = False, True
            return self._read(t.out) if readback else t.out
        if self._shown is None:
            raise ParameterError("under", "set_under() before show()")
        under, self._under = self._under, None
        shade = self._unshown
        staging = None
        if isinstance(under, np.ndarray):
            if under.shape != (self.height, self.width, 4) or under.dtype != np.uint8:
                raise ParameterError("under", f"must be a ({self.height}, {self.width}, 4) uint8 frame, "
                                              f"got {under.shape} {under.dtype}")
            staging = V.Buffer(r.dev, under.nbytes, ("transfer_src",), host_visible=True)
            staging.write(np.ascontiguousarray(under))
        t = r.targets_for(self.width, self.height)
        rect = self._dirty
        if shade and rect is None:        # the chunks since the last image are all off screen
            shade = self._unshown = False
        if shade:
            self.write_ubo(0.0)
            #: the pixel rect (x, y, w, h) the last shading pass covered
            self.shaded_rect = rect
        img = self._shown
        if under is None and not shade:
            return self._read(img) if readback else img
        try:
            def rec(cb):
                if under is not None:
                    cb.memory_barrier("color_output", "color_write", "transfer", "transfer_read")
                    cb.image_barrier(img, "transfer_dst", "transfer", "none", "transfer", "transfer_write")
                    if staging is not None:
                        cb.copy_buffer_to_image(staging, img)
                    else:
                        src, (sw, sh) = under
                        cb.blit_image(src, img, (0, 0, sw, sh), (0, 0, self.width, self.height))
                    cb.image_barrier(img, "transfer_src", "transfer", "transfer_write",
                                     "color_output", "color_read|color_write")
                if shade:
                    pipe = r.cache.pipeline(_OVER_EDL_DESC if r.edl else _OVER_DESC)
                    cb.begin_render_pass(r.cache.render_pass(_RP_OVER), self._fb_over, [None])
                    cb.set_scissor(*rect)
                    cb.bind_pipeline(pipe)
                    cb.bind_descriptor_set(pipe, t.resolve_set)
                    cb.draw(3)
                    cb.end_render_pass()
            r.dev.submit(rec)
        finally:
            if staging is not None:
                staging.destroy()
        if shade:
            self._unshown, self._dirty = False, None
        return self._read(img) if readback else img

    def _chunk_rect(self, first: int, count: int) -> tuple[int, int, int, int] | None:
        """A pixel rect (x, y, w, h) holding every pixel splats ``first`` ..
        ``first + count - 1`` can cover (from boxes of blocks of splats, grown by
        the largest splat axis times the splat scale and by the deformation's
        reach; ``PROGRESSIVE_SHADE_PAD_PX`` for the low-pass disc and point
        splats); the whole image when a box reaches the camera plane; None
        when the chunk is off screen."""
        r = self.r
        cached = _BOXES.get(r)     # per renderer and cloud: shared by its refinements
        if cached is None or cached[0] is not r.cloud:
            c = r.cloud
            starts = np.arange(0, c.n, _BOX_BLOCK)
            reach = np.sqrt(np.maximum(np.einsum("ij,ij->i", c.u, c.u), np.einsum("ij,ij->i", c.v, c.v)))
            rad = np.maximum.reduceat(reach, starts)
            cached = _BOXES[r] = (c, np.minimum.reduceat(c.positions, starts, axis=0) - rad[:, None],
                                             np.maximum.reduceat(c.positions, starts, axis=0) + rad[:, None], rad)
        _, lo, hi, rad = cached
        b0, b1 = first // _BOX_BLOCK, -(-(first + count) // _BOX_BLOCK)
        grow = rad[b0:b1, None] * max(r.splat_scale - 1.0, 0.0) + r.displacement_reach()
        lo, hi = lo[b0:b1] - grow, hi[b0:b1] + grow
        corners = np.stack([np.where(np.array([i & 1, i & 2, i & 4], bool), hi, lo) for i in range(8)], axis=1)
        view = self.camera.view_matrix()
        e = corners.reshape(-1, 3) @ view[:3, :3].T + view[:3, 3]
        depth = -e[:, 2]
        near = self.r.near_far[0]
        if (depth <= 0.5 * near).any():
            return 0, 0, self.width, self.height
        f = 1.0 / np.tan(np.radians(self.camera.fov_deg) / 2.0)
        w, h = self.width, self.height
        x = 0.5 * w * (1.0 + f * (h / w) * e[:, 0] / depth)
        y = 0.5 * h * (1.0 - f * e[:, 1] / depth)
        pad = PROGRESSIVE_SHADE_PAD_PX
        x0, x1 = max(int(np.floor(x.min() - pad)), 0), min(int(np.ceil(x.max() + pad)), w)
        y0, y1 = max(int(np.floor(y.min() - pad)), 0), min(int(np.ceil(y.max() + pad)), h)
        if x1 <= x0 or y1 <= y0:
            return None
        return x0, y0, x1 - x0, y1 - y0

    def _read(self, image) -> np.ndarray:
        def rec(cb):
            cb.copy_image_to_buffer(image, self._rb)
            cb.host_read_barrier()
        self.r.dev.submit(rec)
        return self._rb.read().reshape(self.height, self.width, 4).copy()

    def close(self) -> None:
        if self._fb_over is not None or self._shown is not None:
            self.r.dev.wait_idle()          # a presented frame may still read the shown image
        for name in ("_fb_over", "_shown", "_rb"):
            obj = getattr(self, name)
            if obj is not None:
                obj.destroy()
                setattr(self, name, None)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
