"""The compute tile rasterizer of the Gaussian renderer (``path="compute"``
of :class:`splatedit.render.gaussian.renderer.GaussianRenderer`), 3DGS style (Kerbl
et al. 2023, "3D Gaussian Splatting for Real-Time Radiance Field Rendering",
section 6), beside the quad raster path.

After the pre-pass and the depth sort (``order[:n visible]`` front to back,
the count in the indirect draw's instance count), all on the GPU:

1. ``gs_tile_setup``: the visible count -> the dispatch of the scan passes;
2. ``gs_tile_reduce`` / ``gs_tile_offsets`` / ``gs_tile_emit``: a device-wide
   exclusive scan (reduce, then scan of the block sums, then scan inside each
   block) of the number of TILE x TILE tiles each Gaussian's ellipse of alpha
   >= floor touches gives it its slots; it writes one (tile id, Gaussian) pair
   per tile there, so the pairs come in depth order;
3. a stable GPU radix sort of the pairs by tile id (16-bit keys: 2 passes;
   :class:`splatedit.render.gaussian.gpu_sort.RadixSort`) keeps depth order inside each tile;
4. ``gs_tile_ranges``: each tile's run of pairs;
5. ``gs_tile_blend``: one workgroup per tile blends its Gaussians front to
   back in batches through shared memory, stops per pixel where the
   transmittance would fall below GS_MIN_TRANSMITTANCE and per tile when every
   pixel has, and stores (C, 1 - T) into the quad path's accumulator image,
   which the same resolve (``gs_resolve.frag``) turns into the output.

The pair buffers hold ``capacity`` pairs; a frame that wants more drops the
rest and reports it (:meth:`TileRasterizer.pairs_wanted`): the renderer grows
the buffers and draws the frame again.

Only :mod:`splatedit.render.vk` calls Vulkan.
"""

from __future__ import annotations

import numpy as np

from splatedit.render import vk as V
from splatedit.render.gaussian.gpu_sort import RadixSort
from splatedit.render.uniforms import TILE_PUSH
from splatedit.tolerances import GS_MIN_TRANSMITTANCE

#: tile edge in pixels (gs_tile.glsl TILE)
TILE = 16
_TBLOCK = 2048
#: set 1 of the tile passes (gs_tile.glsl): pair keys, pair values, scan, tile
#: ranges, the tile sort's dispatch arguments, the accumulator (storage image)
TILE_SET = (V.Binding(0, "storage", "comp"), V.Binding(1, "storage", "comp"), V.Binding(2, "storage", "comp"),
            V.Binding(3, "storage", "comp"), V.Binding(4, "storage", "comp"), V.Binding(5, "storage_image", "comp"))
#: the largest tile grid whose ids fit the 16-bit sort (4096 x 4096 pixels)
MAX_TILES_16BIT = 1 << 16


