"""``splatedit bench batch``: batch conversion of scan tiles on Dask.

Synthetic tiles (:func:`terrain_tiles`: a rolling terrain with box buildings,
cut into square tiles that split buildings, positions only, so every tile
needs normals and sizes) converted

* one by one in a loop (``splatedit convert`` of each file: no halo),
* by :func:`splatedit.commands.batch.run_batch` with 1 and 2 workers, on the
  thread and on the process pool,

in the same run, and the seam check: the normals and sizes of the points
near tile borders, from the batch output, against converting the merged
cloud at once (and against the loop, which has no halo).
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

import numpy as np

#: tile side (model units, metres)
TILE_SIDE = 100.0


def _ground(x, y):
    return 3.0 * np.sin(x / 17.0) * np.cos(y / 23.0) + 0.02 * x + 0.5 * np.sin((x + 2 * y) / 7.0)


def terrain_points(nx: int, ny: int, n: int, seed: int = 0) -> np.ndarray:
    """(n, 3) float64 points of a terrain of ``nx`` x ``ny`` tiles of
    ``TILE_SIDE``: ground, and box buildings (roofs and walls) scattered
    over it, a few of them across tile borders; 1 cm of noise."""
    rng = np.random.default_rng(seed)
    w, h = nx * TILE_SIDE, ny * TILE_SIDE
    nb = max(1, int(6 * nx * ny))
    cx, cy = rng.uniform(5, w - 5, nb), rng.uniform(5, h - 5, nb)
    # some buildings centred on tile borders, so that seams cut them
    on_x = rng.random(nb) < 0.3
    cx[on_x] = np.clip(np.round(cx[on_x] / TILE_SIDE) * TILE_SIDE, 10, w - 10)
    hx, hy = rng.uniform(4, 10, nb), rng.uniform(4, 10, nb)
    top = _ground(cx, cy) + rng.uniform(5, 15, nb)
    n_wall = int(0.15 * n)
    x, y = rng.uniform(0, w, n - n_wall), rng.uniform(0, h, n - n_wall)
    z = _ground(x, y)
    for b in range(nb):                     # roofs over the footprints
        inside = (np.abs(x - cx[b]) <= hx[b]) & (np.abs(y - cy[b]) <= hy[b])
        z[inside] = np.maximum(z[inside], top[b])
    # walls: points on the four sides, by wall area
    area = 2 * (hx + hy) * (top - _ground(cx, cy))
    b = rng.choice(nb, size=n_wall, p=area / area.sum())
    t = rng.uniform(-1, 1, n_wall)
    side = rng.integers(0, 4, n_wall)
    wx = np.where(side < 2, cx[b] + t * hx[b], cx[b] + np.where(side == 2, -1, 1) * hx[b])
    wy = np.where(side < 2, cy[b] + np.where(side == 0, -1, 1) * hy[b], cy[b] + t * hy[b])
    wz = rng.uniform(_ground(wx, wy), top[b])
    pts = np.column_stack([np.concatenate([x, wx]), np.concatenate([y, wy]), np.concatenate([z, wz])])
    pts += rng.normal(scale=0.01, size=pts.shape)
    keep = (pts[:, 0] >= 0) & (pts[:, 0] < w) & (pts[:, 1] >= 0) & (pts[:, 1] < h)
    return pts[keep]


def terrain_tiles(folder, nx: int = 5, ny: int = 2, points_per_tile: int = 200_000, *, ext: str = ".las",
                  seed: int = 0) -> tuple[list[Path], np.ndarray]:
    """Write the terrain as ``nx * ny`` tile files ``tile_IX_IY<ext>``
    (``.las`` or ``.xyz``) into ``folder``.  Returns (paths, (n, 3) all
    points in tile order)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    pts = terrain_points(nx, ny, nx * ny * points_per_tile, seed)
    ix = np.minimum((pts[:, 0] // TILE_SIDE).astype(int), nx - 1)
    iy = np.minimum((pts[:, 1] // TILE_SIDE).astype(int), ny - 1)
    paths, parts = [], []
    for j in range(ny):
        for i in range(nx):
            p = pts[(ix == i) & (iy == j)]
            path = folder / f"tile_{i}_{j}{ext}"
            if ext == ".xyz":
                np.savetxt(path, p, fmt="%.4f")
                p = np.loadtxt(path).reshape(-1, 3)                # as stored (0.1 mm decimals)
            else:
                import laspy
                hdr = laspy.LasHeader(point_format=0, version="1.2")
                hdr.scales = np.array([0.0001, 0.0001, 0.0001])
                hdr.offsets = np.floor(p.min(axis=0))
                las = laspy.LasData(hdr)
                las.x, las.y, las.z = p[:, 0], p[:, 1], p[:, 2]
                las.write(str(path))
                p = np.column_stack([las.x, las.y, las.z]).astype(np.float64)   # as stored (0.1 mm grid)
            paths.append(path)
            parts.append(p)
    return paths, np.concatenate(parts)


def _frames(cloud) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """World positions, unit normals and radii of a written tile."""
    nrm = np.cross(cloud.u, cloud.v)
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    return cloud.positions + cloud.origin, nrm, np.linalg.norm(cloud.u, axis=1)


def seam_check(outputs: list[Path], merged_points: np.ndarray, *, border: float) -> dict:
    """Compare the splats of points within ``border`` of an inner tile
    border with those of the merged cloud estimated at once.

    Returns:
        points compared, the largest normal angle (degrees, sign ignored),
        the fraction of opposite normals, the largest and 99th percentile
        relative radius difference and the fraction of radii that differ by
        more than 1e-6 (relative).
    """
    from scipy.spatial import cKDTree
    from splatedit.io import read
    from splatedit.model.estimate import estimate_splats
    merged = estimate_splats(merged_points)
    m_pos, m_nrm, m_rad = _frames(merged)
    tree = cKDTree(m_pos)
    w = merged_points[:, 0].max()
    h = merged_points[:, 1].max()
    pos, nrm, rad = [], [], []
    for out in outputs:
        p, nn, r = _frames(read(out))
        pos.append(p)
        nrm.append(nn)
        rad.append(r)
    pos, nrm, rad = np.concatenate(pos), np.concatenate(nrm), np.concatenate(rad)
    fx = np.abs(pos[:, 0] - np.round(pos[:, 0] / TILE_SIDE) * TILE_SIDE)
    fy = np.abs(pos[:, 1] - np.round(pos[:, 1] / TILE_SIDE) * TILE_SIDE)
    inner_x = (pos[:, 0] > border) & (pos[:, 0] < w - border)
    inner_y = (pos[:, 1] > border) & (pos[:, 1] < h - border)
    near = ((fx < border) & inner_x) | ((fy < border) & inner_y)
    d, j = tree.query(pos[near])
    dots = np.einsum("ij,ij->i", nrm[near], m_nrm[j])
    ang = np.degrees(np.arccos(np.clip(np.abs(dots), 0, 1)))
    rel = np.abs(rad[near] - m_rad[j]) / m_rad[j]
    return {"seam_points": int(near.sum()), "match_dist_max": float(d.max()) if len(d) else 0.0,
            "normal_deg_max": float(ang.max()) if len(ang) else 0.0,
            "normal_flipped_frac": float(np.mean(dots < 0)) if len(dots) else 0.0,
            "radius_rel_max": float(rel.max()) if len(rel) else 0.0,
            "radius_rel_p99": float(np.quantile(rel, 0.99)) if len(rel) else 0.0,
            "radius_differs_frac": float(np.mean(rel > 1e-6)) if len(rel) else 0.0}


def _cpu() -> float:
    """CPU seconds (user + system) of this process and its reaped children
    (the process pool's workers are reaped when each run closes its pool)."""
    import resource
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def bench_batch(nx: int = 5, ny: int = 2, points_per_tile: int = 200_000, *, ext: str = ".las",
                workers=(1, 2), schedulers=("threads", "processes"), seam: bool = True, rounds: int = 2):
    """Yield one dict per case: the loop, each scheduler x worker count
    (``rounds`` times each, in turn), and the seam checks (batch with halo,
    loop without) against the merged cloud."""
    from splatedit.io import convert
    from splatedit.io.batch import BatchOptions, plan_jobs, run_batch
    from splatedit.tolerances import TILE_HALO_NEIGHBOURHOODS
    with tempfile.TemporaryDirectory(prefix="splatedit-bench-batch-") as tmp:
        tmp = Path(tmp)
        paths, merged = terrain_tiles(tmp / "tiles", nx, ny, points_per_tile, ext=ext)
        base = {"bench": "batch", "tiles": len(paths), "points": int(len(merged)), "format": ext,
                "cores": os.cpu_count()}
        # rounds of every case in turn (the machine's load drifts: a ratio is
        # taken within one round; the median over the rounds is reported too)
        runs: dict = {}
        last = loop_dir = None
        for rnd in range(rounds):
            loop_dir = tmp / f"loop{rnd}"
            loop_dir.mkdir()
            t0, c0 = time.perf_counter(), _cpu()
            for p in paths:
                convert(p, loop_dir / (p.stem + ".ply"))          # what `splatedit convert FILE OUT` does
            loop_s, loop_cpu = time.perf_counter() - t0, _cpu() - c0
            runs.setdefault(("loop", 0), []).append((loop_s, loop_s, 0, os.getloadavg()[0], loop_cpu))
            for sched in schedulers:
                for nw in workers:
                    out = tmp / f"dask-{sched}-{nw}-{rnd}"
                    jobs = plan_jobs(paths, out, ".ply", overwrite=False)
                    t0, c0 = time.perf_counter(), _cpu()
                    res = run_batch(jobs, BatchOptions(scheduler=sched, workers=nw))
                    s, cpu = time.perf_counter() - t0, _cpu() - c0
                    assert all(r.error is None for r in res), [r.error for r in res if r.error]
                    runs.setdefault((sched, nw), []).append((s, loop_s, sum(r.halo for r in res),
                                                             os.getloadavg()[0], cpu))
                    last = [j.out for j in jobs]
        for (sched, nw), rows in runs.items():
            secs = [r[0] for r in rows]
            line = {**base, "case": "loop (convert per file, no halo)" if sched == "loop" else f"dask {sched}",
                    "seconds_median": round(float(np.median(secs)), 3), "seconds": [round(s, 3) for s in secs],
                    "cpu_seconds": [round(r[4], 2) for r in rows], "load_avg_1m": [round(r[3], 2) for r in rows]}
            if sched != "loop":
                ratios = [r[0] / r[1] for r in rows]
                line.update(workers=nw, vs_loop_same_round=[round(x, 3) for x in ratios],
                            vs_loop_median=round(float(np.median(ratios)), 3), halo_points=int(rows[0][2]))
            yield line
        if seam and last is not None:
            from splatedit.io.batch import load_tile
            reach = load_tile(str(paths[0])).reach
            border = 2.0 * reach
            yield {**base, "case": "seam: batch (halo) vs merged", "halo_neighbourhoods": TILE_HALO_NEIGHBOURHOODS,
                   "border_m": round(border, 3), **seam_check(last, merged, border=border)}
            yield {**base, "case": "seam: loop (no halo) vs merged", "border_m": round(border, 3),
                   **seam_check(sorted(loop_dir.iterdir()), merged, border=border)}

