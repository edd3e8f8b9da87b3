"""Exact k nearest neighbours of a large cloud, tile by tile.

One k-d tree over a 10M-point cloud is a large object next to the points
(its index array and nodes), and its query runs one thread pool over the
whole cloud while everything around it (tree build, gathers) is serial.
:func:`tiled_knn` instead

1. sorts the points along a Z-order curve (:func:`splatedit.model.pca.morton_codes`)
   and cuts the curve into the cells of an octree level whose cells hold about
   ``TILE_CELL_POINTS`` points on average (a cell is a contiguous run of the
   sorted points);
2. groups consecutive cells into tiles of about ``TILE_POINTS`` points; for
   every tile it builds a small ``cKDTree`` over the tile's cells and their
   occupied neighbour cells (the 26 around each, the halo) and queries the
   tile's points;
3. keeps a point's answer only when it is provably exact: every point that
   is not in the tree lies outside the 3x3x3 cells around the query's own
   cell, at least ``cell + wall`` away (``wall``: the distance to the nearest
   face of its own cell), so a k-th distance below that bound is exact (ties
   aside).  The few points that fail (points near a cell wall, sparse
   regions) are queried again on the next coarser octree level (cells twice
   as large); what is still left after ``TILE_RETRY_LEVELS`` levels (strays
   far from the surface, whose coarse 3x3x3 blocks would hold most of the
   surface) is queried against one tree over all points.

Memory is the (n, k) int32 index table and the (n, kd) float32 distance
columns asked for, plus one small tree per thread; the tiles run on a thread
pool (tree build and query release the GIL).  The CPU time equals one global
tree's (10M bunny points, k = 16, same session: 28.0 s tiled, 26.7 s
global): the deep tree's queries are not slower per point on this machine;
the halo costs 26% more tree points (see docs/PERFORMANCE.md, "10M raw
points").
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from splatedit.model.pca import interleave
from splatedit.progress import report
from splatedit.tolerances import TILE_CELL_POINTS, TILE_EXACT_MARGIN_REL, TILE_POINTS, TILE_RETRY_LEVELS

_BITS = 21
#: the 27 offsets of a cell's 3x3x3 block
_OFFSETS = np.stack(np.meshgrid([-1, 0, 1], [-1, 0, 1], [-1, 0, 1], indexing="ij"), -1).reshape(-1, 3)


@dataclass(frozen=True)
class CellGrid:
    """The occupied cells of one octree level over Morton-sorted points.

    Attributes:
        level: octree level (cells are ``2^(21 - level)`` grid steps wide).
        key: (c,) uint64 sorted Morton codes of the occupied cells.
        start: (c + 1,) int64; cell j holds sorted points ``start[j]:start[j+1]``.
        width: cell edge in model units.
    """
    level: int
    key: np.ndarray
    start: np.ndarray
    width: float

    @property
    def counts(self) -> np.ndarray:
        """(c,) int64 points per cell."""
        return np.diff(self.start)

    def coords(self, cells) -> np.ndarray:
        """(m, 3) int64 integer coordinates of cells ``cells`` ((m,) int)."""
        key = self.key[np.asarray(cells)]
        out = np.zeros((len(key), 3), dtype=np.int64)
        for b in range(self.level):
            for a in range(3):
                out[:, a] |= ((key >> np.uint64(3 * b + a)) & np.uint64(1)).astype(np.int64) << b
        return out

    def neighbourhood(self, cells) -> np.ndarray:
        """Sorted unique indices of the occupied cells in the 3x3x3 blocks
        around ``cells`` ((m,) int, themselves included)."""
        c = self.coords(cells)
        nb = (c[:, None, :] + _OFFSETS[None]).reshape(-1, 3)
        ok = np.all((nb >= 0) & (nb < (1 << self.level)), axis=1)
        return _found(self.key, np.unique(interleave(nb[ok])))


def _found(sorted_keys: np.ndarray, keys: np.ndarray) -> np.ndarray:
    """Indices into ``sorted_keys`` of those of ``keys`` (sorted, unique) present."""
    pos = np.searchsorted(sorted_keys, keys)
    inside = pos < len(sorted_keys)
    pos, keys = pos[inside], keys[inside]
    return pos[sorted_keys[pos] == keys]


def cell_grid(codes: np.ndarray, level: int, scale: float) -> CellGrid:
    """Cells of octree ``level`` over sorted Morton ``codes`` ((n,) uint64,
    ascending) on a grid of ``scale`` steps per model unit."""
    shift = np.uint64(3 * (_BITS - level))
    key = codes >> shift
    brk = np.flatnonzero(key[1:] != key[:-1]) + 1
    start = np.concatenate([[0], brk, [len(codes)]]).astype(np.int64)
    width = float(2 ** (_BITS - level) / scale) if scale > 0 else np.inf
    return CellGrid(level, key[start[:-1]], start, width)


def fine_level(codes: np.ndarray, cell_points: float = TILE_CELL_POINTS) -> int:
    """The octree level whose occupied cells hold about ``cell_points``
    points on average (the first level at or below it)."""
    n = len(codes)
    for level in range(1, _BITS + 1):
        key = codes >> np.uint64(3 * (_BITS - level))
        cells = 1 + int(np.count_nonzero(key[1:] != key[:-1]))
        if n / cells <= cell_points:
            return level
    return _BITS


def _ranges(start: np.ndarray, cells: np.ndarray) -> np.ndarray:
    """Concatenated point indices ``start[c]:start[c+1]`` of ``cells``."""
    lo, hi = start[cells], start[cells + 1]
    ln = hi - lo
    off = np.repeat(lo - np.concatenate([[0], np.cumsum(ln)[:-1]]), ln)
    return off + np.arange(int(ln.sum()))


@dataclass
class TiledKnnStats:
    """What :func:`tiled_knn` did: ``level`` of the fine cells, ``tiles``,
    ``tree_points`` (points in all trees, halos included: the tiles' overhead
    is ``tree_points / n - 1``), ``retried`` (queries redone on coarser
    levels), ``global_queries`` (those left to one tree over all points)."""
    level: int = 0
    tiles: int = 0
    tree_points: int = 0
    retried: int = 0
    global_queries: int = 0


def tiled_knn(points, codes, lo, scale: float, k: int, *, dist_columns: int | None = None,
              tile_points: int = TILE_POINTS, cell_points: float = TILE_CELL_POINTS,
              retry_levels: int = TILE_RETRY_LEVELS,
              threads: int = -1, progress=None, stats: TiledKnnStats | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Exact k nearest neighbours (the point itself included) of Morton-sorted points.

    Args:
        points: (n, 3) float64 positions sorted by ``codes``.
        codes: (n,) uint64 ascending Morton codes of ``points`` from
            :func:`splatedit.model.pca.morton_codes` (``lo``, ``scale`` from
            there too: (3,) float64 grid corner, grid steps per model unit).
        k: neighbours per point, clamped to n.
        dist_columns: keep this many leading distance columns (default k).
        threads: tiles processed at once (-1: one per CPU); each tile's tree
            is built and queried without the GIL.
        retry_levels: coarser octree levels on which inexact answers are
            retried before the rest go to one tree over all points.
    Returns:
        dist (n, kd) float32 sorted distances (model units) and idx (n, k)
        int32 (int64 from 2^31 points) indices into ``points``: the same as
        one global ``cKDTree`` query, ties between equal distances aside.
    """
    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    k = int(min(max(k, 1), n))
    kd = k if dist_columns is None else int(min(max(dist_columns, 1), k))
    stats = TiledKnnStats() if stats is None else stats
    dist = np.empty((n, kd), dtype=np.float32)
    idx = np.empty((n, k), dtype=np.int32 if n < 2 ** 31 else np.int64)
    if n == 0:
        return dist, idx
    threads = (os.cpu_count() or 1) if threads < 0 else threads
    level = fine_level(codes, cell_points) if scale > 0 else 0
    stats.level = level
    todo = None                                  # None: every point
    for retry in range(retry_levels + 1):
        grid = cell_grid(codes, level - retry, scale) if level - retry > 0 else \
            CellGrid(0, np.zeros(1, np.uint64), np.array([0, n], np.int64), np.inf)
        todo = _level_pass(pts, np.asarray(lo, np.float64), scale, grid, k, kd, todo, tile_points,
                           dist, idx, stats, threads, progress if todo is None else None)
        if len(todo) == 0:
            return dist, idx
        stats.retried += len(todo)
        if grid.level == 0:
            break
    # what is left (strays far from everything: the 3x3x3 blocks of coarse cells
    # around them hold far more points than their k-NN balls): one tree over all
    d, i = cKDTree(pts).query(pts[todo], k=k, workers=-1)
    dist[todo] = d.reshape(len(todo), k)[:, :kd]
    idx[todo] = i.reshape(len(todo), k)
    stats.global_queries += len(todo)
    return dist, idx


