"""Small COPC scans for the out-of-core editor tests: a terrain with three
raised blocks (buildings), coloured, written by splatedit's own COPC writer
with small nodes so that a few tens of thousands of points make a deep tree."""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: where the terrain sits in the file (georeferenced-like coordinates)
TERRAIN_ORIGIN = np.array([512000.0, 4100000.0, 100.0])
#: the blocks: centre x, centre y (terrain units from its corner), side, height
BLOCKS = ((50.0, 60.0, 20.0, 12.0), (140.0, 120.0, 25.0, 9.0), (100.0, 40.0, 15.0, 15.0))


def terrain_points(n: int, seed: int = 0, size: float = 200.0) -> tuple[np.ndarray, np.ndarray]:
    """(n, 3) float64 file coordinates and (n, 3) uint8 colours of a rolling
    terrain ``size`` units wide with :data:`BLOCKS` raised on it."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0.0, size, (n, 2))
    z = 3.0 * np.sin(xy[:, 0] / 17.0) + 2.0 * np.cos(xy[:, 1] / 11.0)
    for cx, cy, side, h in BLOCKS:
        z[(abs(xy[:, 0] - cx) < side / 2) & (abs(xy[:, 1] - cy) < side / 2)] += h
    xyz = np.column_stack([xy, z]) + TERRAIN_ORIGIN
    col = np.column_stack([np.clip(90 + 12 * z, 0, 255), 110 + 60 * (np.sin(xy[:, 0] / 9.0) > 0),
                           np.full(n, 70.0)]).astype(np.uint8)
    return xyz, col


def terrain_copc(path: Path, n: int = 60_000, *, node_points: int = 1500, leaf_points: int = 4000,
                 seed: int = 0) -> Path:
    """Write :func:`terrain_points` as a COPC file at ``path``; returns ``path``."""
    from splatedit.io.copc import write_copc
    xyz, col = terrain_points(n, seed)
    write_copc(path, xyz, col, node_points=node_points, leaf_points=leaf_points)
    return Path(path)
