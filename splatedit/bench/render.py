"""Renderer benchmark: per-pass GPU times (timestamp queries) of the EWA frame,
the one-pixel point floor, and the deformation overhead.

``bench_render`` yields one dict per case (the CLI prints each as a JSON
line; keys in its docstring): a Fibonacci-sampled unit sphere per splat count
(splat radius = sampling spacing, ~2-3x overlap) framed to fill the view,
then the bundled bunny model; back-face culling on, validation off.  Times
are GPU timestamps, medians (and best) over ``repeats`` frames after a warm-up.
lavapipe shares the CPU with everything else on the machine: compare
``frame_over_floor`` (both measured in the same run) rather than raw times.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Iterator

import numpy as np

from splatedit.model.cloud import SplatCloud
from splatedit.render.camera import Camera
from splatedit.render.splat.renderer import Renderer


def fibonacci_sphere(n: int, start: int = 0, stop: int | None = None):
    """Points ``start..stop`` of an ``n``-point Fibonacci sphere (unit radius):
    ``(normals, t1, t2)``, each (stop - start, 3) float64 (the points are the
    normals; t1, t2 unit tangents)."""
    i = np.arange(start, n if stop is None else stop) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = np.pi * (1.0 + 5 ** 0.5) * i
    r = np.sqrt(1.0 - z * z)
    nrm = np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)
    a = np.where(np.abs(nrm[:, [0]]) < 0.9, np.array([[1.0, 0, 0]]), np.array([[0, 1.0, 0]]))
    t1 = np.cross(nrm, a)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    return nrm, t1, np.cross(nrm, t1)


def sphere_cloud(n: int, overlap: float = 1.0) -> SplatCloud:
    nrm, t1, t2 = fibonacci_sphere(n)
    s = overlap * np.sqrt(4 * np.pi / n)
    return SplatCloud(nrm, t1 * s, t2 * s, None, name=f"sphere{n}")


def smooth_basis(points: np.ndarray):
    """A smooth 4-column basis with analytic gradient (Gaussian bumps)."""
    q = np.array([[0.5, 0.5, 0.5], [-0.5, 0.3, 0.2], [0.1, -0.6, 0.4], [0.0, 0.0, -0.7]])
    diff = points[:, None, :] - q[None]
    B = np.exp(-np.einsum("nki,nki->nk", diff, diff) / 0.8)
    g = -2.0 / 0.8 * diff * B[..., None]
    return B, g[..., 0], g[..., 1], g[..., 2]


def turned_handle_displacement(dC, lo, hi):
    """``dC`` as the residual of one handle turned by 120 degrees about a tilted
    axis: every splat takes the rotation branch of the pre-pass (all its
    math, closed forms), while the frame offsets are small (1e-3 of the model)
    so that the deformed geometry, and with it culling and the record writes,
    stays that of the linear case the ratio is taken against."""
    from splatedit.deform.rotation import HandleRotation, RotationDisplacement
    size = float(np.max(hi - lo))
    axis = np.array([0.3, 1.0, 0.2]) / np.linalg.norm([0.3, 1.0, 0.2])
    offsets = 1e-3 * size * (np.vstack([[0.0, 0.0, 0.0], np.eye(3)]) + 0.5)
    rot = HandleRotation(axis * np.radians(120.0), 0.5 * (lo + hi), offsets)
    return RotationDisplacement(np.asarray(dC, dtype=np.float64), (rot,))


def _frames(r: Renderer, cam, w, h, repeats):
    """(median, best) per-pass GPU times over ``repeats`` frames after a warm-up."""
    r.render(cam, w, h)                          # warm-up (pipeline JIT)
    runs = []
    for _ in range(repeats):
        r.render(cam, w, h)
        runs.append(dict(r.last_timings_ms))
    med = {k: float(np.median([x[k] for x in runs])) for k in runs[0]}
    best = min(runs, key=lambda x: x["total"])
    return med, best


def _point_share(r: Renderer) -> float:
    """Share of the drawn splats of the last frame on the square-point path."""
    if r.prepass_part.current is None:
        return float("nan")
    d = r.prepass_part.current.draws.read().view(np.uint32)
    return float(d[5]) / max(int(d[1]) + int(d[5]), 1)


def _paths(r: Renderer, cam, w: int, h: int, repeats: int) -> dict:
    """Both rasterization paths of the plain frame in the same run, alternating
    (raster, compute, raster, ...) so that machine load hits both alike: the
    compute path's keys, its ratio to the raster path and how far apart their
    images are (RGB, 8-bit levels; coverage = non-background pixels)."""
    saved = r.raster_path
    frames = {"raster": [], "compute": []}
    images = {}
    try:
        for p in ("raster", "compute"):
            r.raster_path = p
            images[p] = r.render(cam, w, h)               # warm-up, and the compared image
        for _ in range(repeats):
            for p in ("raster", "compute"):
                r.raster_path = p
                r.render(cam, w, h)
                frames[p].append(dict(r.last_timings_ms))
        r.raster_path = "compute"
        ran_compute = r.frame_path(w, h)
    finally:
        r.raster_path = saved
    med = {p: float(np.median([x["total"] for x in v])) for p, v in frames.items()}
    best = {p: float(min(x["total"] for x in v)) for p, v in frames.items()}
    a, b = (images[p][..., :3].astype(np.int16) for p in ("raster", "compute"))
    diff = np.abs(a - b)
    bg = np.array([round(255 * c) for c in r.background[:3]], np.int16)
    cov_a, cov_b = (np.any(x != bg, axis=2) for x in (a, b))
    cmed = {k: float(np.median([x[k] for x in frames["compute"]])) for k in frames["compute"][0]}
    return {
        "path_compute_ran": ran_compute,
        "ms_frame_raster": round(med["raster"], 2), "ms_frame_compute": round(med["compute"], 2),
        "compute_over_raster": round(med["compute"] / med["raster"], 3),
        "compute_over_raster_best": round(best["compute"] / best["raster"], 3),
        "ms_compute_visibility": round(cmed.get("visibility", float("nan")), 2),
        "ms_compute_attributes": round(cmed.get("attributes", float("nan")), 2),
        "image_mean_diff": round(float(diff.mean()), 4), "image_max_diff": int(diff.max()),
        "image_bad_share": round(float((diff.max(axis=2) > 24).mean()), 5),
        "coverage_raster": int(cov_a.sum()), "coverage_compute": int(cov_b.sum()),
        "coverage_mismatch": int((cov_a != cov_b).sum()),
    }


def _case(r: Renderer, cloud: SplatCloud, model: str, w: int, h: int, repeats: int,
          deform: bool = True) -> dict:
    t0 = time.perf_counter()
    n = cloud.n
    r.set_cloud(cloud)
    cam = Camera.frame(*cloud.bounds(), aspect=w / h, direction=(0.3, 0.4, 1.0))
    paths = _paths(r, cam, w, h, repeats)
    plain, plain_best = _frames(r, cam, w, h, repeats)
    share = _point_share(r)
    r.render_points_floor(cam, w, h)
    floors = [r.render_points_floor(cam, w, h) for _ in range(repeats)]
    pts, pts_best = float(np.median(floors)), float(min(floors))
    out = {
        "bench": "render", "model": model, "device": r.dev.name, "path": r.frame_path(w, h),
        "splats": int(n), "width": w, "height": h, **paths,
        "ms_prepass": round(plain["prepass"], 2), "ms_visibility": round(plain["visibility"], 2),
        "ms_attributes": round(plain["attributes"], 2),
        "ms_shading": round(plain["shading"], 2), "ms_frame": round(plain["total"], 2),
        "splats_per_s": round(n / (plain["total"] * 1e-3)),
        "ms_points_floor": round(pts, 2), "frame_over_floor": round(plain["total"] / pts, 3),
        "ms_frame_best": round(plain_best["total"], 2), "ms_points_floor_best": round(pts_best, 2),
        "frame_over_floor_best": round(plain_best["total"] / pts_best, 3),
        "point_path_share": round(share, 4),
    }
    if deform:
        out.update(_deformed(r, cloud, cam, w, h, repeats, plain, plain_best))
    out["loadavg_1min"] = load_average()
    out["wall_s"] = round(time.perf_counter() - t0, 1)
    return out


def _deformed(r: Renderer, cloud: SplatCloud, cam, w: int, h: int, repeats: int, plain, plain_best) -> dict:
    """The deformation cases of :func:`bench_render` (default path)."""
    n = cloud.n
    lo, hi = cloud.bounds()
    B = smooth_basis((cloud.positions - 0.5 * (lo + hi)) / max(float(np.max(hi - lo)) / 2.0, 1e-12))
    dC = np.array([[0.1, 0.2, 0.0], [0.0, -0.1, 0.1], [0.05, 0.0, 0.1], [-0.1, 0.0, 0.0]])
    dC = dC * 0.1 * float(np.max(hi - lo))
    r.set_basis(np.arange(n), *B)
    r.set_displacement(dC)
    full, full_best = _frames(r, cam, w, h, repeats)
    r.distortion_map = True
    try:
        heat, heat_best = _frames(r, cam, w, h, repeats)
    finally:
        r.distortion_map = False
    # the same basis as one rotation-aware handle turned 120 degrees (rotation.glsl)
    r.set_displacement(turned_handle_displacement(dC, lo, hi))
    rot, rot_best = _frames(r, cam, w, h, repeats)
    # a contiguous support region: the 10% of the splats nearest to one point
    d2 = np.sum((cloud.positions - cloud.positions[0]) ** 2, axis=1)
    idx = np.sort(np.argpartition(d2, max(n // 10 - 1, 0))[:max(n // 10, 1)])
    r.set_basis(idx, *(m[idx] for m in B))
    r.set_displacement(dC)
    tenth, tenth_best = _frames(r, cam, w, h, repeats)
    r.clear_basis()
    return {
        "ms_frame_deformed_all": round(full["total"], 2),
        "deformed_all_over_plain": round(full["total"] / plain["total"], 3),
        "ms_frame_deformed_10pct": round(tenth["total"], 2),
        "deformed_10pct_over_plain": round(tenth["total"] / plain["total"], 3),
        "deformed_all_over_plain_best": round(full_best["total"] / plain_best["total"], 3),
        "ms_prepass_deformed_all": round(full["prepass"], 2),
        "ms_prepass_heat_map": round(heat["prepass"], 2),
        "ms_frame_heat_map": round(heat["total"], 2),
        "heat_map_over_deformed_prepass": round(heat["prepass"] / full["prepass"], 3),
        "heat_map_over_deformed_prepass_best": round(heat_best["prepass"] / full_best["prepass"], 3),
        "ms_prepass_rotation_all": round(rot["prepass"], 2),
        "rotation_over_deformed_prepass": round(rot["prepass"] / full["prepass"], 3),
        "rotation_over_deformed_prepass_best": round(rot_best["prepass"] / full_best["prepass"], 3),
        "deformed_10pct_over_plain_best": round(tenth_best["total"] / plain_best["total"], 3),
    }


def load_average() -> float:
    """The 1-minute load average (/proc/loadavg), NaN where it cannot be read."""
    try:
        with open("/proc/loadavg") as f:
            return float(f.read().split()[0])
    except (OSError, ValueError, IndexError):
        return float("nan")


def bench_render(counts=(100_000, 1_000_000, 2_000_000), size=(1280, 720), repeats: int = 3,
                 device_name: str | None = None, bunny: bool = True, models=(),
                 deform_max: int = 2_000_000) -> Iterator[dict]:
    """Yield one dict per case: a sphere per splat count in ``counts``, then
    (``bunny``) the bundled bunny model (``splatedit.data.default_model_path()``
    read with :func:`splatedit.io.read`) and every file of ``models`` (e.g. a
    real scan), all at ``size``.

    Every case has these keys (times in ms are GPU timestamps; "median"
    and "best" are over ``repeats`` frames after a warm-up frame):

    * ``bench`` = "render", ``model`` ("sphere" / "bunny" / the file name),
      ``device``, ``path`` (the default path's, "raster" / "compute", which
      the other per-pass keys measure), ``splats``, ``width``, ``height``;
    * both paths of the plain frame in the same run (alternating frames):
      ``ms_frame_raster``, ``ms_frame_compute`` (medians),
      ``compute_over_raster`` (and ``_best``: the fastest frames),
      ``path_compute_ran`` (what the compute request drew: "raster" where the
      device cannot), ``ms_compute_visibility``, ``ms_compute_attributes``;
      their images: ``image_mean_diff``, ``image_max_diff`` (RGB levels),
      ``image_bad_share`` (share of pixels off by more than 24 levels),
      ``coverage_raster``, ``coverage_compute``, ``coverage_mismatch``
      (non-background pixels, and pixels covered by one path only);
    * ``ms_prepass``, ``ms_visibility``, ``ms_attributes``, ``ms_shading``,
      ``ms_frame``: median per pass and whole frame (undeformed, default path);
    * ``splats_per_s``: splats / median frame time;
    * ``ms_points_floor``: median one-pixel POINT_LIST floor
      (:meth:`Renderer.render_points_floor`); ``frame_over_floor`` = ms_frame
      / ms_points_floor;
    * ``ms_frame_best``, ``ms_points_floor_best``, ``frame_over_floor_best``:
      the same with the fastest frame of each (less sensitive to machine load);
    * ``point_path_share``: share of the drawn splats on the square-point path;
    * ``loadavg_1min``: /proc/loadavg at the end of the case (NaN elsewhere);
    * ``wall_s``: wall-clock seconds of the case.

    Cases of at most ``deform_max`` splats (they hold a full basis) add, on
    the default path:

    * ``ms_frame_deformed_all`` / ``deformed_all_over_plain``: median frame
      with every splat carrying a 4-column basis row (Gaussian bumps,
      displacement ~2% of the model size), and its ratio to ``ms_frame``;
    * ``ms_frame_deformed_10pct`` / ``deformed_10pct_over_plain``: the same
      with a contiguous support of 10% of the splats (the nearest to one splat);
    * ``deformed_all_over_plain_best``, ``deformed_10pct_over_plain_best``:
      the ratios of the fastest frames;
    * ``ms_prepass_deformed_all`` / ``ms_prepass_heat_map`` / ``ms_frame_heat_map``:
      median pre-pass (and frame) with every splat deformed, without and with
      the distortion heat map (``Renderer.distortion_map``: the per-splat
      stretch in the pre-pass); ``heat_map_over_deformed_prepass`` (and
      ``_best``) their ratio;
    * ``ms_prepass_rotation_all`` / ``rotation_over_deformed_prepass`` (and
      ``_best``): the pre-pass with the same basis as a rotation-aware handle
      turned 120 degrees (``DeformationMode.ROTATION``), over the linear one.
    """
    w, h = size
    with Renderer(device_name=device_name, validation=False) as r:
        for n in counts:
            yield _case(r, sphere_cloud(int(n)), "sphere", w, h, repeats, deform=int(n) <= deform_max)
        from splatedit.io import read
        if bunny:
            from splatedit.data import default_model_path
            yield _case(r, read(default_model_path()), "bunny", w, h, repeats)
        for path in models:
            cloud = read(path)
            yield _case(r, cloud, Path(path).name, w, h, repeats, deform=cloud.n <= deform_max)
