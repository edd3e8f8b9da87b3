"""Compute-shader rasterization of the EWA splat frame (issue 18, item 2).

The raster path draws the pre-pass records (:mod:`splatedit.render.splat.prepass`)
as quads and square points in two render passes.  On GPUs whose raster
hardware is a small part of the chip (an H100/H200 runs vertex and fragment
shaders on 2 of 66 TPCs) and on lavapipe (a CPU: triangle setup of tiny
primitives dominates) the same records are rasterized in compute
(``shaders_glsl/splat_cs_raster.glsl``), following Schuetz, Kerbl, Wimmer
2021 ("Rendering Point Clouds with Compute Shaders and Vertex Order
Optimization"):

1. visibility (``splat_cs_vis.comp``): per covered pixel, the window depth
   pushed back by the visibility epsilon (as the raster depth pass) and the
   splat index + 1 packed into 64 bits, ``(depth bits << 32) | id``,
   ``atomicMin`` into a per-pixel uint64 buffer (depths in 0..1 are positive
   floats, whose bit patterns order as the floats do);
2. attributes (``splat_cs_attr.comp``): per covered pixel whose unpushed
   depth is at most the visible one, float32 ``atomicAdd`` of w*rgb, w,
   w*normal, w*depth into two RGBA float32 buffers;
3. copy (``splat_cs_copy_*.comp``): the buffers into the raster path's
   accumulator images, so the resolve pass (``resolve.frag``),
   :meth:`Renderer.render_buffers` and the output are shared with the raster
   path.

Splats whose bound holds at most :data:`BIG_PIXELS` pixels are drawn by one
invocation each (a loop over the bound).  Larger ones go to a list, are
binned into per-tile lists (16x16-pixel tiles, up to 128 splats per tile)
and drawn by one workgroup per tile whose invocations own 4 pixels each and
keep the nearest sample (visibility) or the sums (attributes) in registers:
one atomic per pixel and tile instead of one per pixel and splat.  A tile
with more than 128 listed splats tests every listed splat's bound instead
(correct, slower: only with thousands of large splats on screen).

Device features: ``shaderInt64`` + ``shaderBufferInt64Atomics`` and
``VK_EXT_shader_atomic_float``'s ``shaderBufferFloat32AtomicAdd`` (lavapipe
22.3 and NVIDIA drivers have both; :attr:`Device.compute_raster`).  A device
without them draws the raster path.  Float atomics add in a
non-deterministic order: the sums differ from run to run in the last float32
bits (the raster path blends in primitive order, into RGBA16F by default).

Which path a frame takes: :func:`choose_path` (the renderer's
``raster_path`` argument, env var ``SPLATEDIT_RASTER``; the rule for
``"auto"`` is documented there).  Picking stays on the raster path (its pick
pass writes the index of the nearest splat at its exact, unpushed depth);
the progressive refinement draws raster chunks.

Only :mod:`splatedit.render.vk` calls Vulkan.
"""

from __future__ import annotations

import math
import os

import numpy as np

from splatedit.errors import ParameterError
from splatedit.render import vk as V
from splatedit.render.uniforms import CRAST_PUSH, SPLAT_REC_A

#: descriptor set of the compute rasterizer: frame UBO, records A/B, the
#: pre-pass's draw counts, visibility buffer, two accumulation buffers, the
#: big-splat list, the two accumulator images (copy pass), the tile lists
CRAST_SET = (V.Binding(0, "uniform", "comp"), V.Binding(5, "storage", "comp"), V.Binding(6, "storage", "comp"),
             V.Binding(7, "storage", "comp"), V.Binding(10, "storage", "comp"), V.Binding(11, "storage", "comp"),
             V.Binding(12, "storage", "comp"), V.Binding(13, "storage", "comp"),
             V.Binding(14, "storage_image", "comp"), V.Binding(15, "storage_image", "comp"),
             V.Binding(16, "storage", "comp"))
#: a splat whose pixel bound holds more pixels than this goes to the tile
#: lists (see the module docstring).  On lavapipe (hippo scan at 1280x720,
#: same run, load 12): 256 and 1024 take the same time, 64 and 16 are 2-4x
#: slower; a tile's 256 pixels make it the bound where a splat covers a tile
BIG_PIXELS = 256
WORKGROUP = 64
#: workgroups of the binning dispatch (mode 1): invocation i takes list
#: entries i, i + 64 * groups, ...; enough to fill a large GPU, cheap when the
#: list is empty (one read of the count per invocation)
BIG_GROUPS = 256
#: tile side (pixels) and list entries per tile (splat_cs_raster.glsl TILE, TILE_CAP)
TILE, TILE_CAP = 16, 128
#: bytes per pixel of the visibility buffer and of each accumulation buffer
VIS_BYTES, ACC_BYTES = 8, 16

