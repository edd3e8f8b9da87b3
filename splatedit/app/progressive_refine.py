"""Progressive full-quality refinement in the editor's window.

When motion stops on a model drawn at a level of detail, the full-quality
frame is drawn a chunk of splats per idle frame by a
:class:`~splatedit.render.progressive.ProgressiveFrame` on the full renderer
(the editor's one Vulkan device), and the window shows the chunks drawn so
far composited over the level-of-detail frame: the image sharpens region by
region instead of freezing, and input is handled between the steps (any
change drops the refinement, :class:`~splatedit.app.frames.FrameScheduler`).

The chunk size follows the frame budget: it starts at
``budget_ms / ms_per_splat`` and is rescaled after every step by the ratio of
the budget to the step's measured time.
"""

from __future__ import annotations

import time

import numpy as np

from splatedit.render.progressive import ProgressiveFrame, composite
from splatedit.tolerances import EDITOR_PROGRESSIVE_CHUNK_MAX_GROWTH, EDITOR_PROGRESSIVE_MIN_CHUNK


class ProgressiveRefinement:
    """One view refined progressively.

    Args:
        frame: the :class:`ProgressiveFrame` (owned: closed by :meth:`close`).
        key: the :class:`~splatedit.app.frames.SceneKey` it draws.
        under: (h, w, 4) uint8 level-of-detail frame the chunks are composited over.
        budget_ms: target milliseconds per step.
    """

    def __init__(self, frame: ProgressiveFrame, key, under: np.ndarray, budget_ms: float):
        self.frame = frame
        self.key = key
        self.under = under
        self.budget_ms = float(budget_ms)
        self.t0 = time.perf_counter()
        #: seconds from the start to the first shown chunk, and to full quality
        self.first_chunk_s: float | None = None
        self.done_s: float | None = None
        #: milliseconds of every step (one GPU submit each), and of every whole
        #: presented frame while refining (step + composite + present + GUI)
        self.step_ms: list[float] = []
        self.frame_ms: list[float] = []
        #: splats drawn in the attribute phase when each image was shown
        self.shown_splats: list[int] = []
        #: pixels covered by full-quality splats in each shown image
        self.covered_pixels: list[int] = []
        self.image: np.ndarray | None = None

    @property
    def done(self) -> bool:
        return self.frame.done

    @property
    def total_ms(self) -> float:
        return float(sum(self.step_ms))

    def step(self) -> np.ndarray | None:
        """Draw the next chunk; the (h, w, 4) uint8 image to show (the chunks so
        far over the level-of-detail frame) or None after a visibility chunk."""
        f = self.frame
        t = time.perf_counter()
        img = f.step()
        ms = (time.perf_counter() - t) * 1e3
        self.step_ms.append(ms)
        if not f.done and ms > 0:
            scale = min(self.budget_ms / ms, EDITOR_PROGRESSIVE_CHUNK_MAX_GROWTH)
            f.chunk = max(EDITOR_PROGRESSIVE_MIN_CHUNK, int(f.chunk * scale))
        if img is None:
            return None
        self.shown_splats.append(f.n if f.done else f.next)
        self.covered_pixels.append(int(np.count_nonzero(img[..., 3])))
        if self.first_chunk_s is None:
            self.first_chunk_s = time.perf_counter() - self.t0
        if f.done:
            self.done_s = time.perf_counter() - self.t0
        if f.done:      # the full frame: background where no splat is (alpha 0 only marks it)
            img = img.copy()
            img[..., 3] = 255
            self.image = img
        else:
            self.image = composite(img, self.under)
        return self.image

    def close(self) -> None:
        self.frame.close()
