"""The full frame of a :class:`~splatedit.render.gaussian.renderer.GaussianRenderer`
drawn in chunks over several presented frames (the editor's refinement after
motion stops, :class:`splatedit.app.view.progressive_refine.ProgressiveRefinement`).

Steps: the first runs the pre-pass and the depth sort of every Gaussian
(:meth:`GaussianRenderer.prepare_frame`); each next one draws the next
``chunk`` Gaussians of the sorted order into the accumulation target (the
first clears it, the others load it).  The blending is front to back, so
drawing the sorted order in consecutive chunks sums the same terms in the
same order as one draw: the finished image is the one-shot frame's.  Until it
is finished :meth:`show` returns the frame shown under it (the level of
detail); then the resolved full frame.  Input is handled between the steps
(the scheduler drops the frame on any change), so a 1M-Gaussian frame no
longer freezes the window for its seconds.

The renderer's pre-pass records belong to the last :meth:`prepare_frame` or
pick of that renderer; a step that finds another one ran since (its
``epoch`` changed) sorts again.  Only :mod:`splatedit.render.vk` calls Vulkan.
"""

from __future__ import annotations

import numpy as np

from splatedit.errors import ParameterError
from splatedit.render.camera import Camera
from splatedit.render.frame import Frame, FrameContext, Resolve
from splatedit.render.gaussian.passes import GsQuads


def draw_chunk(r, first: int, count: int, clear: bool) -> None:
    """Draw Gaussians ``first`` .. ``first + count`` of the sorted order of
    the last :meth:`GaussianRenderer.prepare_frame` of ``r`` into its
    accumulation target (cleared first with ``clear``, else blended over what
    it holds; the pass :class:`~splatedit.render.gaussian.passes.GsQuads` with a
    chunk); submits and waits.  Consecutive chunks from 0 give
    :meth:`GaussianRenderer.record_draw`'s sums (front-to-back blending in the
    same order)."""
    frame = Frame([GsQuads(chunk=(int(first), int(count)), clear=clear)], inputs=("cloud", "records", "order"))
    ctx = FrameContext(r, r.targets)
    r.dev.submit(lambda cb: frame.record(cb, ctx))


class GaussianProgressiveFrame:
    """One view of ``renderer`` (its scene, basis and displacement as set)
    drawn ``chunk`` Gaussians per :meth:`step` (the chunk may be changed
    between steps).  The interface of
    :class:`~splatedit.render.splat.progressive.ProgressiveFrame` that the
    refinement uses: ``phase`` ("sort", "attr", "done"), ``next``, ``n``,
    ``chunk``, ``done``, ``fraction``, :meth:`set_under`, :meth:`step`,
    :meth:`show`, :meth:`close`.  No pick map in chunks (``chunked_pick``
    False): the brush picks the view when it needs it
    (:meth:`GaussianRenderer.pick`, one pass)."""

    chunked_pick = False

    def __init__(self, renderer, camera: Camera, width: int, height: int, chunk: int):
        if chunk < 1:
            raise ParameterError("chunk", f"must be >= 1, got {chunk}")
        renderer.require_scene()
        self.r = renderer
        self.camera = camera
        self.width, self.height = int(width), int(height)
        self.chunk = int(chunk)
        self.n = int(renderer.count)
        self.phase = "sort"
        self.next = 0
        self._visible = 0
        self._epoch = None
        self._under = None
        self._image = None

    @property
    def done(self) -> bool:
        return self.phase == "done"

    @property
    def fraction(self) -> float:
        """Share of the work done (the sort counts as one chunk)."""
        if self.done:
            return 1.0
        if self.phase == "sort":
            return 0.0
        return min(self.next / max(self._visible, 1), 1.0)

    def set_under(self, under) -> None:
        """The frame shown until the full one is complete: (h, w, 4) uint8
        pixels (a device image is not kept: nothing is shown under then)."""
        self._under = under if isinstance(under, np.ndarray) else None

    def step(self, readback: bool = False) -> None:
        """Sort, or draw the next chunk (the last one also resolves and reads back)."""
        r = self.r
        if self.done:
            return
        if self.phase == "attr" and r.epoch != self._epoch:
            self.phase, self.next = "sort", 0            # another frame or pick used the records
        if self.phase == "sort":
            r.prepare_frame(self.camera, self.width, self.height)
            self._epoch = r.epoch
            self._visible = r.visible
            self.phase = "attr"
            if self._visible == 0:
                self._finish()
            return
        first, count = self.next, min(self.chunk, self._visible - self.next)
        draw_chunk(r, first, count, clear=first == 0)
        self.next += count
        if self.next >= self._visible:
            self._finish()

    def _finish(self) -> None:
        r = self.r
        t = r.targets_for(self.width, self.height)
        if self._visible == 0:
            draw_chunk(r, 0, 0, clear=True)
        frame = Frame([Resolve()], inputs=("accum",))
        self._image = t.read_output(lambda cb: frame.record(cb, FrameContext(r, t, t.offscreen)))
        self.next = self.n
        self.phase = "done"

    def show(self, readback: bool = True):
        """(h, w, 4) uint8: the full frame once done, else the frame under it
        (white where none was given)."""
        if self._image is not None:
            return self._image
        if self._under is not None:
            return self._under
        return np.full((self.height, self.width, 4), 255, np.uint8)

    def close(self) -> None:
        """Nothing of its own to free (the renderer's targets are reused)."""
        self._under = self._image = None
