"""``splatedit bench gpu-sort``: the GPU radix sort of (key, value) pairs
against the bitonic sort it replaced and numpy, in the same run.

Per pair count: uniformly random uint32 keys with their indices as values.
Cases: ``radix`` (the device's scatter variant, :func:`default_scatter`),
``radix_<other variant>``, ``bitonic`` (padded to a power of two with
0xFFFFFFFF keys), ``numpy_stable`` (``np.argsort(kind="stable")``, what the
radix sort equals) and ``numpy`` (the default introsort, the renderer's CPU
sort).  GPU times are the median of ``repeats`` timestamped submissions (the
keys restored by a copy outside the timestamps), CPU times the best wall time.
The radix output is checked against numpy's stable argsort each run.
"""

from __future__ import annotations

import time
from typing import Iterator

import numpy as np

from splatedit.bench.render import load_average
from splatedit.render import vk as V
from splatedit.render.gaussian.gpu_sort import BitonicSort, RadixSort, default_scatter, subgroup_scatter_supported


def _gpu_times(dev, record, restore, repeats: int) -> float:
    """Median GPU ms of ``record`` over ``repeats`` submissions, each after ``restore``."""
    q = V.QueryPool(dev, 2)
    try:
        out = []
        for _ in range(repeats + 1):                 # the first: warm-up (pipeline JIT)
            def rec(cb):
                restore(cb)
                cb.memory_barrier("transfer", "transfer_write", "compute", "shader_read|shader_write")
                cb.reset_queries(q)
                cb.timestamp(q, 0, bottom=False)
                record(cb)
                cb.timestamp(q, 1)
            dev.submit(rec)
            out.append(float(q.results_ns(2)[1]) * 1e-6)
        return float(np.median(out[1:]))
    finally:
        q.destroy()


def bench_gpu_sort(counts=(100_000, 1_000_000, 4_000_000), repeats: int = 3, device_name: str | None = None,
                   seed: int = 0) -> Iterator[dict]:
    """Yield one dict per (count, case): ``bench`` = "gpu_sort", ``device``,
    ``pairs``, ``case``, ``ms``, ``pairs_per_s``, ``over_radix`` (ms / the
    radix sort's ms of the same count), ``loadavg_1min``; radix cases add
    ``scatter`` (variant) and ``exact`` (equal to numpy's stable argsort)."""
    rng = np.random.default_rng(seed)
    with V.Device(device_name=device_name, validation=False) as dev:
        cache = V.PipelineCache(dev)
        try:
            auto = default_scatter(dev)
            modes = [auto] + [m for m in ("subgroup", "shared") if m != auto and
                              (m == "shared" or subgroup_scatter_supported(dev))]
            for n in counts:
                n = int(n)
                keys = rng.integers(0, 2**32, n, dtype=np.uint64).astype(np.uint32)
                n2 = 1 << max(int(np.ceil(np.log2(max(n, 1)))), 0)
                lines = []
                pristine = [V.Buffer(dev, 4 * n2, ("storage",), host_visible=True) for _ in range(2)]
                work = [V.Buffer(dev, 4 * n2, ("storage",)) for _ in range(2)]
                count = V.Buffer(dev, 16, ("storage",), host_visible=True)
                try:
                    padded = np.full(n2, 0xFFFFFFFF, np.uint32)
                    padded[:n] = keys
                    pristine[0].view(np.uint32)[:] = padded
                    pristine[1].view(np.uint32)[:] = np.arange(n2, dtype=np.uint32)
                    count.view(np.uint32)[:] = (n, 0, 0, 0)

                    def restore(cb):
                        for src, dst in zip(pristine, work):
                            cb.copy_buffer(src, dst, 4 * n2)
                    t0 = time.perf_counter()
                    want = np.argsort(keys, kind="stable")
                    t_stable = time.perf_counter() - t0
                    t0 = time.perf_counter()
                    np.argsort(keys)
                    t_default = time.perf_counter() - t0
                    for mode in modes:
                        s = RadixSort(dev, cache, work[0], work[1], count, capacity=n, mode=mode)
                        try:
                            ms = _gpu_times(dev, lambda cb: s.record(cb), restore, repeats)
                        finally:
                            s.destroy()
                        got = work[1].download(4 * n).view(np.uint32) if n else np.zeros(0, np.uint32)
                        lines.append({"case": "radix" if mode == auto else f"radix_{mode}", "scatter": mode,
                                      "ms": ms, "exact": bool(np.array_equal(got, want))})
                    b = BitonicSort(dev, cache, work[0], work[1])
                    try:
                        lines.append({"case": "bitonic", "ms": _gpu_times(dev, lambda cb: b.record(cb, n2),
                                                                          restore, repeats)})
                    finally:
                        b.destroy()
                    lines.append({"case": "numpy_stable", "ms": t_stable * 1e3})
                    lines.append({"case": "numpy", "ms": t_default * 1e3})
                finally:
                    for buf in (*pristine, *work, count):
                        buf.destroy()
                base = lines[0]["ms"]
                for ln in lines:
                    yield {"bench": "gpu_sort", "device": dev.name, "pairs": n, **ln, "ms": round(ln["ms"], 3),
                           "pairs_per_s": round(n / max(ln["ms"] * 1e-3, 1e-12)),
                           "over_radix": round(ln["ms"] / max(base, 1e-9), 3), "loadavg_1min": load_average()}
        finally:
            cache.destroy()
