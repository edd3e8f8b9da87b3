"""One frame description for every renderer: passes as objects (issue 18, item 1).

A frame is an ordered list of :class:`Pass` objects.  Each pass names what it
reads and writes (:data:`RESOURCES`) and records itself into a command
buffer against a :class:`FrameContext` (the renderer, its per-size targets,
the output target).  :class:`Frame` checks the order once (every input is
written by an earlier pass or is an input of the frame) and records the
list with a GPU timestamp after every pass; :meth:`Frame.read_timings` sums
them per timing bucket.

The splat renderer's passes live in :mod:`splatedit.render.splat.passes`,
the Gaussian renderer's in :mod:`splatedit.render.gaussian.passes`; the shading
pass :class:`Resolve` is shared (each renderer names its resolve shader and
descriptor-set layout: ``resolve_shader``, ``resolve_set_layout``).
Progressive refinement (:mod:`splatedit.render.splat.progressive`,
:mod:`splatedit.render.gaussian.progressive`) records chunks of the same pass
objects.  docs/dev/architecture.md says how to add a pass.

Only :mod:`splatedit.render.vk` calls Vulkan.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

#: what passes read and write.  Splat frames: the cloud (uploads), the
#: pre-pass records, the depth image, the accumulator images, the compute
#: rasterizer's visibility and accumulation buffers, the pick images, the
#: output target.  Gaussian frames also: ``order`` (the visible Gaussians'
#: indices, sorted front to back, and their count).
RESOURCES = ("cloud", "records", "order", "depth", "accum", "vis_buffer", "accum_buffers", "pick", "output")


@dataclass
class FrameContext:
    """What a pass records against: the renderer ``r`` (a
    :class:`~splatedit.render.splat.renderer.Renderer` or a
    :class:`~splatedit.render.gaussian.renderer.GaussianRenderer`), its per-size
    targets ``t``, the output ``target`` (a
    :class:`~splatedit.render.targets.RenderTarget` or None), whether the
    splats go through the pre-pass (``prepared``) and the pre-pass windows of
    the frame (splat frames)."""

    r: Any
    t: Any
    target: Any = None
    prepared: bool = True
    windows: int = 1
    extra: dict = field(default_factory=dict)


class Pass:
    """One pass of a frame: ``reads`` / ``writes`` name :data:`RESOURCES`;
    ``timing`` is the bucket of the renderer's ``last_timings_ms`` its GPU
    time adds to.  Subclasses implement :meth:`record`."""

    name = "pass"
    timing = ""
    reads: tuple[str, ...] = ()
    writes: tuple[str, ...] = ()

    def record(self, cb, ctx: FrameContext) -> None:
        raise NotImplementedError

    def __repr__(self):
        return f"{type(self).__name__}({self.name})"


class Resolve(Pass):
    """The shading pass of both renderers: a full-screen pass reading the
    accumulator (splats: normalise, shade; Gaussians: C + T * background)
    and writing ``ctx.target``, with the renderer's ``resolve_shader`` and
    ``resolve_set_layout``."""

    name, timing, reads, writes = "resolve", "shading", ("accum",), ("output",)

    def __init__(self, timing: str = "shading"):
        self.timing = timing

    def record(self, cb, ctx):
        ctx.t.record_resolve(cb, ctx.target, ctx.r.resolve_shader, ctx.r.resolve_set_layout)


class Frame:
    """An ordered list of passes; ``inputs``: resources available before the
    first pass (a frame recorded after another submission names what that
    one left, e.g. ``("cloud", "records", "order")``).  Raises ValueError
    when a pass reads what no earlier pass wrote, or names an unknown
    resource."""

    def __init__(self, passes, inputs=("cloud",)):
        self.passes = list(passes)
        have = set(inputs)
        for p in self.passes:
            missing = [x for x in p.reads if x not in have]
            if missing:
                raise ValueError(f"{p!r} reads {missing} before any pass writes them")
            unknown = [x for x in p.reads + p.writes if x not in RESOURCES]
            if unknown:
                raise ValueError(f"{p!r} names unknown resources {unknown}")
            have.update(p.writes)
        self.outputs = have

    @property
    def timings(self) -> tuple[str, ...]:
        """The timing buckets of the passes, in order, each once."""
        out = []
        for p in self.passes:
            if p.timing not in out:
                out.append(p.timing)
        return tuple(out)

    @property
    def query_count(self) -> int:
        """Timestamps :meth:`record` writes: one before the first pass and one after each."""
        return len(self.passes) + 1

    def record(self, cb, ctx: FrameContext, query=None, first_query: int = 0) -> None:
        """Record every pass; with ``query`` (a QueryPool whose entries
        ``first_query`` .. ``first_query + query_count`` are reset) a
        timestamp before the first and after every pass."""
        if query is not None:
            cb.timestamp(query, first_query, bottom=False)
        for i, p in enumerate(self.passes):
            p.record(cb, ctx)
            if query is not None:
                cb.timestamp(query, first_query + i + 1)

    def read_timings(self, query, first_query: int = 0) -> dict[str, float]:
        """GPU milliseconds per timing bucket (passes of one bucket summed) and
        ``total``, from the timestamps of :meth:`record` (the submission must
        have finished)."""
        ts = query.results_ns(len(self.passes) + 1, first_query)
        out = {name: 0.0 for name in self.timings}
        for i, p in enumerate(self.passes):
            out[p.timing] += float(ts[i + 1] - ts[i]) * 1e-6
        out["total"] = float(ts[len(self.passes)] - ts[0]) * 1e-6
        return out
