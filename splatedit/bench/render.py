"""Renderer benchmark: per-pass GPU times (timestamp queries) of the EWA frame,
the one-pixel point floor, and the deformation overhead.

``bench_render`` yields one dict per splat count (the CLI prints each as a JSON
line).  Scene: a Fibonacci-sampled unit sphere (splat radius = sampling
spacing, ~2-3x overlap) framed to fill the view, back-face culling on,
validation off.  Times are medians over ``repeats`` frames after a warm-up.
"""

from __future__ import annotations

import time
from typing import Iterator

import numpy as np

from splatedit.model.cloud import SplatCloud
from splatedit.render.camera import Camera
from splatedit.render.renderer import Renderer


def sphere_cloud(n: int, overlap: float = 1.0) -> SplatCloud:
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = np.pi * (1.0 + 5 ** 0.5) * i
    r = np.sqrt(1.0 - z * z)
    nrm = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
    a = np.where(np.abs(nrm[:, [0]]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
    t1 = np.cross(nrm, a)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(nrm, t1)
    s = overlap * np.sqrt(4 * np.pi / n)
    return SplatCloud(nrm, t1 * s, t2 * s, None, name=f"sphere{n}")


def _basis(points: np.ndarray):
    """A smooth 4-column basis with analytic gradient (Gaussian bumps)."""
    q = np.array([[0.5, 0.5, 0.5], [-0.5, 0.3, 0.2], [0.1, -0.6, 0.4], [0.0, 0.0, -0.7]])
    diff = points[:, None, :] - q[None]
    B = np.exp(-np.einsum("nki,nki->nk", diff, diff) / 0.8)
    g = -2.0 / 0.8 * diff * B[..., None]
    return B, g[..., 0], g[..., 1], g[..., 2]


def _median_frame(r: Renderer, cam, w, h, repeats):
    r.render(cam, w, h)                          # warm-up (pipeline JIT)
    runs = []
    for _ in range(repeats):
        r.render(cam, w, h)
        runs.append(dict(r.last_timings_ms))
    return {k: float(np.median([x[k] for x in runs])) for k in runs[0]}


def bench_render(counts=(100_000, 1_000_000, 2_000_000), size=(1280, 720), repeats: int = 3,
                 device_name: str | None = None) -> Iterator[dict]:
    """Yield one dict per splat count: ms per pass and frame, splats/s, the
    point-list floor, and deformed frames (all splats / 10% in the support)."""
    w, h = size
    with Renderer(device_name=device_name, validation=False) as r:
        for n in counts:
            t0 = time.perf_counter()
            cloud = sphere_cloud(int(n))
            r.set_cloud(cloud)
            cam = Camera.frame(*cloud.bounds(), aspect=w / h, direction=(0.3, 0.4, 1.0))
            plain = _median_frame(r, cam, w, h, repeats)
            r.render_points_floor(cam, w, h)
            pts = float(np.median([r.render_points_floor(cam, w, h) for _ in range(repeats)]))
            B = _basis(cloud.positions)
            dC = np.array([[0.1, 0.2, 0.0], [0.0, -0.1, 0.1], [0.05, 0.0, 0.1], [-0.1, 0.0, 0.0]])
            r.set_basis(np.arange(n), *B)
            r.set_displacement(dC)
            full = _median_frame(r, cam, w, h, repeats)
            idx = np.arange(0, n, 10)
            r.set_basis(idx, *(m[idx] for m in B))
            r.set_displacement(dC)
            tenth = _median_frame(r, cam, w, h, repeats)
            r.clear_basis()
            yield {
                "bench": "render", "device": r.dev.name, "splats": int(n), "width": w, "height": h,
                "ms_prepass": round(plain["prepass"], 2), "ms_visibility": round(plain["visibility"], 2), "ms_attributes": round(plain["attributes"], 2),
                "ms_shading": round(plain["shading"], 2), "ms_frame": round(plain["total"], 2),
                "splats_per_s": round(n / (plain["total"] * 1e-3)),
                "ms_points_floor": round(pts, 2), "frame_over_floor": round(plain["total"] / pts, 3),
                "ms_frame_deformed_all": round(full["total"], 2),
                "deformed_all_over_plain": round(full["total"] / plain["total"], 3),
                "ms_frame_deformed_10pct": round(tenth["total"], 2),
                "deformed_10pct_over_plain": round(tenth["total"] / plain["total"], 3),
                "wall_s": round(time.perf_counter() - t0, 1),
            }
