"""Progressive full-quality refinement in the editor's window (the default).

When motion stops on a model drawn at a level of detail, the full-quality
frame is drawn a few chunks of splats per presented frame by a
:class:`~splatedit.render.splat.progressive.ProgressiveFrame` on the full renderer
(the editor's one Vulkan device), and the window shows the chunks drawn so
far composited over the level-of-detail frame *on the device* (one shading
pass over the pixels they cover per presented frame, no readback on the GUI
path): the image sharpens region by region instead of freezing, and input
is handled between presented frames (any change drops the refinement,
:class:`~splatedit.app.view.frames.FrameScheduler`).

Per presented frame :meth:`ProgressiveRefinement.advance` draws chunks until
the work budget is used (the frame interval ``frame_ms`` minus the measured
cost of presenting and composing, at least ``EDITOR_PROGRESSIVE_MIN_WORK_SHARE``
of it), then composes the image once.  The chunk size follows the budget: it
starts at ``work / EDITOR_PROGRESSIVE_STEPS_PER_FRAME / ms_per_splat`` and is
rescaled after every step by the ratio of the step budget to the step's
measured time (and by ``1 / EDITOR_PROGRESSIVE_ATTR_COST`` when the colour
half starts); a step that leaves room for another is followed by one.
"""

from __future__ import annotations

import time

import numpy as np

from splatedit.render.splat.progressive import ProgressiveFrame
from splatedit.tolerances import (EDITOR_PROGRESSIVE_ATTR_COST, EDITOR_PROGRESSIVE_CHUNK_MAX_GROWTH,
                                  EDITOR_PROGRESSIVE_MIN_CHUNK,
                                  EDITOR_PROGRESSIVE_MIN_WORK_SHARE, EDITOR_PROGRESSIVE_STEPS_PER_FRAME)


class ProgressiveRefinement:
    """One view refined progressively.

    Args:
        frame: the :class:`ProgressiveFrame` (owned: closed by :meth:`close`).
        key: the :class:`~splatedit.app.view.frames.SceneKey` it draws.
        under: the level-of-detail frame shown where no chunk has arrived:
            (h, w, 4) uint8 pixels, or ``(device image, (w, h))``
            (:meth:`ProgressiveFrame.set_under`).
        frame_ms: target milliseconds between presented frames.
        resident: True (the GUI path): :meth:`advance` returns the device
            image; False: its pixels (one readback per presented frame).
    """

    def __init__(self, frame: ProgressiveFrame, key, under, frame_ms: float, resident: bool):
        self.frame = frame
        self.key = key
        frame.set_under(under)
        self.frame_target_ms = float(frame_ms)
        self.resident = bool(resident)
        self.t0 = time.perf_counter()
        #: seconds from the start to the first shown chunk, and to full quality
        self.first_chunk_s: float | None = None
        self.done_s: float | None = None
        #: milliseconds of every step (one GPU submit each); per presented
        #: frame: the steps, the composition (shading pass over the LOD frame,
        #: readback on the CPU path) and the whole frame (steps + composition +
        #: present + GUI, from the scheduler)
        self.step_ms: list[float] = []
        self.work_ms: list[float] = []
        self.show_ms: list[float] = []
        self.frame_ms: list[float] = []
        #: splats drawn in the attribute phase when each image was shown
        self.shown_splats: list[int] = []
        self._present_ms = 0.0            # estimate of a frame's cost besides advance()
        self._show_est = 0.0
        self.image = None

    @property
    def done(self) -> bool:
        return self.frame.done

    @property
    def total_ms(self) -> float:
        return float(sum(self.step_ms) + sum(self.show_ms))

    def budget_ms(self) -> float:
        """Milliseconds of steps for the next presented frame."""
        t = self.frame_target_ms
        return max(t - self._present_ms - self._show_est, EDITOR_PROGRESSIVE_MIN_WORK_SHARE * t)

    def frame_done(self, frame_ms: float) -> None:
        """The whole presented frame took ``frame_ms``: learn the presenting cost."""
        self.frame_ms.append(frame_ms)
        if self.work_ms:
            rest = max(frame_ms - self.work_ms[-1] - self.show_ms[-1], 0.0)
            self._present_ms = rest if len(self.frame_ms) == 1 else 0.7 * self._present_ms + 0.3 * rest

    def advance(self):
        """Draw chunks up to the budget, then compose the image to show: a
        device image (``resident``) or (h, w, 4) uint8 pixels."""
        f = self.frame
        budget = self.budget_ms()
        target = budget / EDITOR_PROGRESSIVE_STEPS_PER_FRAME
        t0 = time.perf_counter()
        while not f.done:
            phase = f.phase
            ts = time.perf_counter()
            f.step(readback=False)
            ms = (time.perf_counter() - ts) * 1e3
            self.step_ms.append(ms)
            if not f.done and ms > 0:
                scale = min(target / ms, EDITOR_PROGRESSIVE_CHUNK_MAX_GROWTH)
                if f.phase != phase:        # visibility done: colour steps cost more per splat
                    scale /= EDITOR_PROGRESSIVE_ATTR_COST
                f.chunk = max(EDITOR_PROGRESSIVE_MIN_CHUNK, int(f.chunk * scale))
            if (time.perf_counter() - t0) * 1e3 + min(ms, target) > budget:
                break
        t1 = time.perf_counter()
        self.work_ms.append((t1 - t0) * 1e3)
        img = f.show(readback=not self.resident)
        show = (time.perf_counter() - t1) * 1e3
        self.show_ms.append(show)
        self._show_est = show if len(self.show_ms) == 1 else 0.7 * self._show_est + 0.3 * show
        if f.done or (f.phase == "attr" and f.next > 0):
            self.shown_splats.append(f.n if f.done else f.next)
            if self.first_chunk_s is None:
                self.first_chunk_s = time.perf_counter() - self.t0
        if f.done:
            self.done_s = time.perf_counter() - self.t0
        self.image = img
        return img

    def timings(self) -> dict:
        """Figures of the refinement (the status file's ``last_refinement``)."""
        def r(v):
            return None if v is None else round(float(v), 3)
        med = (lambda a: r(np.median(a)) if a else None)
        return {"first_chunk_s": r(self.first_chunk_s), "done_s": r(self.done_s), "steps": len(self.step_ms),
                "step_ms_max": r(max(self.step_ms)) if self.step_ms else None, "shown": len(self.shown_splats),
                "frames": len(self.frame_ms), "frame_ms_median": med(self.frame_ms),
                "frame_ms_max": r(max(self.frame_ms)) if self.frame_ms else None,
                "work_ms_median": med(self.work_ms), "show_ms_median": med(self.show_ms),
                "present_ms_median": med([f - w - s for f, w, s in zip(self.frame_ms, self.work_ms, self.show_ms)])}

    def close(self) -> None:
        self.frame.close()
