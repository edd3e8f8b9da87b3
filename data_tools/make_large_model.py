#!/usr/bin/env python3
"""Make a large splat model for benchmarks by sampling a mesh's surface.

Points are drawn area-uniformly: a triangle is picked with probability
proportional to its area, then a uniform point in it with the square-root
barycentric map (u = 1 - sqrt(r1), v = sqrt(r1) (1 - r2), w = sqrt(r1) r2).
Normals are the barycentric interpolation of the mesh's area-weighted vertex
normals; splat sizes come from the neighbour spacing
(splatedit.model.estimate.splat_axes).  The output is a splat PLY written by
splatedit.io.write (not committed; give it a path outside the repository or
one that is git-ignored).

With ``--normals-radius`` the file is what scanner pipelines write instead
(issue 23's 10M file): x y z nx ny nz radius as float32 (28 bytes a point,
280 MB at 10M), the radius from the sample density (the spacing of a
hexagonal sampling of the same area, times SPLAT_RADIUS_FACTOR), written
in chunks without estimating anything.

Usage: python data_tools/make_large_model.py OUT.ply [--points N] [--input MESH] [--seed S]
                                             [--normals-radius]
       (default: 1,000,000 points sampled from the default bunny)
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from splatedit.data import default_model_path
from splatedit.io import read, write
from splatedit.model.cloud import SplatCloud
from splatedit.model.estimate import splat_axes
from splatedit.model.mesh import mesh_vertex_normals


def sample_surface(vertices, faces, n_points: int, seed: int = 0):
    """Area-uniform samples of a triangle mesh.

    Args:
        vertices: (n, 3) float64; faces: (f, 3) int64.
    Returns:
        points (n_points, 3) float64 and unit normals (n_points, 3) float64.
    """
    rng = np.random.default_rng(seed)
    V = np.asarray(vertices, dtype=np.float64)
    F = np.asarray(faces, dtype=np.int64)
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    cdf = np.cumsum(area)
    tri = np.minimum(np.searchsorted(cdf, rng.random(n_points) * cdf[-1], side="right"),
                     len(F) - 1)
    r1 = np.sqrt(rng.random(n_points))
    r2 = rng.random(n_points)
    wa, wb, wc = 1.0 - r1, r1 * (1.0 - r2), r1 * r2
    f = F[tri]
    pts = wa[:, None] * V[f[:, 0]] + wb[:, None] * V[f[:, 1]] + wc[:, None] * V[f[:, 2]]
    vn = mesh_vertex_normals(V, F)
    vn /= np.maximum(np.linalg.norm(vn, axis=1, keepdims=True), 1e-300)
    nrm = wa[:, None] * vn[f[:, 0]] + wb[:, None] * vn[f[:, 1]] + wc[:, None] * vn[f[:, 2]]
    ln = np.linalg.norm(nrm, axis=1, keepdims=True)
    fn = np.cross(b - a, c - a)[tri]
    nrm = np.where(ln > 1e-12, nrm / np.maximum(ln, 1e-300),
                   fn / np.maximum(np.linalg.norm(fn, axis=1, keepdims=True), 1e-300))
    return pts, nrm


def write_normals_radius_ply(path: Path, vertices, faces, n_points: int, seed: int = 0,
                             chunk: int = 1_000_000) -> int:
    """Write ``n_points`` area-uniform samples as a binary little-endian PLY
    of float32 x y z nx ny nz radius, ``chunk`` points at a time.  Returns
    the file size in bytes."""
    from splatedit.tolerances import SPLAT_RADIUS_FACTOR
    V = np.asarray(vertices, dtype=np.float64)
    F = np.asarray(faces, dtype=np.int64)
    area = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1).sum()
    radius = SPLAT_RADIUS_FACTOR * np.sqrt(2.0 * area / (np.sqrt(3.0) * n_points))
    names = ("x", "y", "z", "nx", "ny", "nz", "radius")
    head = ["ply", "format binary_little_endian 1.0", f"element vertex {n_points}"]
    head += [f"property float {p}" for p in names] + ["end_header", ""]
    with open(path, "wb") as fh:
        fh.write("\n".join(head).encode("ascii"))
        for i, lo in enumerate(range(0, n_points, chunk)):
            m = min(chunk, n_points - lo)
            pts, nrm = sample_surface(V, F, m, seed * 100_003 + i)
            arr = np.empty((m, 7), dtype="<f4")
            arr[:, :3], arr[:, 3:6], arr[:, 6] = pts, nrm, radius
            fh.write(arr.tobytes())
    return path.stat().st_size


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="area-uniform splat sampling of a mesh")
    ap.add_argument("output", type=Path)
    ap.add_argument("--points", type=int, default=1_000_000)
    ap.add_argument("--input", type=Path, default=None, help="mesh (default: the bunny)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--overwrite", action="store_true")
    ap.add_argument("--normals-radius", action="store_true",
                    help="write float32 x y z nx ny nz radius (no splat axes, no estimation)")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    mesh = read(args.input or default_model_path())
    if mesh.faces is None or not len(mesh.faces):
        raise SystemExit(f"{args.input}: not a mesh (no faces)")
    if args.normals_radius:
        if args.output.exists() and not args.overwrite:
            raise SystemExit(f"{args.output}: exists (--overwrite)")
        size = write_normals_radius_ply(args.output, mesh.positions, mesh.faces, args.points, args.seed)
        print(f"{args.output}: {args.points} points, {size} bytes, {time.perf_counter() - t0:.1f} s")
        return 0
    pts, nrm = sample_surface(mesh.positions, mesh.faces, args.points, args.seed)
    u, v = splat_axes(pts, nrm)
    cloud = SplatCloud(pts, u, v, name=f"{mesh.name} x{args.points}")
    write(args.output, cloud, overwrite=args.overwrite)
    print(f"{args.output}: {cloud.n} splats, {args.output.stat().st_size} bytes, "
          f"{time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
