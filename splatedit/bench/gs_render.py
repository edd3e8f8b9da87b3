"""Gaussian splatting renderer benchmark (``splatedit bench gaussian-render``).

Per Gaussian count: Gaussians (SH degree 3) on the splats of a
Fibonacci-sampled unit sphere (:func:`splatedit.bench.render.sphere_cloud`,
:func:`splatedit.bench.gs_scenes.gaussians_from_splats`), framed to fill
the view, validation off.  Both draw paths (quads, the compute tile
rasterizer) and the depth sorts (numpy argsort of the read-back keys, the GPU
radix sort, the bitonic sort it replaced) are measured in the same run, and
the deformation overhead with every Gaussian carrying a 4-column basis row.
Times are medians over ``repeats`` frames after a warm-up: GPU timestamps
for the passes, wall clock for the CPU sort.
"""

from __future__ import annotations

import time
from typing import Iterator

import numpy as np

from splatedit.bench.gs_scenes import gaussians_from_splats
from splatedit.errors import ParameterError
from splatedit.bench.render import smooth_basis, load_average, turned_handle_displacement, sphere_cloud
from splatedit.render.camera import Camera
from splatedit.render.gaussian.renderer import GaussianRenderer, gaussian_bounds


def _frames(r: GaussianRenderer, cam, w, h, repeats) -> dict:
    r.render(cam, w, h)                      # warm-up (pipeline JIT, first upload)
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        r.render(cam, w, h)
        t = dict(r.last_timings_ms)
        t["wall"] = (time.perf_counter() - t0) * 1e3
        t["total"] = t["prepass"] + t["sort"] + t["draw"] + t["resolve"]
        runs.append(t)
    return {k: float(np.median([x[k] for x in runs])) for k in runs[0]}


#: (path, sort) cases of one run, the first the baseline of the ratios
CASES = (("raster", "cpu"), ("raster", "gpu"), ("raster", "bitonic"), ("compute", "cpu"), ("compute", "gpu"))


def bench_gaussians(counts=(100_000, 1_000_000), size=(1280, 720), repeats: int = 3,
                    device_name: str | None = None, paths=("raster", "compute"), deform: bool = True,
                    bitonic_max: int = 1_100_000) -> Iterator[dict]:
    """Yield one dict per Gaussian count and (path, sort) case of :data:`CASES`
    whose path is in ``paths`` (the bitonic sort up to ``bitonic_max`` Gaussians), keys:

    * ``bench`` = "render_gaussians", ``device``, ``path`` ("raster": a quad
      per Gaussian; "compute": the tile rasterizer), ``sort`` ("cpu": numpy;
      "gpu": the GPU radix sort; "bitonic"), ``default`` (the renderer's
      choice on this device), ``gaussians``, ``visible``, ``width``, ``height``;
    * ``ms_prepass``, ``ms_sort``, ``ms_draw`` (quads, or every tile pass from
      the scan to the blend), ``ms_resolve``, ``ms_frame`` (their sum),
      ``ms_wall`` (the whole render call, readback included), ``sort_share``,
      ``gaussians_per_s``, ``tile_pairs`` (compute);
    * ``frame_over_first`` / ``wall_over_first``: ms_frame / ms_wall over the
      first case's of the same count (measured in the same run);
    * the first case with ``deform``: ``ms_prepass_deformed`` /
      ``deformed_prepass_over_plain`` / ``ms_frame_deformed`` /
      ``deformed_frame_over_plain`` (every Gaussian deformed: 4 basis
      columns, ~2% displacement) and ``ms_prepass_rotation`` /
      ``rotation_prepass_over_linear`` (the rotation-aware branch);
    * ``loadavg_1min``, ``wall_s`` (the case's);
    * a count the device cannot hold (lavapipe: above 2,097,152) gives one
      line with ``skipped`` (the reason) instead of its cases.
    """
    from splatedit.render.gaussian.renderer import choose_path, choose_sort
    w, h = size
    for n in counts:
        g = gaussians_from_splats(sphere_cloud(int(n), overlap=1.0), seed=0)
        lo, hi = gaussian_bounds(g)
        cam = Camera.frame(lo, hi, aspect=w / h, direction=(0.3, 0.4, 1.0))
        first = None
        for path, sort in CASES:
            if path not in paths or (sort == "bitonic" and n > bitonic_max):
                continue
            t0 = time.perf_counter()
            out = {"bench": "render_gaussians", "path": path, "sort": sort, "gaussians": int(n),
                   "width": w, "height": h}
            with GaussianRenderer(sort=sort, path=path, device_name=device_name, validation=False) as r:
                try:
                    r.set_gaussians(g)
                except ParameterError as exc:      # beyond the device's storage-buffer range
                    yield {**out, "device": r.dev.name, "skipped": str(exc)}
                    break
                m = _frames(r, cam, w, h, repeats)
                out["device"] = r.dev.name
                out["default"] = f"{choose_path(r.dev)}+{choose_sort(r.dev)}"
                out["visible"] = int(m["visible"])
                for k in ("prepass", "sort", "draw", "resolve"):
                    out[f"ms_{k}"] = round(m[k], 2)
                out["ms_frame"] = round(m["total"], 2)
                out["ms_wall"] = round(m["wall"], 2)
                out["sort_share"] = round(m["sort"] / m["total"], 3)
                out["gaussians_per_s"] = round(n / (m["total"] * 1e-3))
                if path == "compute":
                    out["tile_pairs"] = r._tiles.pairs_wanted()
                if first is None:
                    first = m
                out["frame_over_first"] = round(m["total"] / first["total"], 3)
                out["wall_over_first"] = round(m["wall"] / first["wall"], 3)
                if deform and first is m:
                    B = smooth_basis(g.positions)
                    dC = np.array([[0.1, 0.2, 0.0], [0.0, -0.1, 0.1], [0.05, 0.0, 0.1], [-0.1, 0.0, 0.0]]) * 0.2
                    r.set_basis(np.arange(n), *B)
                    r.set_displacement(dC)
                    d = _frames(r, cam, w, h, repeats)
                    out["ms_prepass_deformed"] = round(d["prepass"], 2)
                    out["deformed_prepass_over_plain"] = round(d["prepass"] / m["prepass"], 3)
                    out["ms_frame_deformed"] = round(d["total"], 2)
                    out["deformed_frame_over_plain"] = round(d["total"] / m["total"], 3)
                    # the editor's default mode: every Gaussian through the rotation-aware branch
                    # (bench render's 120-degree handle with tiny frame offsets: same culling)
                    r.set_displacement(turned_handle_displacement(dC, *g.bounds()))
                    q = _frames(r, cam, w, h, repeats)
                    out["ms_prepass_rotation"] = round(q["prepass"], 2)
                    out["rotation_prepass_over_linear"] = round(q["prepass"] / d["prepass"], 3)
            out["loadavg_1min"] = load_average()
            out["wall_s"] = round(time.perf_counter() - t0, 1)
            yield out