PATHS = ("auto", "raster", "compute")
ENV = "SPLATEDIT_RASTER"


def requested_path(raster_path: str | None) -> str:
    """The path asked for: ``raster_path`` if given, else env var
    ``SPLATEDIT_RASTER`` (``compute`` / ``raster``), else ``"auto"``."""
    if raster_path is None:
        raster_path = os.environ.get(ENV, "").strip().lower() or "auto"
        if raster_path not in PATHS:
            raise ParameterError(ENV, f"must be 'compute' or 'raster', got {raster_path!r}")
    if raster_path not in PATHS:
        raise ParameterError("raster_path", f"must be one of {', '.join(PATHS)}, got {raster_path!r}")
    return raster_path


def choose_path(requested: str, dev: V.Device, width: int, height: int, prepared: bool) -> str:
    """``"compute"`` or ``"raster"`` for a frame of ``width`` x ``height``.

    The compute path needs the device features (:attr:`Device.compute_raster`),
    the pre-pass records (``prepared``: not the vertex path) and buffers of
    ``width * height * 16`` bytes within ``maxStorageBufferRange``; otherwise
    the frame is drawn by the raster path whatever was requested.

    ``"auto"``: where the compute path can run, the renderer measures
    (:meth:`Renderer.frame_path`): the first frame of each image size and
    splat count also draws one frame on each path (GPU timestamps, no
    shading) and keeps the faster, for every size and count in the same
    half-octave buckets (:func:`probe_key`); a count in the bucket next to a
    measured one (same size bucket) takes that measurement's choice without
    probing (a cloud that grows, as an out-of-core scan's view refines, would
    otherwise draw two extra full frames at every half-octave: 3.8 s of 5 s for
    the first frame of a 1.16M-splat grown scan on lavapipe, docs/PERFORMANCE.md).  On lavapipe the compute path wins for
    dense clouds of small splats and loses for sparse scans of large splats
    (docs/PERFORMANCE.md); on GPUs issue 18 expects compute to win (an
    H100/H200 rasterizes on 3% of the chip; compute point rasterizers reach
    10x GL_POINTS on desktop GPUs, Schuetz et al. 2021): not measured yet."""
    if requested == "raster":
        return "raster"
    if not (dev.compute_raster and prepared):
        return "raster"
    if width * height * ACC_BYTES > int(dev.limits.maxStorageBufferRange):
        return "raster"
    return "compute"


def probe_key(width: int, height: int, n: int) -> tuple[int, int]:
    """The key of the "auto" path's measurement: the pixel count and the splat
    count in half-octave buckets, so that a window being resized or a level
    of detail changing its count by a few percent reuses a measurement (a
    probe draws two extra frames)."""
    return round(2.0 * math.log2(max(width * height, 1))), round(2.0 * math.log2(max(n, 1)))


