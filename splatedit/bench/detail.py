"""``splatedit bench detail``: the detail-preserving mode's cost beside the
linear and the rotation mode's, on the bumpy plane of its tests scaled up (one handle rotated
90 degrees about the bend line): precompute (fit) seconds, CPU apply ms per
frame (the rotation row also times the unfused reference apply) and the GPU
pre-pass ms (GPU timestamps, lavapipe here)."""

from __future__ import annotations

import os
import time

import numpy as np

from splatedit.deform import transform as tf
from splatedit.deform.modes import DeformationMode
from splatedit.model.cloud import SplatCloud


def bumpy_plane(nx: int, ny: int, pitch: float = 12.0, height: float = 2.5, width: float = 1.8):
    """(cloud, support, handle): a grid plane (spacing 1) with Gaussian bumps."""
    x, y = np.meshgrid(np.arange(nx, dtype=float), np.arange(ny, dtype=float), indexing="ij")
    x, y = x.ravel(), y.ravel()
    px = (x + pitch / 2) % pitch - pitch / 2
    py = (y + pitch / 2) % pitch - pitch / 2
    g = height * np.exp(-(px ** 2 + py ** 2) / (2 * width ** 2))
    tu = np.stack([np.ones_like(x), np.zeros_like(x), -g * px / width ** 2], axis=1)
    tv = np.stack([np.zeros_like(x), np.ones_like(x), -g * py / width ** 2], axis=1)
    n = np.cross(tu, tv)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    u = tu / np.linalg.norm(tu, axis=1, keepdims=True)
    v = np.cross(n, u)
    cloud = SplatCloud(np.stack([x, y, g], axis=1), 0.75 * u, 0.75 * v, name="bumpy")
    return cloud, x >= 0.2 * nx, x >= 0.8 * nx


def _ms(fn, repeats):
    fn()
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return 1e3 * float(np.median(times))


def bench_detail(sizes=((300, 300), (1000, 1000)), repeats: int = 3, gpu: bool = True):
    """Yield one dict per (size, mode): n, n_support, fit_s, decompose_s,
    apply_ms (CPU, median of 7), prepass_ms (GPU, median; NaN without --gpu);
    the rotation row also has apply_unfused_ms (the unfused reference
    :func:`~splatedit.deform.rotation.apply_rotation`, the CPU path before the
    folded one of :mod:`splatedit.deform.rotation_apply`)."""
    from splatedit.deform.basis import DeformationBasis
    from splatedit.deform.detail import DetailBasis
    for nx, ny in sizes:
        cloud, sup, handle = bumpy_plane(nx, ny)
        m = tf.rotate((0.0, 1.0, 0.0), -90.0, (0.5 * (nx - 1), 0.0, 0.0))
        fitted = {}
        for name, cls in (("linear", DeformationBasis), ("rotation", DeformationBasis),
                          ("detail", DetailBasis)):
            if cls not in fitted:      # rotation and linear share the fit
                t = time.perf_counter()
                fitted[cls] = (cls.fit(cloud, sup, [handle]), time.perf_counter() - t)
            b, fit_s = fitted[cls]
            dc = b.displacement([m], mode=DeformationMode(name))
            apply_ms = _ms(lambda: b.apply_arrays(cloud, dc), max(7, repeats))
            extra = {}
            if name == "rotation":     # before/after: the unfused reference in the same run
                from splatedit.deform.rotation import apply_rotation
                extra["apply_unfused_ms"] = round(_ms(lambda: apply_rotation(b, cloud, dc.dC, dc),
                                                      repeats), 2)
            prep = float("nan")
            if gpu:
                prep = _prepass_ms(cloud, b, dc, repeats)
            yield {"bench": "detail", "mode": name, "n": cloud.n, "n_support": int(len(b.indices)),
                   "fit_s": round(fit_s, 3), "decompose_s": round(b.stats.get("decompose_seconds", 0.0), 3),
                   "apply_ms": round(apply_ms, 2), **extra, "prepass_ms": round(prep, 2),
                   "loadavg_1min": os.getloadavg()[0]}


def _prepass_ms(cloud, basis, dc, repeats):
    from splatedit.render.camera import Camera
    from splatedit.render.splat.renderer import Renderer
    with Renderer() as r:
        r.set_cloud(cloud)
        r.set_basis(*basis.rows_for_gpu())
        if hasattr(basis, "detail_for_gpu"):
            r.set_detail(basis.indices, basis.detail_for_gpu())
        r.set_displacement(dc)
        cam = Camera.frame(*cloud.bounds(), 16 / 9)
        r.render(cam, 1280, 720)
        runs = []
        for _ in range(repeats):
            r.render(cam, 1280, 720)
            runs.append(r.last_timings_ms.get("prepass", float("nan")))
        return float(np.median(runs))
