"""Device-wide GPU sorts of (key, value) pairs of uint32, recorded into a
command buffer: :class:`RadixSort` (the one the renderers use) and
:class:`BitonicSort` (the sort it replaced, kept for comparison).

:class:`RadixSort` is a least-significant-digit radix sort with 8-bit digits
(``bits // 8`` passes), in the reduce-then-scan scheme (Merrill & Grimshaw
2011, "High Performance and Scalable Radix Sorting"; the pass structure of
AMD's FidelityFX parallel sort): per pass

1. upsweep (``gs_radix_upsweep.comp``): one workgroup per block of
   ``RADIX_BLOCK`` keys counts the digits of its block;
2. scan (``gs_radix_scan.comp``): one workgroup per digit turns the digit's
   block counts into offsets (exclusive scan) and its total;
3. scatter (``gs_radix_scatter*.comp``): each block ranks its keys stably
   (ballots over the subgroup's digit bits where the device has subgroup
   ballots in compute shaders, else comparisons in shared memory) and writes
   each pair to digit base + block offset + rank.

The element count is read on the GPU from a buffer (e.g. the visible count an
earlier pass wrote): ``gs_radix_setup.comp`` clamps it to the capacity and
writes the indirect dispatch size, so the CPU never reads it back.  The pairs
ping-pong between the caller's buffers and the sort's scratch; an even number
of passes (``bits`` 16 or 32) leaves the result in the caller's buffers.

Only :mod:`splatedit.render.vk` calls Vulkan.
"""

from __future__ import annotations

import numpy as np

from splatedit.errors import ParameterError
from splatedit.render import vk as V
from splatedit.render.uniforms import GS_SORT_PUSH, RADIX_PUSH

#: keys per workgroup of the radix sort (gs_radix.glsl BLOCK = 256 invocations x 8)
RADIX_BLOCK = 2048
_RADIX = 256
#: set 0 of the radix shaders (gs_radix.glsl): count, keys in, values in, keys
#: out, values out, histograms, dispatch arguments
RADIX_SET = tuple(V.Binding(i, "storage", "comp") for i in range(7))
#: set 0 of the bitonic sort (gs_sort.comp): keys, values
BITONIC_SET = (V.Binding(0, "storage", "comp"), V.Binding(1, "storage", "comp"))
_BITONIC_WG = 256
#: scatter variants: "subgroup" (ballots), "shared" (shared memory only)
RADIX_MODES = ("auto", "subgroup", "shared")


def subgroup_scatter_supported(dev: V.Device) -> bool:
    """Whether the ballot variant of the scatter runs on ``dev``: subgroup
    ballots in compute shaders, subgroups of 8..128 invocations that divide
    the 256-invocation workgroup (at most 32 subgroups: the shader's counters)."""
    sp = V.subgroup_properties(dev)
    return sp.compute and sp.ballot and 8 <= sp.size <= 128 and 256 % sp.size == 0


def default_scatter(dev: V.Device) -> str:
    """The scatter variant of ``mode="auto"``: "subgroup" where
    :func:`subgroup_scatter_supported`, except on a CPU device (lavapipe
    emulates the ballots: the shared-memory variant sorted 100k pairs there in
    0.64x the time, ``bench gpu-sort``), else "shared"."""
    if subgroup_scatter_supported(dev) and not V.is_cpu_device(dev):
        return "subgroup"
    return "shared"


def _barrier_in(cb):
    """Writes of the caller (compute shaders, transfers, host) -> the sort's reads."""
    cb.memory_barrier("compute|transfer|host", "shader_write|transfer_write|host_write",
                      "compute|draw_indirect", "shader_read|shader_write|indirect_read")


def _barrier_out(cb):
    """The sort's writes -> any later reader (compute, vertex, fragment, transfer, draw)."""
    cb.memory_barrier("compute", "shader_write", "compute|vertex|fragment|transfer|draw_indirect",
                      "shader_read|shader_write|transfer_read|indirect_read")


