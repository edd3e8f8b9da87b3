"""Large-model renderer benchmark: upload, full frame and level-of-detail build.

``bench_upload_lod`` gives one dict for an ``n``-splat Fibonacci sphere (the
scene of :mod:`splatedit.bench.render`) rendered at ``size``:

* ``upload_s``: :meth:`Renderer.set_cloud` (float32 conversion + chunked
  staging upload) wall time;
* ``first_frame_s`` / ``frame_s``: wall time of the first full-quality frame
  (pipeline creation included) and of a second one; ``frame_gpu_ms``: the
  second frame's GPU timestamps (``prepass``, passes, ``total``);
* ``lod_build_s`` and the level sizes of :class:`~splatedit.model.lod.LodPyramid`
  with the default budgets; ``lod_frame_s``: a frame of the finest level
  (at most 400k splats: what the editor draws while moving);
* ``lod_rate_s_per_m``: LOD build seconds per million splats.

Validation is off.  lavapipe shares the CPU: compare the ratios in one run.
"""

from __future__ import annotations

import time

from splatedit.bench.render import sphere_cloud
from splatedit.model.lod import LodPyramid
from splatedit.render.camera import Camera
from splatedit.render.splat.renderer import Renderer


def bench_upload_lod(n: int, size=(1280, 720), cloud=None) -> dict:
    w, h = size
    cloud = sphere_cloud(n) if cloud is None else cloud
    cam = Camera.frame(*cloud.bounds(), aspect=w / h, direction=(0.3, 0.4, 1.0))
    out = {"case": "upload_frame_lod", "splats": cloud.n, "width": w, "height": h}
    with Renderer(validation=False) as r:
        t0 = time.perf_counter()
        r.set_cloud(cloud)
        out["upload_s"] = round(time.perf_counter() - t0, 2)
        t0 = time.perf_counter()
        r.render(cam, w, h)
        out["first_frame_s"] = round(time.perf_counter() - t0, 2)
        t0 = time.perf_counter()
        r.render(cam, w, h)
        out["frame_s"] = round(time.perf_counter() - t0, 2)
        out["frame_gpu_ms"] = {k: round(v, 1) for k, v in r.last_timings_ms.items()}
        out["prepass"] = r.use_prepass()
        out["prepass_windows"] = r.prepass_windows
        t0 = time.perf_counter()
        pyr = LodPyramid(cloud)
        lod_s = time.perf_counter() - t0
        out["lod_build_s"] = round(lod_s, 2)
        out["lod_rate_s_per_m"] = round(lod_s / (cloud.n / 1e6), 2)
        out["lod_levels"] = [lvl.n for lvl in pyr.levels]
        lvl = pyr.levels[0] if pyr.levels else None
        if lvl is not None:
            r.set_cloud(lvl.cloud)
            r.render(cam, w, h)
            t0 = time.perf_counter()
            r.render(cam, w, h)
            out["lod_frame_s"] = round(time.perf_counter() - t0, 2)
            out["lod_frame_splats"] = lvl.n
    return out
