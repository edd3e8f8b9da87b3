"""Cost of the default view's parts on a synthetic unit sphere of N splats,
clean and with 1 % of its points moved 30 radii out (median of 3, seconds):
the main-body extent (splatedit.model.extent), the bounding box it replaces,
the up-axis detection from the normals, and the whole default camera.

    PYTHONPATH=$PWD .venv/bin/python scripts/bench_framing.py [N ...]
"""

from __future__ import annotations

import statistics
import sys
import time

import numpy as np

from splatedit.model.cloud import SplatCloud
from splatedit.model.extent import framing_extent
from splatedit.model.orientation import detect_up_axis
from splatedit.render.framing import default_view


def _sphere(n: int, far: float) -> SplatCloud:
    rng = np.random.default_rng(0)
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    a = np.cross(p, [0.3, 0.5, 0.8])
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    b = np.cross(p, a)
    p[: int(far * n)] *= 30.0
    return SplatCloud(p, a * 1e-3, b * 1e-3, values_checked=True)


def _median(f) -> float:
    times = []
    for _ in range(3):
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def main(counts) -> None:
    for n in counts:
        for far in (0.0, 0.01):
            c = _sphere(n, far)
            row = {"splats": n, "far_fraction": far,
                   "extent_s": _median(lambda: framing_extent(c.positions)),
                   "bounds_s": _median(c.bounds),
                   "up_from_normals_s": _median(lambda: detect_up_axis(c.normals, c.positions)),
                   "default_view_s": _median(lambda: default_view(c, (1280, 720)))}
            print({k: round(v, 3) if isinstance(v, float) else v for k, v in row.items()}, flush=True)


if __name__ == "__main__":
    main([int(x) for x in sys.argv[1:]] or [1_000_000, 4_000_000])
