"""Progressive full-quality frames: a huge model drawn a chunk of splats at a time.

A full-quality frame of 10M splats takes tens of seconds on lavapipe.  A
:class:`ProgressiveFrame` spreads it over many short steps (one GPU submit
each) so a window stays responsive and the image sharpens while it is drawn:

1. visibility: ``ceil(n / chunk)`` steps draw the splats' depth into the
   renderer's depth target (the first step clears it, the others load it);
2. attributes: the same chunks are accumulated into the colour/normal
   targets against the complete depth buffer, and after every chunk the
   shading pass resolves what has been accumulated so far into an image.

Each chunk goes through the compute pre-pass when the renderer uses it
(:meth:`Renderer._use_prepass`): a step runs the pre-pass of the chunk's
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

Editor use (:mod:`splatedit.app.progressive_refine`): when motion stops, create
``ProgressiveFrame(full_renderer, camera, w, h, chunk)`` with ``chunk`` sized
to the frame budget (``budget_ms / ms_per_splat``), call :meth:`step` once
per idle frame and show ``composite(image, lod_frame)`` until :attr:`done`;
drop it on any camera or scene change.
"""

from __future__ import annotations

import numpy as np

from splatedit.errors import ParameterError
from splatedit.render import vk as V
from splatedit.render.camera import Camera
from splatedit.render.renderer import _RP_DEPTH, Renderer, _rp_attr
from splatedit.render.splat_layout import _WORKGROUP

_RP_DEPTH_LOAD = V.RenderPassDesc(depth=V.Attachment("d32f", "load", initial="depth", final="depth"))


def _rp_attr_load(fmt: str) -> V.RenderPassDesc:
    col = V.Attachment(fmt, "load", initial="shader_read", final="shader_read")
    return V.RenderPassDesc(colors=(col, col),
                            depth=V.Attachment("d32f", "load", initial="depth", final="depth"))


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
        renderer._check_open()
        renderer._require_cloud()
        if int(chunk) < 1:
            raise ParameterError("chunk", f"must be at least 1, got {chunk!r}")
        self.r = renderer
        self.camera = camera
        self.width, self.height = width, height
        self.chunk = int(chunk)
        self.n = renderer.n
        self._rb = V.Buffer(renderer.dev, width * height * 4, ("transfer_dst",), host_visible=True)
        self._restart()

    def _restart(self) -> None:
        self.phase = "depth"
        self.next = 0
        self.restarts = getattr(self, "restarts", -1) + 1
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

    def _span(self, prepared: bool) -> tuple[int, int]:
        """(first splat, count) of the next chunk: on the pre-pass path a whole
        number of workgroups inside one pre-pass window."""
        first = self.next
        if not prepared:
            return first, min(self.chunk, self.n - first)
        end = next(w0 + wn for w0, wn, _ in self.r._prep_objects().windows if w0 <= first < w0 + wn)
        size = -(-self.chunk // _WORKGROUP) * _WORKGROUP
        return first, min(size, end - first)

    def step(self) -> np.ndarray | None:
        """Draw the next chunk.  Returns the (height, width, 4) uint8 image
        so far after an attribute chunk (alpha 0 where nothing is drawn yet),
        None after a visibility chunk or when already done."""
        r = self.r
        r._check_open()
        if self.done:
            return None
        if r.frames_recorded != self._serial or r.n != self.n:
            self.n = r.n
            self._restart()
        t = r._targets_for(self.width, self.height)
        prepared = r._use_prepass()
        #: the path of the last step: True for the compute pre-pass
        self.prepared = prepared
        first, count = self._span(prepared)
        objs, sets, window = [], None, 0
        if prepared:
            window, sets, objs = r._prep_range(first, count)

        def draw(cb, kind: str, desc: V.RenderPassDesc, fb, clears) -> None:
            if prepared:
                r._record_prepass(cb, window, sets)
            cb.begin_render_pass(r.cache.render_pass(desc), fb, clears)
            if prepared:
                r._record_splats(cb, kind, True, window)
            else:
                r._record_vertex_splats(cb, kind, first, count)
            cb.end_render_pass()

        try:
            if self.phase == "depth":
                r._write_ubo(self.camera, self.width, self.height)

                def rec(cb):
                    draw(cb, "depth", _RP_DEPTH if first == 0 else _RP_DEPTH_LOAD, t.fb_depth,
                         [1.0] if first == 0 else [None])
                r.dev.submit(rec)
                out = None
            else:
                alpha = r.background_alpha
                r.background_alpha = 0.0
                try:
                    r._write_ubo(self.camera, self.width, self.height)
                finally:
                    r.background_alpha = alpha
                fmt = r.accum_format

                def rec(cb):
                    clear = [(0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0), None] if first == 0 else [None] * 3
                    draw(cb, "attr", _rp_attr(fmt, "shader_read") if first == 0 else _rp_attr_load(fmt),
                         t.fb_attr, clear)
                    r._record_resolve(cb, t, t.offscreen)
                    cb.copy_image_to_buffer(t.out, self._rb)
                    cb.host_read_barrier()
                r.dev.submit(rec)
                out = self._rb.read().reshape(self.height, self.width, 4)
        finally:
            for o in reversed(objs):
                o.destroy()
        self.next += count
        if self.next >= self.n:
            self.next = 0
            self.phase = "attr" if self.phase == "depth" else "done"
        return out

    def close(self) -> None:
        if self._rb is not None:
            self._rb.destroy()
            self._rb = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
