"""The splat renderer's passes (issue 18, item 1, splat side), on the frame
model of :mod:`splatedit.render.frame`.

Each pass declares what it reads and writes (names of the frame's targets
and buffers, :data:`RESOURCES`) and records itself into a command buffer; a
:class:`Frame` checks that every input is produced by an earlier pass (or is
an input of the frame) and records the list with a timestamp after every
pass.  The splat renderer's two paths are two pass lists over the same
accumulator images and the same resolve pass:

* raster: ``Prepass -> RasterSplats(depth) -> RasterSplats(attr) -> Resolve``
* compute: ``Prepass -> ComputeVisibility -> ComputeAttributes ->
  AccumulatorCopy -> Resolve``

With eye-dome lighting (``edl``) the last pass is :class:`EyeDomeResolve`
instead of :class:`Resolve`.

(:func:`splat_frame`), and the pick frame is ``Prepass -> RasterSplats(pick)``.
:mod:`splatedit.render.splat.progressive` records its chunks with the same
:class:`RasterSplats` and :class:`Resolve` objects (a chunk of splats, loading
what earlier chunks left).

Only :mod:`splatedit.render.vk` calls Vulkan.
"""

from __future__ import annotations

from splatedit.render import vk as V
from splatedit.render.frame import RESOURCES, Frame, FrameContext, Pass, Resolve
from splatedit.render.splat.layout import RP_DEPTH, RP_PICK, rp_attr

__all__ = ["RESOURCES", "Frame", "FrameContext", "Pass", "Resolve", "Prepass", "RasterSplats",
           "ComputeVisibility", "ComputeAttributes", "AccumulatorCopy", "EyeDomeResolve", "splat_frame", "pick_frame"]

_RP_DEPTH_LOAD = V.RenderPassDesc(depth=V.Attachment("d32f", "load", initial="depth", final="depth"))
_RP_PICK_LOAD = V.RenderPassDesc(colors=(V.Attachment("r32ui", "load", initial="transfer_src", final="transfer_src"),),
                                 depth=V.Attachment("d32f", "load", initial="transfer_src", final="transfer_src"))


def _rp_attr_load(fmt: str) -> V.RenderPassDesc:
    col = V.Attachment(fmt, "load", initial="shader_read", final="shader_read")
    return V.RenderPassDesc(colors=(col, col), depth=V.Attachment("d32f", "load", initial="depth", final="depth"))


class Prepass(Pass):
    """The compute pre-pass (deformation, culling, screen setup; records and
    indirect counts).  With several pre-pass windows the splat passes run it
    per window themselves, and this pass records nothing."""

    name, timing, reads, writes = "prepass", "prepass", ("cloud",), ("records",)

    def record(self, cb, ctx):
        if ctx.prepared and ctx.windows == 1:
            ctx.r.record_prepass(cb)


class RasterSplats(Pass):
    """A raster splat pass: ``kind`` ``"depth"`` (visibility), ``"attr"``
    (attribute accumulation into the accumulator images, left in layout
    ``attr_final``) or ``"pick"``.  ``chunk`` = (first splat, count, pre-pass
    window, descriptor sets from :meth:`Renderer.prep_range` or None) draws
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
            return RP_DEPTH, t.fb_depth, [1.0]
        if self.kind == "attr":
            fb = t.fb_attr if self.attr_final == "shader_read" else r.fb_attr_readback(t)
            return rp_attr(r.accum_format, self.attr_final), fb, [(0.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0), None]
        t.ensure_pick()
        return RP_PICK, t.fb_pick, [(0, 0, 0, 0), 1.0]

    def record(self, cb, ctx):
        desc, fb, clears = self._target(ctx)
        r = ctx.r
        if self.chunk is None:
            r.record_splat_pass(cb, self.kind, desc, fb, clears, ctx.prepared)
            return
        first, count, window, sets = self.chunk
        if first > 0:
            desc = {"depth": _RP_DEPTH_LOAD, "attr": _rp_attr_load(r.accum_format), "pick": _RP_PICK_LOAD}[self.kind]
            clears = [None] * len(clears)
        if ctx.prepared:
            r.record_prepass(cb, window, sets)
        cb.begin_render_pass(r.cache.render_pass(desc), fb, clears)
        if ctx.prepared:
            r.record_splats(cb, self.kind, True, window)
        else:
            r.record_vertex_splats(cb, self.kind, first, count)
        cb.end_render_pass()


class _ComputeSplats(Pass):
    """A compute rasterizer pass over every pre-pass window (per window: its
    pre-pass when the frame has several, then the dispatches)."""

    visibility = True

    def record(self, cb, ctx):
        r = ctx.r
        crast = r.compute_rasterizer(ctx.t)
        crast.record_clear(cb, self.visibility)
        prep = r.prep_objects()
        for k, (_, wn, _) in enumerate(prep.windows):
            if ctx.windows > 1:
                cb.memory_barrier("compute", "shader_read", "compute", "none")
                r.record_prepass(cb, k)
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
        ctx.r.compute_rasterizer(ctx.t).record_copy(cb, ctx.r, self.final)


class EyeDomeResolve(Resolve):
    """The shading pass with eye-dome lighting (Boucheny 2009): the resolve
    shading, then every covered pixel darkened by the log-depth steps down
    to its 8 neighbours at ``F.display.w`` pixels, ``exp(-300 *
    F.display.z * mean step)`` (shaders_glsl/resolve_edl.frag); it reads
    the linear view depth the accumulators hold (w*depth / w), so a scan
    without normals still shows its edges and creases."""

    name, timing, reads, writes = "resolve_edl", "shading", ("accum",), ("output",)
    shader = "resolve_edl.frag"

    def record(self, cb, ctx):
        ctx.t.record_resolve(cb, ctx.target, self.shader, ctx.r.resolve_set_layout)


def splat_frame(path: str, attr_final: str = "shader_read", resolve: bool = True, edl: bool = False) -> Frame:
    """The splat renderer's frame on ``path`` (``"raster"`` / ``"compute"``):
    pre-pass, visibility, attributes (accumulator images in layout
    ``attr_final``), and (``resolve``) the shading pass, with eye-dome
    lighting (:class:`EyeDomeResolve`) when ``edl``."""
    if path == "compute":
        passes = [Prepass(), ComputeVisibility(), ComputeAttributes(), AccumulatorCopy(attr_final)]
    elif path == "raster":
        passes = [Prepass(), RasterSplats("depth"), RasterSplats("attr", attr_final)]
    else:
        raise ValueError(f"unknown path {path!r}")
    if resolve:
        passes.append(EyeDomeResolve() if edl else Resolve())
    return Frame(passes)


def pick_frame() -> Frame:
    """The pick frame: pre-pass and the raster pick pass."""
    return Frame([Prepass(), RasterSplats("pick")])