class ComputeRaster:
    """Buffers and the descriptor set of the compute rasterizer for one image
    size and one pre-pass (record) allocation of renderer ``r``."""

    def __init__(self, r, t, prep):
        self.t, self.prep = t, prep
        dev = r.dev
        px = t.width * t.height
        slots = prep.rec_a.size // SPLAT_REC_A.itemsize
        self.objects = []
        try:
            self.vis = self._add(V.Buffer(dev, px * VIS_BYTES, ("storage",)))
            self.acc_c = self._add(V.Buffer(dev, px * ACC_BYTES, ("storage",)))
            self.acc_n = self._add(V.Buffer(dev, px * ACC_BYTES, ("storage",)))
            self.big = self._add(V.Buffer(dev, 4 + 4 * slots, ("storage",)))
            self.tiles = (-(-t.width // TILE)) * (-(-t.height // TILE))
            self.bins = self._add(V.Buffer(dev, 4 * self.tiles * (1 + TILE_CAP), ("storage",)))
            self.dset = self._add(V.DescriptorSet(dev, r.cache.set_layout(CRAST_SET)))
            self.dset.write({0: r.ubo, 5: prep.rec_a, 6: prep.rec_b, 7: prep.draws, 10: self.vis,
                             11: self.acc_c, 12: self.acc_n, 13: self.big,
                             14: (t.accum_color, None), 15: (t.accum_normal, None), 16: self.bins})
        except BaseException:
            self.destroy()
            raise

    def _add(self, obj):
        self.objects.append(obj)
        return obj

    def destroy(self) -> None:
        for o in reversed(self.objects):
            o.destroy()
        self.objects.clear()

    # ------------------------------------------------------------ recording
    def _pipe(self, r, comp: str):
        layout = V.LayoutDesc(sets=(CRAST_SET,), push_bytes=CRAST_PUSH.itemsize, push_stages="comp")
        return r.cache.pipeline(V.ComputeDesc(comp, layout))

    def record_clear(self, cb, visibility: bool) -> None:
        """Clear the visibility buffer (all ones: no splat) or the accumulation
        buffers (zeros), before the pass that writes them."""
        cb.memory_barrier("compute|fragment|transfer", "shader_read|shader_write", "transfer", "transfer_write")
        if visibility:
            cb.fill_buffer(self.vis, 0xFFFFFFFF)
        else:
            cb.fill_buffer(self.acc_c, 0)
            cb.fill_buffer(self.acc_n, 0)
        cb.memory_barrier("transfer", "transfer_write", "compute", "shader_read|shader_write")

    def record_draw(self, cb, r, visibility: bool, slots: int) -> None:
        """The visibility or attribute dispatches over the ``slots`` record slots
        of the current pre-pass window (its records and counts written and
        made visible to compute reads before)."""
        pipe = self._pipe(r, "splat_cs_vis.comp" if visibility else "splat_cs_attr.comp")
        cb.memory_barrier("compute", "shader_read", "transfer", "transfer_write")
        cb.fill_buffer(self.big, 0, 0, 4)                  # the big-splat list's count
        cb.fill_buffer(self.bins, 0, 0, 4 * self.tiles)    # the tile lists' counts
        cb.memory_barrier("transfer", "transfer_write", "compute", "shader_read|shader_write")
        cb.bind_pipeline(pipe)
        cb.bind_descriptor_set(pipe, self.dset)
        groups = max(-(-slots // WORKGROUP), 1)
        limit = int(r.dev.limits.maxComputeWorkGroupCount[0])
        gx = min(groups, limit)
        cb.push_constants(pipe, np.array((slots, 0, 0, BIG_PIXELS), CRAST_PUSH))
        cb.dispatch(gx, -(-groups // gx))                  # small splats; big ones listed
        cb.memory_barrier("compute", "shader_write", "compute", "shader_read|shader_write")
        big = min(BIG_GROUPS, limit)
        cb.push_constants(pipe, np.array((slots, 1, big, BIG_PIXELS), CRAST_PUSH))
        cb.dispatch(big)                                   # binning into the tile lists
        cb.memory_barrier("compute", "shader_write", "compute", "shader_read|shader_write")
        cb.push_constants(pipe, np.array((slots, 2, 0, BIG_PIXELS), CRAST_PUSH))
        cb.dispatch(-(-self.t.width // TILE), -(-self.t.height // TILE))     # the tiles
        cb.memory_barrier("compute", "shader_write", "compute", "shader_read|shader_write")

    def record_copy(self, cb, r, final: str) -> None:
        """Copy the accumulation buffers into the accumulator images and leave
        them in layout ``final`` (``shader_read`` for the resolve pass,
        ``transfer_src`` for a readback)."""
        t = self.t
        comp = "splat_cs_copy_16f.comp" if r.accum_format == "rgba16f" else "splat_cs_copy_32f.comp"
        layout = V.LayoutDesc(sets=(CRAST_SET,), push_bytes=0, push_stages="comp")
        pipe = r.cache.pipeline(V.ComputeDesc(comp, layout))
        for img in (t.accum_color, t.accum_normal):    # after earlier readers and raster-path writes
            cb.image_barrier(img, "general", "fragment|transfer|color_output", "color_write", "compute",
                             "shader_write")
        cb.bind_pipeline(pipe)
        cb.bind_descriptor_set(pipe, self.dset)
        cb.dispatch(-(-t.width // 8), -(-t.height // 8))
        stage, access = ("fragment", "shader_read") if final == "shader_read" else ("transfer", "transfer_read")
        for img in (t.accum_color, t.accum_normal):
            cb.image_barrier(img, final, "compute", "shader_write", stage, access)
