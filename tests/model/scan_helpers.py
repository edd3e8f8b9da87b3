"""Realistic defects for the scan-cleaning tests: injected outliers, cut
surfaces, sliver strips, and a surface-coverage probe."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

#: the shared scans of tests that estimate normals and sizes
SCANS = ("kitten.xyz", "hippo1.ply", "poste_france.xyz")


def inject_outliers(points, seed: int = 0, fraction: float = 0.01, far: int = 5) -> np.ndarray:
    """``points`` followed by ``fraction * n`` points uniform in the bounding
    box and ``far`` strays 0.6-1.0 bounding-box diagonals from its centre."""
    rng = np.random.default_rng(seed)
    lo, hi = points.min(axis=0), points.max(axis=0)
    diag = float(np.linalg.norm(hi - lo))
    uniform = lo + rng.random((int(fraction * len(points)), 3)) * (hi - lo)
    dirs = rng.normal(size=(far, 3))
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    strays = (lo + hi) / 2 + dirs * diag * rng.uniform(0.6, 1.0, (far, 1))
    return np.vstack([points, uniform, strays])


def spacing(points) -> float:
    """Median nearest-neighbour distance."""
    d, _ = cKDTree(points).query(points, k=2)
    return float(np.median(d[:, 1]))


def uncovered(cloud, probes, k: int = 16) -> int:
    """How many probe points project into none of the splat ellipses of their
    k nearest splat centres."""
    _, idx = cKDTree(cloud.positions).query(probes, k=k)
    covered = np.zeros(len(probes), dtype=bool)
    uu = np.einsum("ij,ij->i", cloud.u, cloud.u)
    vv = np.einsum("ij,ij->i", cloud.v, cloud.v)
    for j in range(k):
        i = idx[:, j]
        d = probes - cloud.positions[i]
        s = np.einsum("ij,ij->i", d, cloud.u[i]) / uu[i]
        t = np.einsum("ij,ij->i", d, cloud.v[i]) / vv[i]
        covered |= s * s + t * t <= 1.0
    return int((~covered).sum())


def triangle_samples(vertices, faces, per_face: int = 4, seed: int = 0) -> np.ndarray:
    """(f * per_face, 3) uniform random points of every triangle."""
    rng = np.random.default_rng(seed)
    r1, r2 = np.sqrt(rng.random((len(faces), per_face))), rng.random((len(faces), per_face))
    w = np.stack([1 - r1, r1 * (1 - r2), r1 * r2], -1)
    return np.einsum("fsk,fkd->fsd", w, vertices[faces]).reshape(-1, 3)


def cut_mesh(vertices, faces, axis: int = 1):
    """Keep the faces wholly above the median coordinate along ``axis``;
    returns the used vertices and re-indexed faces (an open border along the cut)."""
    keep = (vertices[faces][:, :, axis] > np.median(vertices[:, axis])).all(axis=1)
    f = faces[keep]
    used = np.unique(f)
    remap = np.full(len(vertices), -1)
    remap[used] = np.arange(len(used))
    return vertices[used], remap[f]


def grid_with_sliver_border(nx: int = 65, ny: int = 40, h: float = 1.0, step: int = 8,
                            lift: float = 0.25):
    """A planar (z = 0) grid mesh of spacing h whose top border is a strip of
    long sliver triangles: a sparse row of vertices (every ``step`` columns)
    ``lift * h`` above the last grid row, fanned to it (triangles about
    step/2 * h long and lift * h high, as meshing a scan's edge makes them).

    Returns vertices (n, 3), faces (f, 3) and the y of the true top border.
    """
    xs, ys = np.meshgrid(np.arange(nx) * h, np.arange(ny) * h)
    grid = np.column_stack([xs.ravel(), ys.ravel(), np.zeros(nx * ny)])

    def g(i, j):
        return i * nx + j

    faces = []
    for i in range(ny - 1):
        for j in range(nx - 1):
            faces += [[g(i, j), g(i, j + 1), g(i + 1, j + 1)], [g(i, j), g(i + 1, j + 1), g(i + 1, j)]]
    tops = list(range(0, nx, step))
    top_y = (ny - 1 + lift) * h
    top = np.column_stack([np.array(tops) * h, np.full(len(tops), top_y), np.zeros(len(tops))])
    base, last = nx * ny, ny - 1
    for t in range(len(tops) - 1):
        a, b = tops[t], tops[t + 1]
        mid = (a + b) // 2
        faces += [[g(last, c), g(last, c + 1), base + t] for c in range(a, mid)]
        faces += [[g(last, c), g(last, c + 1), base + t + 1] for c in range(mid, b)]
        faces.append([g(last, mid), base + t + 1, base + t])
    return np.vstack([grid, top]), np.asarray(faces, dtype=np.int64), top_y