def tile_grid(width: int, height: int) -> tuple[int, int]:
    """Tiles per row and tile rows covering a width x height image."""
    return -(-int(width) // TILE), -(-int(height) // TILE)


class TileRasterizer:
    """Scratch and passes of the tile rasterizer for one scene.

    Args:
        dev, cache: the renderer's device and pipeline cache.
        gs_set: the renderer's set 0 (``gs_common.glsl``: frame block, records,
            order, indirect draw) and its layout ``gs_layout``.
        gaussians: Gaussians of the scene (sizes the scan's block sums).
        capacity: (tile, Gaussian) pairs the buffers hold at first.
        accum_format: "rgba16f" or "rgba32f" (the blend's storage image format).
    """

    def __init__(self, dev: V.Device, cache: V.PipelineCache, gs_set, gs_layout: tuple, gaussians: int,
                 capacity: int, accum_format: str, sort_mode: str = "auto"):
        self.dev, self.cache, self.gs_set, self.gs_layout = dev, cache, gs_set, gs_layout
        self.accum_format = accum_format
        self.sort_mode = sort_mode
        limit = int(dev.limits.maxStorageBufferRange) // 4
        #: the most pairs a storage buffer can hold on this device
        self.max_capacity = limit
        self._blocks = -(-max(int(gaussians), 1) // _TBLOCK)
        self._scan = V.Buffer(dev, 4 * (8 + self._blocks), ("storage", "indirect"), host_visible=True)
        self._scan.view(np.uint32)[:] = 0
        self._pairs = []
        self._sort = None
        self._size = None           # (targets, ranges buffer, set 1)
        self.capacity = 0
        try:
            self._alloc_pairs(min(max(int(capacity), 1), limit))
        except BaseException:
            self.destroy()
            raise

    def _alloc_pairs(self, capacity: int):
        self._free_pairs()
        self.capacity = int(capacity)
        self._keys = V.Buffer(self.dev, 4 * self.capacity, ("storage",))
        self._pairs.append(self._keys)
        self._vals = V.Buffer(self.dev, 4 * self.capacity, ("storage",))
        self._pairs.append(self._vals)
        self._sort = RadixSort(self.dev, self.cache, self._keys, self._vals, self._scan,
                               capacity=self.capacity, count_index=2, mode=self.sort_mode)

    def _free_pairs(self):
        self._free_size()
        if self._sort is not None:
            self._sort.destroy()
            self._sort = None
        for b in reversed(self._pairs):
            b.destroy()
        self._pairs = []

    def _free_size(self):
        if self._size is not None:
            _, ranges, dset = self._size
            dset.destroy()
            ranges.destroy()
            self._size = None

    def grow(self, pairs: int) -> bool:
        """Make room for ``pairs`` pairs (with 25 % headroom, within the
        device's storage-buffer range); waits for the device.  False when
        the device cannot hold them (the frame then misses Gaussians)."""
        want = min(int(pairs * 1.25) + 1, self.max_capacity)
        if want <= self.capacity:
            return False
        self.dev.wait_idle()
        self._alloc_pairs(want)
        return pairs <= self.capacity

    def pairs_wanted(self) -> int:
        """(tile, Gaussian) pairs the last recorded frame wanted (read after it finished)."""
        return int(self._scan.view(np.uint32)[0])

    def _size_state(self, targets):
        if self._size is not None and self._size[0] is targets:
            return self._size
        if self._size is not None:
            self.dev.wait_idle()
            self._free_size()
        tx, ty = tile_grid(targets.width, targets.height)
        ranges = V.Buffer(self.dev, 8 * tx * ty, ("storage",))
        dset = V.DescriptorSet(self.dev, self.cache.set_layout(TILE_SET))
        dset.write({0: self._keys, 1: self._vals, 2: self._scan, 3: ranges, 4: self._sort.args,
                    5: (targets.accum, None)})
        self._size = (targets, ranges, dset)
        return self._size

    def _bind(self, cb, shader: str, dset):
        layout = V.LayoutDesc(sets=(self.gs_layout, TILE_SET), push_bytes=TILE_PUSH.itemsize, push_stages="comp")
        pipe = self.cache.pipeline(V.ComputeDesc(shader, layout))
        cb.bind_pipeline(pipe)
        cb.bind_descriptor_set(pipe, self.gs_set, 0)
        cb.bind_descriptor_set(pipe, dset, 1)
        return pipe

    def record(self, cb, targets) -> None:
        """Record the tile passes of one frame into ``cb``: they read the
        depth-sorted ``order`` and the visible count and leave the
        accumulator ``targets.accum`` in SHADER_READ layout for the resolve."""
        _, ranges, dset = self._size_state(targets)
        tx, ty = tile_grid(targets.width, targets.height)
        push = np.array((self.capacity, tx, ty, GS_MIN_TRANSMITTANCE), TILE_PUSH)
        cb.memory_barrier("host|compute|transfer", "host_write|shader_write|transfer_write",
                          "compute|transfer", "shader_read|shader_write|transfer_write")
        cb.fill_buffer(ranges, 0)
        steps = (("gs_tile_setup.comp", None), ("gs_tile_reduce.comp", 16), ("gs_tile_offsets.comp", None),
                 ("gs_tile_emit.comp", 16))
        for shader, indirect in steps:
            cb.memory_barrier("compute|transfer", "shader_write|transfer_write", "compute|draw_indirect",
                              "shader_read|shader_write|indirect_read")
            pipe = self._bind(cb, shader, dset)
            cb.push_constants(pipe, push)
            if indirect is None:
                cb.dispatch(1)
            else:
                cb.dispatch_indirect(self._scan, indirect)
        self._sort.record(cb, bits=16 if tx * ty <= MAX_TILES_16BIT else 32)
        pipe = self._bind(cb, "gs_tile_ranges.comp", dset)
        cb.push_constants(pipe, push)
        cb.dispatch_indirect(self._sort.args, 0)
        cb.memory_barrier("compute", "shader_write", "compute", "shader_read")
        cb.image_barrier(targets.accum, "general", "fragment|compute", "none", "compute", "shader_write")
        pipe = self._bind(cb, "gs_tile_blend32.comp" if self.accum_format == "rgba32f" else "gs_tile_blend.comp",
                          dset)
        cb.push_constants(pipe, push)
        cb.dispatch(tx, ty)
        cb.image_barrier(targets.accum, "shader_read", "compute", "shader_write", "fragment", "shader_read")

    def destroy(self) -> None:
        """Free every buffer and set (idempotent)."""
        self._free_pairs()
        if self._scan is not None:
            self._scan.destroy()
            self._scan = None
