"""Mirror (X-symmetry) selection: Ctrl+M adds the mirror image of the brush
target (support or active handle) across the model's symmetry plane (the
middle of its bounding box along X; Select > Mirror axis chooses Y or Z);
Shift+M toggles symmetric painting: every brush dab also paints (or
erases) its mirror image.  See :mod:`splatedit.select.mirror`.

A tool on the narrow protocol (:attr:`Tool.ctx` only); the brush asks
:meth:`MirrorTool.with_mirror` for each dab while painting is symmetric.
"""

from __future__ import annotations

import numpy as np

from splatedit.app.ui.keymap import Action, Section
from splatedit.app.tools.base import Tool
from splatedit.select.mirror import AXES, mirror_indices


#: the editor job's key while a mirror runs (the status file's ``jobs``)
JOB = "mirror"


class MirrorTool(Tool):
    section = Section.SELECTION
    #: the editor attribute it is reachable as (``editor.mirror``)
    name = "mirror"

    def __init__(self, ed):
        super().__init__(ed)
        self.painting = False        # symmetric brush strokes
        self.axis = 0                # the plane's normal: 0 X, 1 Y, 2 Z

    def actions(self):
        return {Action.MIRROR_SELECTION: self.mirror_selection, Action.MIRROR_PAINT: self.toggle_painting,
                Action.MIRROR_AXIS: self.next_axis}

    def status(self):
        return f"symmetric painting across {AXES[self.axis]} (Shift+M)" if self.painting else None

    def toggle_painting(self) -> None:
        self.painting = not self.painting
        self.ctx.say(f"symmetric painting {'on' if self.painting else 'off'} (across {AXES[self.axis]})")

    def next_axis(self) -> None:
        self.axis = (self.axis + 1) % 3
        self.ctx.say(f"mirror across {AXES[self.axis]} (the middle of the model's bounding box)")

    def with_mirror(self, idx: np.ndarray) -> np.ndarray:
        """``idx`` and the mirror images of its splats (just ``idx`` while
        the neighbour graph is being built)."""
        g = self.ctx.neighbour_graph()
        if g is None or g.tree is None or not len(idx):
            return idx
        pos = self.ctx.document.cloud.positions
        return np.union1d(idx, mirror_indices(pos, idx, g.tree, g.spacing, self.axis))

    def mirror_selection(self) -> bool:
        """Add the mirror image of the brush target to it (one undo step).

        A background job (:meth:`ToolContext.start_job`; the mirror of half
        a 1M-splat model and its closure took ~10 s on the main thread, the
        window stood still): the matching and the closure run on a copy of
        the selection, which is installed when the job lands, unless the
        selection changed meanwhile (then nothing happens and the status
        line says so).  True when the job started."""
        c = self.ctx
        if c.busy():
            return False
        if c.job_running(JOB):
            c.say("mirror: already running")
            return False
        g = c.neighbour_graph()
        if g is None or g.tree is None:
            c.say("the neighbour graph is still being built: try again in a moment")
            return False
        mask = c.target_mask()
        if not mask.any():
            c.say(f"mirror: the {c.target} is empty")
            return False
        job = c.background_select()
        if job is None:
            c.say("the neighbour graph is still being built: try again in a moment")
            return False
        target, axis, before = c.target, self.axis, int(mask.sum())
        pos, idx = c.document.cloud.positions, np.flatnonzero(mask)
        label = f"mirror {target}"

        def work(progress):
            progress("mirror: matching the splats", 0.0)
            mirror = mirror_indices(pos, idx, g.tree, g.spacing, axis)
            new = job.target_mask().copy()
            new[mirror] = True
            progress("mirror: closing the selection", 0.5)
            return job.compute(new)

        def land(done) -> None:
            if c.document is not job.session:
                return                      # another model was opened meanwhile: nothing to say
            if done.error is not None:
                c.say(f"mirror failed: {done.error}")
            elif not done.result:
                c.say(f"mirror: the {target} is already symmetric across {AXES[axis]}")
            elif not c.install(job, label):
                c.say("mirror: the selection changed while it ran; nothing mirrored (Ctrl+M again)")
            else:
                c.say(f"mirror {target} across {AXES[axis]}: {int(c.target_mask().sum()) - before:+,} {c.items}")
            c.redraw()

        c.start_job(JOB, "mirroring the selection", work, land)
        c.say(f"mirroring the {target} across {AXES[axis]} ...")
        return True


TOOL = MirrorTool
