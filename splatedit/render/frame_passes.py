"""The splat frame as a list of pass objects (issue 18, item 1, splat side).

Each pass declares what it reads and writes (names of the frame's targets
and buffers, :data:`RESOURCES`) and records itself into a command buffer; a
:class:`Frame` checks that every input is produced by an earlier pass (or is
an input of the frame) and records the list with a timestamp after every
pass.  The splat renderer's two paths are two pass lists over the same
accumulator images and the same resolve pass:

* raster: ``Prepass -> RasterSplats(depth) -> RasterSplats(attr) -> Resolve``
* compute: ``Prepass -> ComputeVisibility -> ComputeAttributes ->
  AccumulatorCopy -> Resolve``

(:func:`splat_frame`), and the pick frame is ``Prepass -> RasterSplats(pick)``.
:mod:`splatedit.render.progressive` records its chunks with the same
:class:`RasterSplats` and :class:`Resolve` objects (a chunk of splats, loading
what earlier chunks left).

Only :mod:`splatedit.render.vk` calls Vulkan.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from splatedit.render import vk as V
from splatedit.render.splat_layout import _RP_DEPTH, RP_PICK, _rp_attr

#: what passes read and write: the cloud (uploads), the pre-pass records,
#: the depth image, the accumulator images, the compute rasterizer's
#: visibility and accumulation buffers, the pick images, the output target
RESOURCES = ("cloud", "records", "depth", "accum", "vis_buffer", "accum_buffers", "pick", "output")

_RP_DEPTH_LOAD = V.RenderPassDesc(depth=V.Attachment("d32f", "load", initial="depth", final="depth"))
_RP_PICK_LOAD = V.RenderPassDesc(colors=(V.Attachment("r32ui", "load", initial="transfer_src", final="transfer_src"),),
                                 depth=V.Attachment("d32f", "load", initial="transfer_src", final="transfer_src"))


def _rp_attr_load(fmt: str) -> V.RenderPassDesc:
    col = V.Attachment(fmt, "load", initial="shader_read", final="shader_read")
    return V.RenderPassDesc(colors=(col, col), depth=V.Attachment("d32f", "load", initial="depth", final="depth"))


@dataclass
class FrameContext:
    """What a pass records against: the renderer ``r`` (a
    :class:`~splatedit.render.renderer.Renderer`), its per-size targets ``t``,
    the output ``target`` (a :class:`~splatedit.render.targets.RenderTarget`
    or None), whether the splats go through the pre-pass (``prepared``) and
    the pre-pass windows of the frame."""

    r: Any
    t: Any
    target: Any = None
    prepared: bool = True
    windows: int = 1
    extra: dict = field(default_factory=dict)


class Pass:
    """One pass of a frame: ``reads`` / ``writes`` name :data:`RESOURCES`;
    ``timing`` is the bucket of :attr:`Renderer.last_timings_ms` its GPU time
    adds to."""

    name = "pass"
    timing = ""
    reads: tuple[str, ...] = ()
    writes: tuple[str, ...] = ()

    def record(self, cb, ctx: FrameContext) -> None:
        raise NotImplementedError

    def __repr__(self):
        return f"{type(self).__name__}({self.name})"


class Prepass(Pass):
    """The compute pre-pass (deformation, culling, screen setup; records and
    indirect counts).  With several pre-pass windows the splat passes run it
    per window themselves, and this pass records nothing."""

    name, timing, reads, writes = "prepass", "prepass", ("cloud",), ("records",)

    def record(self, cb, ctx):
        if ctx.prepared and ctx.windows == 1:
            ctx.r._record_prepass(cb)


class RasterSplats(Pass):
    """A raster splat pass: ``kind`` ``"depth"`` (visibility), ``"attr"``
    (attribute accumulation into the accumulator images, left in layout
    ``attr_final``) or ``"pick"``.  ``chunk`` = (first splat, count, pre-pass
    window, descriptor sets from :meth:`Renderer._prep_range` or None) draws
    only those splats (preparing them first on the pre-pass path), loading
    what earlier chunks left unless ``first`` is 0."""

    timing = ""

    def __init__(self, kind: str, attr_final: str = "shader_read", chunk=None):
        self.kind, self.attr_final, self.chunk = kind, attr_final, chunk
        self.name = f"raster_{kind}"
        self.timing = {"depth": "visibility", "attr": "attributes", "pick": "pick"}[kind]
        self.reads = ("records",) + (("depth",) if kind == "attr" else ())
        self.writes = {"depth": ("depth",), "attr": ("accum",), "pick": ("pick",)}[kind]

    def _target(self, ctx):
        """(render pass description, framebuffer, clear values) of a whole frame."""
        r, t = ctx.r, ctx.t
        if self.kind == "depth":
            return _RP_DEPTH, t.fb_depth, [1.0]
        if self.kind == "attr":
            fb = t.fb_attr if self.attr_final == "shader_read" else r._fb_attr_readback(t)
            return _rp_attr(r.accum_format, self.attr_final), fb, [(0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0), None]
        t.ensure_pick()
        return RP_PICK, t.fb_pick, [(0, 0, 0, 0), 1.0]

    def record(self, cb, ctx):
        desc, fb, clears = self._target(ctx)
        r = ctx.r
        if self.chunk is None:
            r._record_splat_pass(cb, self.kind, desc, fb, clears, ctx.prepared)
            return
        first, count, window, sets = self.chunk
        if first > 0:
            desc = {"depth": _RP_DEPTH_LOAD, "attr": _rp_attr_load(r.accum_format), "pick": _RP_PICK_LOAD}[self.kind]
            clears = [None] * len(clears)
        if ctx.prepared:
            r._record_prepass(cb, window, sets)
        cb.begin_render_pass(r.cache.render_pass(desc), fb, clears)
        if ctx.prepared:
            r._record_splats(cb, self.kind, True, window)
        else:
            r._record_vertex_splats(cb, self.kind, first, count)
        cb.end_render_pass()


class _ComputeSplats(Pass):
    """A compute rasterizer pass over every pre-pass window (per window: its
    pre-pass when the frame has several, then the dispatches)."""

    visibility = True

    def record(self, cb, ctx):
        r = ctx.r
        crast = r._compute_raster(ctx.t)
        crast.record_clear(cb, self.visibility)
        prep = r._prep_objects()
        for k, (_, wn, _) in enumerate(prep.windows):
            if ctx.windows > 1:
                cb.memory_barrier("compute", "shader_read", "compute", "none")
                r._record_prepass(cb, k)
            cb.memory_barrier("compute", "shader_write", "compute", "shader_read")
            crast.record_draw(cb, r, self.visibility, wn)


class ComputeVisibility(_ComputeSplats):
    """Visibility in compute: 64-bit atomicMin of (pushed-back depth, index)."""

    name, timing, reads, writes = "compute_visibility", "visibility", ("records",), ("vis_buffer",)
    visibility = True


class ComputeAttributes(_ComputeSplats):
    """Attribute accumulation in compute against the visibility buffer."""

    name, timing, reads, writes = ("compute_attributes", "attributes", ("records", "vis_buffer"),
                                   ("accum_buffers",))
    visibility = False


class AccumulatorCopy(Pass):
    """The compute rasterizer's accumulation buffers into the accumulator
    images (left in layout ``final``)."""

    name, timing, reads, writes = "accumulator_copy", "attributes", ("accum_buffers",), ("accum",)

    def __init__(self, final: str = "shader_read"):
        self.final = final

    def record(self, cb, ctx):
        ctx.r._compute_raster(ctx.t).record_copy(cb, ctx.r, self.final)


class Resolve(Pass):
    """The shading pass: normalise the accumulators, shade, write the target
    (``ctx.target``)."""

    name, timing, reads, writes = "resolve", "shading", ("accum",), ("output",)

    def record(self, cb, ctx):
        ctx.t.record_resolve(cb, ctx.target, "resolve.frag", ctx.r._resolve_set_layout)


class Frame:
    """An ordered list of passes; ``inputs``: resources available before the
    first pass.  Raises ValueError when a pass reads what no earlier pass
    wrote."""

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

    def record(self, cb, ctx: FrameContext, query=None) -> None:
        """Record every pass; with ``query`` (a QueryPool of at least
        ``len(passes) + 1`` entries, reset) a timestamp before the first and
        after every pass."""
        if query is not None:
            cb.timestamp(query, 0, bottom=False)
        for i, p in enumerate(self.passes):
            p.record(cb, ctx)
            if query is not None:
                cb.timestamp(query, i + 1)

    def read_timings(self, query) -> dict[str, float]:
        """GPU milliseconds per timing bucket (passes of one bucket summed) and
        ``total``, from the timestamps of :meth:`record`."""
        ts = query.results_ns(len(self.passes) + 1)
        out = {name: 0.0 for name in self.timings}
        for i, p in enumerate(self.passes):
            out[p.timing] += float(ts[i + 1] - ts[i]) * 1e-6
        out["total"] = float(ts[len(self.passes)] - ts[0]) * 1e-6
        return out


def splat_frame(path: str, attr_final: str = "shader_read", resolve: bool = True) -> Frame:
    """The splat renderer's frame on ``path`` (``"raster"`` / ``"compute"``):
    pre-pass, visibility, attributes (accumulator images in layout
    ``attr_final``), and (``resolve``) the shading pass."""
    if path == "compute":
        passes = [Prepass(), ComputeVisibility(), ComputeAttributes(), AccumulatorCopy(attr_final)]
    elif path == "raster":
        passes = [Prepass(), RasterSplats("depth"), RasterSplats("attr", attr_final)]
    else:
        raise ValueError(f"unknown path {path!r}")
    if resolve:
        passes.append(Resolve())
    return Frame(passes)


def pick_frame() -> Frame:
    """The pick frame: pre-pass and the raster pick pass."""
    return Frame([Prepass(), RasterSplats("pick")])

