"""The Gaussian renderer's passes (issue 18, item 1, Gaussian side), on the
frame model of :mod:`splatedit.render.frame` shared with the splat renderer.

A Gaussian frame is two submissions, because the CPU sort (``sort="cpu"``)
runs between them and the editor records the draw into its own command
buffer after :meth:`GaussianRenderer.prepare_frame`:

* prepare: ``GsPrepare -> GsSort`` (GPU sorts) or ``GsPrepare`` (the CPU
  sort reads the keys back afterwards), :func:`prepare_frame`;
* draw: ``GsQuads -> Resolve`` (``path="raster"``) or
  ``GsTiles -> Resolve`` (``path="compute"``), inputs ``cloud``,
  ``records``, ``order`` (what the prepare submission left),
  :func:`draw_frame`;
* pick: ``GsPrepare -> GsPick`` (:func:`pick_frame`).

:mod:`splatedit.render.gaussian.progressive` draws the sorted order in chunks with
``GsQuads(chunk=...)`` and finishes with the shared :class:`Resolve`.  The
passes record through the renderer's public pieces (``record_prepass``,
``record_sort``, ``draw_pipeline``, ``pick_pipeline``, ``scene_set``,
``draws``, ``tiles``).  Only :mod:`splatedit.render.vk` calls Vulkan.
"""

from __future__ import annotations

from splatedit.render import vk as V
from splatedit.render.frame import Frame, Pass, Resolve
from splatedit.render.gaussian.resources import rp_accum
from splatedit.render.splat.layout import RP_PICK

__all__ = ["GsPrepare", "GsSort", "GsQuads", "GsTiles", "GsPick", "prepare_frame", "draw_frame", "pick_frame"]


def _rp_accum_load(fmt: str) -> V.RenderPassDesc:
    return V.RenderPassDesc(colors=(V.Attachment(fmt, "load", initial="shader_read", final="shader_read"),))


class GsPrepare(Pass):
    """The pre-pass (deformation, projection to a conic, SH colour, culling,
    the depth key); ``compact``: also append the visible keys (the GPU radix
    sort's input).  Ends with a barrier that makes the records visible to
    the next compute pass and to the host (the CPU sort reads the keys)."""

    name, timing, reads, writes = "gs_prepare", "prepass", ("cloud",), ("records",)

    def __init__(self, compact: bool = False, barrier: bool = True):
        self.compact, self.barrier = compact, barrier

    def record(self, cb, ctx):
        ctx.r.record_prepass(cb, compact=self.compact)
        if self.barrier:
            # the barrier first: lavapipe writes a timestamp without waiting for a
            # dispatch still running (the pass measured ~0 ms without it)
            cb.memory_barrier("compute", "shader_write", "compute|host", "shader_read|shader_write|host_read")


class GsSort(Pass):
    """The GPU depth sort of the visible keys (radix or bitonic, as the renderer's ``sort``)."""

    name, timing, reads, writes = "gs_sort", "sort", ("records",), ("order",)

    def record(self, cb, ctx):
        ctx.r.record_sort(cb)
        cb.memory_barrier("compute", "shader_write", "compute", "shader_read")


class GsQuads(Pass):
    """The quad raster path: one screen-aligned quad per visible Gaussian in
    depth order, blended front to back into the accumulator.  ``chunk`` =
    (first, count): only those of the sorted order, blended over what the
    accumulator holds unless ``clear`` (progressive refinement); None: every
    visible Gaussian (the indirect count of the pre-pass)."""

    name, timing, reads, writes = "gs_quads", "draw", ("records", "order"), ("accum",)

    def __init__(self, chunk: tuple[int, int] | None = None, clear: bool = True):
        self.chunk, self.clear = chunk, clear

    def record(self, cb, ctx):
        r, t = ctx.r, ctx.t
        rp = rp_accum(r.accum_format) if self.clear else _rp_accum_load(r.accum_format)
        pipe = r.draw_pipeline()
        if self.chunk is None:
            cb.memory_barrier("host", "host_write", "draw_indirect|vertex", "indirect_read|shader_read")
        else:
            cb.memory_barrier("host", "host_write", "vertex", "shader_read")
        cb.begin_render_pass(r.cache.render_pass(rp), t.fb_accum, [(0.0, 0.0, 0.0, 0.0) if self.clear else None])
        if self.chunk is None:
            cb.bind_pipeline(pipe)
            cb.bind_descriptor_set(pipe, r.scene_set)
            cb.draw_indirect(r.draws, 0)
        elif self.chunk[1] > 0:
            cb.bind_pipeline(pipe)
            cb.bind_descriptor_set(pipe, r.scene_set)
            cb.draw(4, int(self.chunk[1]), 0, int(self.chunk[0]))
        cb.end_render_pass()


class GsTiles(Pass):
    """The compute tile rasterizer (:class:`~splatedit.render.gaussian.tiles.TileRasterizer`):
    (tile, Gaussian) pairs, their sort by tile, per-tile front-to-back blending."""

    name, timing, reads, writes = "gs_tiles", "draw", ("records", "order"), ("accum",)

    def record(self, cb, ctx):
        ctx.r.tiles.record(cb, ctx.t)


class GsPick(Pass):
    """The pick pass: the pickable Gaussians' ellipses in index order with a
    depth test (records of culled Gaussians are stale: the vertex shader
    drops them through their zeroed opacity)."""

    name, timing, reads, writes = "gs_pick", "pick", ("records",), ("pick",)

    def record(self, cb, ctx):
        r = ctx.r
        pipe = r.pick_pipeline()
        cb.memory_barrier("compute", "shader_write", "vertex", "shader_read")
        cb.begin_render_pass(r.cache.render_pass(RP_PICK), ctx.t.fb_pick, [(0, 0, 0, 0), 1.0])
        cb.bind_pipeline(pipe)
        cb.bind_descriptor_set(pipe, r.scene_set)
        cb.draw(4, r.count)
        cb.end_render_pass()


def prepare_frame(sort: str) -> Frame:
    """The first submission of a Gaussian frame: the pre-pass and, for the
    GPU sorts (``sort`` ``"gpu"`` / ``"bitonic"``), the sort; ``"cpu"``:
    the pre-pass alone (the keys are sorted on the host after it)."""
    if sort == "cpu":
        return Frame([GsPrepare()])
    return Frame([GsPrepare(compact=sort == "gpu"), GsSort()])


def draw_frame(path: str) -> Frame:
    """The second submission: the draw on ``path`` (``"raster"`` /
    ``"compute"``) and the shared resolve."""
    if path == "compute":
        draw = GsTiles()
    elif path == "raster":
        draw = GsQuads()
    else:
        raise ValueError(f"unknown path {path!r}")
    return Frame([draw, Resolve(timing="resolve")], inputs=("cloud", "records", "order"))


def pick_frame() -> Frame:
    """The pick frame: the pre-pass (index order, no sort) and the pick pass."""
    return Frame([GsPrepare(barrier=False), GsPick()])
