"""Estimation benchmark: normals + orientation + sizes of raw points.

``bench_estimate`` yields one dict per point count: points sampled uniformly
on the bundled bunny mesh (no normals), then
:func:`splatedit.model.estimate.estimate_splats` with the time of each stage
(from its progress reports: k-NN, PCA normals, orientation, sizing), the
share of normals that agree with the normal of the face they were sampled
from (``oriented``: 1.0 is every normal outward), and on Linux the process's
peak resident memory during the estimation (``peak_rss_gb``, the sampled
points and their face normals included: the peak is reset after sampling)
and its rise above the resident memory before it, per point
(``rss_rise_bytes_per_point``; memory the process had freed before is
reused without a rise: meaningful in a fresh process, as from the CLI).  When Open3D is installed (the
optional ``bench`` extra) its ``estimate_normals`` runs on the same points in
the same run, with its default neighbourhood (30 nearest) and with ours (16),
and ``ratio_to_open3d`` is our whole estimation over its k = 16 normals alone.
"""

from __future__ import annotations

import time
from typing import Iterator

import numpy as np

from splatedit.tolerances import NORMAL_NEIGHBOURS

_STAGES = ("finding neighbours", "estimating normals", "orienting normals", "sizing splats")


def bunny_points(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """``n`` points uniform on the bundled bunny mesh and the unit normal of
    the face each came from: (n, 3) float64 each."""
    from splatedit.data import default_model_path
    from splatedit.io import read
    mesh = read(default_model_path())
    v, f = mesh.positions, mesh.faces
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    cr = np.cross(b - a, c - a)
    area = np.linalg.norm(cr, axis=1)
    rng = np.random.default_rng(seed)
    tri = rng.choice(len(f), size=n, p=area / area.sum())
    r1 = np.sqrt(rng.random(n))
    r2 = rng.random(n)
    p = (1 - r1)[:, None] * a[tri] + (r1 * (1 - r2))[:, None] * b[tri] + (r1 * r2)[:, None] * c[tri]
    return p, cr[tri] / area[tri, None]


def _rss_bytes(field: str) -> int | None:
    """``VmRSS`` / ``VmHWM`` (peak) of this process in bytes (Linux), else None."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith(field + ":"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return None


def _reset_peak_rss() -> bool:
    """Reset this process's ``VmHWM`` to its current RSS (Linux >= 4.0)."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        return True
    except OSError:
        return False


def _open3d_normals(points: np.ndarray, knn: int) -> float | None:
    try:
        import open3d as o3d
    except ImportError:
        return None
    pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points))
    t0 = time.perf_counter()
    pc.estimate_normals(search_param=o3d.geometry.KDTreeSearchParamKNN(knn=knn))
    return round(time.perf_counter() - t0, 2)


def bench_estimate(counts=(1_000_000,), open3d: bool = True) -> Iterator[dict]:
    from splatedit.model.estimate import estimate_splats
    for n in counts:
        n = int(n)
        pts, face_n = bunny_points(n)
        first: dict[str, float] = {}

        def progress(stage, fraction, first=first):
            first.setdefault(stage, time.perf_counter())

        reset = _reset_peak_rss()
        before = _rss_bytes("VmRSS")
        t0 = time.perf_counter()
        cloud = estimate_splats(pts, progress=progress)
        total = time.perf_counter() - t0
        peak = _rss_bytes("VmHWM") if reset else None
        marks = [t0] + [first.get(s, t0) for s in _STAGES[1:]] + [t0 + total]
        stages = {f"{s.split()[0]}_s": round(b - a, 2) for s, a, b in zip(_STAGES, marks, marks[1:])}
        oriented = float(np.mean(np.einsum("ij,ij->i", np.cross(cloud.u, cloud.v), face_n) > 0))
        del cloud
        line = {"case": "estimate", "points": n, "total_s": round(total, 2), **stages,
                "oriented": oriented}
        if peak is not None and before is not None:
            line["peak_rss_gb"] = round(peak / 1e9, 2)
            line["rss_rise_bytes_per_point"] = round((peak - before) / n)
        if open3d:
            o16 = _open3d_normals(pts, NORMAL_NEIGHBOURS)
            if o16 is None:
                line["open3d"] = "not installed (pip install '.[bench]')"
            else:
                line["open3d_normals_k16_s"] = o16
                line["open3d_normals_k30_s"] = _open3d_normals(pts, 30)
                line["ratio_to_open3d"] = round(total / max(o16, 1e-9), 2)
        yield line