class RadixSort:
    """A GPU radix sort of ``keys`` (uint32) with ``values`` (uint32) in
    place, ascending and stable, for up to ``capacity`` pairs.

    Args:
        cache: the :class:`~splatedit.render.vk.PipelineCache` that builds the pipelines.
        keys, values: storage buffers of at least ``4 * capacity`` bytes.
        count: storage buffer holding the element count as its uint32 number
            ``count_index`` (clamped to ``capacity`` on the GPU).
        capacity: most pairs sorted.
        mode: "auto" (:func:`default_scatter`), "subgroup" (ballots) or
            "shared" (shared memory only).

    Owns its scratch (``8 * capacity`` bytes of ping-pong pairs, the block
    histograms, the dispatch arguments); :meth:`destroy` frees it.
    """

    def __init__(self, dev: V.Device, cache: V.PipelineCache, keys: V.Buffer, values: V.Buffer,
                 count: V.Buffer, *, capacity: int, count_index: int = 0, mode: str = "auto"):
        if mode not in RADIX_MODES:
            raise ParameterError("mode", f"must be one of {RADIX_MODES}, got {mode!r}")
        capacity = int(capacity)
        if capacity < 1:
            raise ParameterError("capacity", f"must be >= 1, got {capacity}")
        for name, b in (("keys", keys), ("values", values)):
            if b.size < 4 * capacity:
                raise ParameterError(name, f"buffer of {b.size} bytes is smaller than 4 x capacity {capacity}")
        if not 0 <= count_index < count.size // 4:
            raise ParameterError("count_index", f"must index a uint32 of the {count.size}-byte count buffer")
        if mode == "auto":
            mode = default_scatter(dev)
        elif mode == "subgroup" and not subgroup_scatter_supported(dev):
            raise ParameterError("mode", f"device {dev.name!r} has no subgroup ballots for the scatter")
        self.dev, self.cache = dev, cache
        self.capacity, self.count_index, self.mode = capacity, int(count_index), mode
        self.keys, self.values, self.count = keys, values, count
        self._objs = []
        try:
            blocks = -(-capacity // RADIX_BLOCK)
            self._alt_keys = self._add(V.Buffer(dev, 4 * capacity, ("storage",)))
            self._alt_vals = self._add(V.Buffer(dev, 4 * capacity, ("storage",)))
            self._hist = self._add(V.Buffer(dev, 4 * _RADIX * (blocks + 1), ("storage",)))
            self._args = self._add(V.Buffer(dev, 16, ("storage", "indirect")))
            #: the sort's dispatch arguments after :meth:`record`: one workgroup
            #: per RADIX_BLOCK pairs (x, 1, 1), then the count sorted (uint32 each)
            self.args = self._args
            layout = cache.set_layout(RADIX_SET)
            self._sets = []
            for src, dst in (((keys, values), (self._alt_keys, self._alt_vals)),
                             ((self._alt_keys, self._alt_vals), (keys, values))):
                s = self._add(V.DescriptorSet(dev, layout))
                s.write({0: count, 1: src[0], 2: src[1], 3: dst[0], 4: dst[1], 5: self._hist, 6: self._args})
                self._sets.append(s)
        except BaseException:
            self.destroy()
            raise

    def _add(self, obj):
        self._objs.append(obj)
        return obj

    def _pipe(self, shader: str):
        layout = V.LayoutDesc(sets=(RADIX_SET,), push_bytes=RADIX_PUSH.itemsize, push_stages="comp")
        return self.cache.pipeline(V.ComputeDesc(shader, layout))

    def record(self, cb, bits: int = 32) -> None:
        """Record the sort of the low ``bits`` (16 or 32) bits of the keys into
        ``cb`` (keys must be below 2**bits for a full order), with the
        barriers before (the caller's compute, transfer and host writes) and
        after (to compute, vertex, fragment, transfer and indirect reads)."""
        if bits not in (16, 32):
            raise ParameterError("bits", f"must be 16 or 32, got {bits!r}")
        scatter = "gs_radix_scatter_sg.comp" if self.mode == "subgroup" else "gs_radix_scatter.comp"
        _barrier_in(cb)
        setup = self._pipe("gs_radix_setup.comp")
        cb.bind_pipeline(setup)
        cb.bind_descriptor_set(setup, self._sets[0])
        cb.push_constants(setup, np.array((0, self.count_index, self.capacity, 0), RADIX_PUSH))
        cb.dispatch(1)
        for p in range(bits // 8):
            dset = self._sets[p % 2]
            push = np.array((8 * p, self.count_index, self.capacity, 0), RADIX_PUSH)
            for shader, indirect in (("gs_radix_upsweep.comp", True), ("gs_radix_scan.comp", False),
                                     (scatter, True)):
                cb.memory_barrier("compute", "shader_write", "compute|draw_indirect",
                                  "shader_read|shader_write|indirect_read")
                pipe = self._pipe(shader)
                cb.bind_pipeline(pipe)
                cb.bind_descriptor_set(pipe, dset)
                cb.push_constants(pipe, push)
                if indirect:
                    cb.dispatch_indirect(self._args, 0)
                else:
                    cb.dispatch(_RADIX)
        _barrier_out(cb)

    def destroy(self) -> None:
        """Free the scratch buffers and descriptor sets (idempotent)."""
        for o in reversed(self._objs):
            o.destroy()
        self._objs = []


class BitonicSort:
    """The bitonic sort (``gs_sort.comp``) of the first ``n`` pairs of
    ``keys`` / ``values``, n a power of two padded by the caller with
    0xFFFFFFFF keys: log2(n) (log2(n) + 1) / 2 dispatches (210 for 1M keys),
    not stable.  Kept as the baseline of ``splatedit bench gpu-sort``."""

    def __init__(self, dev: V.Device, cache: V.PipelineCache, keys: V.Buffer, values: V.Buffer):
        self.dev, self.cache = dev, cache
        self._set = V.DescriptorSet(dev, cache.set_layout(BITONIC_SET))
        self._set.write({0: keys, 1: values})

    def record(self, cb, n: int) -> None:
        if n & (n - 1):
            raise ParameterError("n", f"must be a power of two, got {n}")
        layout = V.LayoutDesc(sets=(BITONIC_SET,), push_bytes=GS_SORT_PUSH.itemsize, push_stages="comp")
        pipe = self.cache.pipeline(V.ComputeDesc("gs_sort.comp", layout))
        _barrier_in(cb)
        cb.bind_pipeline(pipe)
        cb.bind_descriptor_set(pipe, self._set)
        k = 2
        while k <= n:
            j = k // 2
            while j >= 1:
                cb.memory_barrier("compute", "shader_write", "compute", "shader_read|shader_write")
                cb.push_constants(pipe, np.array((k, j, n), GS_SORT_PUSH))
                cb.dispatch((n + _BITONIC_WG - 1) // _BITONIC_WG)
                j //= 2
            k *= 2
        _barrier_out(cb)

    def destroy(self) -> None:
        if self._set is not None:
            self._set.destroy()
            self._set = None


def sortable_float_keys(x: np.ndarray) -> np.ndarray:
    """uint32 keys whose unsigned order is the order of the float32 values
    ``x`` (negative values: all bits flipped; others: the sign bit set), as
    the shaders' ``sortable_depth``; NaNs sort after +inf."""
    b = np.ascontiguousarray(x, np.float32).view(np.uint32)
    return np.where(b >> 31, ~b, b | np.uint32(0x80000000)).astype(np.uint32)