def _level_pass(pts, lo, scale, grid: CellGrid, k, kd, todo, tile_points, dist, idx,
                stats: TiledKnnStats, threads: int, progress) -> np.ndarray:
    """Query ``todo`` (sorted (m,) int64 point indices, None for all) on
    ``grid``'s tiles; return those whose answer is not provably exact."""
    n = len(pts)
    counts = grid.counts
    if todo is None:
        qcells = np.arange(len(counts))
        qstart = grid.start
    else:                                        # cells holding queries, queries per cell
        qcell_of = np.searchsorted(grid.start, todo, side="right") - 1
        qcells, first = np.unique(qcell_of, return_index=True)
        qstart = np.concatenate([first, [len(todo)]]).astype(np.int64)
    # tiles: runs of query cells holding about tile_points points in all
    tile_of = np.cumsum(counts[qcells]) // max(int(tile_points), 1)
    cut = np.concatenate([[0], np.flatnonzero(np.diff(tile_of)) + 1, [len(qcells)]])
    steps = 2 ** (_BITS - grid.level)

    def tile(t):
        tc = qcells[cut[t]:cut[t + 1]]
        if todo is None:
            q = slice(int(grid.start[tc[0]]), int(grid.start[tc[-1] + 1]))
            qi = np.arange(q.start, q.stop)
        else:
            q = qi = todo[qstart[cut[t]]:qstart[cut[t + 1]]]
        cand = _ranges(grid.start, grid.neighbourhood(tc)) if grid.level > 0 else np.arange(n)
        kk = min(k, len(cand))
        # no exact answer lies beyond two cells (the bound below): the search may stop there
        d, i = cKDTree(pts[cand], balanced_tree=False).query(
            pts[q], k=kk, workers=inner, distance_upper_bound=2.0 * grid.width)
        d, i = d.reshape(len(qi), kk), i.reshape(len(qi), kk)
        i[i >= len(cand)] = 0                    # missing neighbours (d = inf): retried below
        if kk < k:                               # too few points around: not exact
            d = np.concatenate([d, np.full((len(qi), k - kk), np.inf)], axis=1)
            i = np.concatenate([i, np.zeros((len(qi), k - kk), i.dtype)], axis=1)
        dist[q] = d[:, :kd]
        idx[q] = cand[i]
        bad = None
        if grid.level > 0:
            g = (pts[q] - lo) * scale / steps
            frac = g - np.floor(g)
            wall = np.minimum(frac, 1.0 - frac).min(axis=1)
            bound = (1.0 + wall) * grid.width * (1.0 - TILE_EXACT_MARGIN_REL)
            bad = qi[~(d[:, k - 1] < bound)]
        return len(cand), int(qi[-1]) + 1, bad

    ntiles = len(cut) - 1
    threads = min(max(int(threads), 1), ntiles)
    inner = 1 if threads > 1 else -1             # threads over tiles, or over one tile's queries
    failed = []
    with ThreadPoolExecutor(threads) as pool:
        for ncand, end, bad in pool.map(tile, range(ntiles)):
            stats.tiles += 1
            stats.tree_points += ncand
            if bad is not None and len(bad):
                failed.append(bad)
            report(progress, "finding neighbours", end / n if todo is None else 1.0)
    return np.concatenate(failed) if failed else np.zeros(0, np.int64)

