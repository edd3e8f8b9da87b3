"""The splats' neighbour graph: rings, grow/shrink and flood fill.

Selections are closed and edited over a symmetric k-nearest-neighbour graph
of the splat centres (scipy.spatial.cKDTree).  An edge (i, j) exists when j
is among the ``GRAPH_NEIGHBOURS`` nearest splats of i or i among those of j,
and its length is at most ``GRAPH_EDGE_MAX_REL`` times the *smaller* of the
two splats' local scales (the median distance to their k neighbours): an
outlier's long edges to the surface and bridges across gaps between parts
are cut, a surface sampled at a varying density stays connected.

"One ring" of a selection is the set of splats one edge away from it, as a
mesh's one-ring; grow and shrink are the graph's morphological dilation and
erosion.  The graph is stored as CSR arrays (``indptr``, ``indices``) and
every operation is vectorised over the current frontier, so its cost is
proportional to the region it touches, not to the cloud.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy import sparse
from scipy.spatial import cKDTree

from splatedit.model.pca import morton_codes
from splatedit.model.tiles import tiled_knn
from splatedit.progress import report
from splatedit.tolerances import (
    GRAPH_BUILD_CHUNK,
    GRAPH_COARSE_STRIDE,
    GRAPH_EDGE_MAX_REL,
    GRAPH_EXACT_MARGIN_REL,
    GRAPH_NEIGHBOURS,
    GRAPH_ROWS_CHUNK,
)


def unique_indices(values: np.ndarray, scratch: np.ndarray) -> np.ndarray:
    """``values`` (int array) without repeats, in no particular order, in
    O(len(values)) with ``scratch`` (int64 array at least as long as the
    largest value + 1, contents ignored) instead of a sort."""
    order = np.arange(len(values))
    scratch[values] = order
    return values[scratch[values] == order]


def _sorted_knn(pts: np.ndarray, k: int, progress=None):
    """The splats ``pts`` (n, 3) float64 along a Z-order curve and their k
    nearest neighbours there: (sorted positions (n, 3), order (n,) int64 with
    ``sorted = pts[order]``, dist (n, k) float32 model units, idx (n, k) int32
    (int64 from 2^31 splats) in the sorted numbering, nearest first, itself
    included) from :func:`tiled_knn`.  The build stays in the sorted
    numbering (its gathers are local) until :func:`_renumbered`."""
    codes, lo, scale = morton_codes(pts)
    order = np.argsort(codes, kind="stable")
    codes = codes[order]
    sp = pts[order]
    dist, nb = tiled_knn(sp, codes, lo, scale, k, progress=progress)
    return sp, order, dist, nb


def _renumbered(indptr_s: np.ndarray, indices_s: np.ndarray, order: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The CSR graph (``indptr_s`` (n + 1,), ``indices_s``) of the Z-order
    sorted splats in the input's numbering (sorted splat s is splat
    ``order[s]``): rows moved, indices mapped, each row sorted.  Returns
    (indptr (n + 1,) int64, indices int32)."""
    n = len(order)
    counts_s = np.diff(indptr_s)
    counts = np.empty(n, np.int64)
    counts[order] = counts_s
    indptr = np.zeros(n + 1, np.int64)
    np.cumsum(counts, out=indptr[1:])
    order_i = order.astype(indices_s.dtype)
    indices = np.empty(len(indices_s), indices_s.dtype)
    for lo in range(0, n, GRAPH_BUILD_CHUNK):
        hi = min(lo + GRAPH_BUILD_CHUNK, n)
        a, b = int(indptr_s[lo]), int(indptr_s[hi])
        shift = np.repeat(indptr[order[lo:hi]] - indptr_s[lo:hi], counts_s[lo:hi])
        indices[np.arange(a, b) + shift] = order_i[indices_s[a:b]]
    del indices_s, order_i
    small = len(indices) < 2 ** 31
    m = sparse.csr_matrix((np.ones(len(indices), np.int8), indices, indptr.astype(np.int32) if small else indptr),
                          shape=(n, n))
    m.sort_indices()
    return indptr, m.indices.astype(np.int32, copy=False)


def _exact_keep(pts: np.ndarray, nb: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Whether the edges (i, j) ((m,) int arrays, j among i's neighbours
    ``nb`` (n, k)) are at most GRAPH_EDGE_MAX_REL times the smaller local
    scale of their ends, all in float64 (the few comparisons float32 leaves
    open)."""
    rows, inv = np.unique(np.concatenate([i, j]), return_inverse=True)
    s = np.median(_lengths(pts, rows, nb[rows]), axis=1)
    d = _pair_lengths(pts, i, j)
    return d <= GRAPH_EDGE_MAX_REL * np.minimum(s[inv[:len(i)]], s[inv[len(i):]])


def _pair_lengths(pts: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """(m,) float64 distances between splats i and j, summed as cKDTree does."""
    dx, dy, dz = (pts[j, a] - pts[i, a] for a in range(3))
    return np.sqrt(dx * dx + dy * dy + dz * dz)


def _lengths(pts: np.ndarray, rows, nb: np.ndarray) -> np.ndarray:
    """(m, k) float64 distances from splats ``rows`` (an int start of m
    consecutive splats, or (m,) indices) to their neighbours ``nb`` (m, k),
    summed x, y, z in that order as cKDTree does (the same float64 values as
    its query)."""
    p = pts[rows:rows + len(nb), None, :] if np.isscalar(rows) else pts[rows][:, None, :]
    q = pts[nb]
    dx, dy, dz = q[..., 0] - p[..., 0], q[..., 1] - p[..., 1], q[..., 2] - p[..., 2]
    return np.sqrt(dx * dx + dy * dy + dz * dz)


def _symmetric(counts: np.ndarray, indices: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(indptr (n + 1,) int64, indices int32) of the union of a directed graph
    (row ``i`` holds ``counts[i]`` targets, ``indices`` concatenated) and its
    transpose, each row's entries in no particular order: scipy's CSR
    transpose and sum, on int32 indices while the edge count allows."""
    itype = np.int32 if len(indices) < 2 ** 30 and n < 2 ** 31 else np.int64
    indptr = np.zeros(n + 1, itype)
    np.cumsum(counts, out=indptr[1:])
    a = sparse.csr_matrix((np.ones(len(indices), np.int8), indices.astype(itype, copy=False), indptr),
                          shape=(n, n))
    del indices, indptr
    a = a + a.T.tocsr()                      # rows unsorted: _renumbered sorts them
    return a.indptr.astype(np.int64), a.indices.astype(np.int32, copy=False)


def _row_sums(flags: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """(m,) int64 number of True ``flags`` in each of m consecutive runs of
    ``counts`` (m,) entries (empty runs included)."""
    cs = np.concatenate([[0], np.cumsum(flags, dtype=np.int64)])
    ends = np.cumsum(counts)
    return cs[ends] - cs[ends - counts]


@dataclass(frozen=True)
class NeighbourGraph:
    """Symmetric neighbour graph of ``n`` splats (CSR, read-only arrays).

    Attributes:
        indptr: (n + 1,) int64 CSR row pointers.
        indices: (E,) int32 neighbour indices (each undirected edge twice).
        spacing: median nearest-neighbour distance of distinct splats (model units).
        positions: (n, 3) float64 splat centres (model units; the array the
            graph was built from, not a copy), or None for a :meth:`subgraph`.
        diagonal: bounding-box diagonal of the positions (model units).

    :attr:`tree` (a cKDTree of the positions) is built on first use.
    """

    indptr: np.ndarray
    indices: np.ndarray
    spacing: float
    positions: np.ndarray | None = None
    diagonal: float = 0.0

    @classmethod
    def build(cls, positions: np.ndarray, k: int = GRAPH_NEIGHBOURS, tree: cKDTree | None = None,
              progress=None) -> "NeighbourGraph":
        """Graph of ``positions`` (n, 3) float64 (model units).

        The k nearest neighbours come from :func:`splatedit.model.tiles.tiled_knn`
        (Morton tiles, no k-d tree over all points, exact) on the splats sorted
        along a Z-order curve; the edge rule runs on its float32 distances
        with the comparisons float32 cannot settle redone in float64, so the
        edges are those of one global ``cKDTree`` query (ties between equal
        distances aside).  The graph is built in the sorted numbering and
        renumbered at the end.  Memory: the (n, k + 1) float32 and int32
        neighbour tables, then about three copies of the CSR indices.
        ``tree``: an existing cKDTree of ``positions`` to reuse for
        :attr:`tree` (built lazily otherwise).  ``progress(stage, fraction)``
        is called per tile and per chunk; an exception it raises (a cancelled
        editor job) abandons the build there.
        """
        pts = np.ascontiguousarray(positions, dtype=np.float64)
        n = len(pts)
        diagonal = float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0))) if n else 0.0
        if n < 2:
            ptr = np.zeros(n + 1, np.int64)
            return cls._frozen(ptr, np.zeros(0, np.int32), 0.0, pts, diagonal, tree)
        kk = min(k, n - 1)
        sp, order, dist, nb = _sorted_knn(pts, kk + 1, progress)
        dist, nb = dist[:, 1:], nb[:, 1:]                  # column 0: the splat itself
        chunks = range(0, n, GRAPH_BUILD_CHUNK)
        # pass 1: local scales (median distance to the k neighbours, from the
        # float32 distances: within 2^-24 of the float64 ones) and the spacing
        # (the nearest neighbour at a different position, duplicates looked
        # through: its float64 length, one gather per splat)
        scale = np.empty(n)
        first = np.empty(n)
        for c, lo in enumerate(chunks):
            d = dist[lo:lo + GRAPH_BUILD_CHUNK].astype(np.float64)
            scale[lo:lo + len(d)] = np.median(d, axis=1)
            col = np.minimum(np.argmax(d > 0, axis=1), kk - 1)
            exact = _lengths(sp, lo, nb[lo:lo + len(d)][np.arange(len(d)), col][:, None])[:, 0]
            first[lo:lo + len(d)] = np.where(exact > 0, exact, np.inf)
            report(progress, "neighbour graph: local scales", (c + 1) / len(chunks))
        positive = first[np.isfinite(first)]
        spacing = float(np.median(positive)) if len(positive) else 0.0
        del first, positive
        # pass 2: the edges short enough for both ends, as a directed CSR; a
        # comparison closer than GRAPH_EXACT_MARGIN_REL is redone in float64
        counts = np.zeros(n, np.int64)
        kept = []
        for c, lo in enumerate(chunks):
            j = nb[lo:lo + GRAPH_BUILD_CHUNK]
            d = dist[lo:lo + len(j)].astype(np.float64)
            limit = GRAPH_EDGE_MAX_REL * np.minimum(scale[lo:lo + len(j), None], scale[j])
            keep = d <= limit
            near = np.abs(d - limit) <= GRAPH_EXACT_MARGIN_REL * limit
            if near.any():
                r, q = np.nonzero(near)
                keep[r, q] = _exact_keep(sp, nb, lo + r, j[r, q])
            counts[lo:lo + len(j)] = keep.sum(axis=1)
            kept.append(j[keep])
            report(progress, "neighbour graph: edges", (c + 1) / len(chunks))
        del dist, nb, scale, sp
        indices = np.concatenate(kept)
        del kept
        indptr, indices = _symmetric(counts, indices, n)
        del counts
        indptr, indices = _renumbered(indptr, indices, order)
        report(progress, "neighbour graph: edges", 1.0)
        return cls._frozen(indptr, indices, spacing, pts, diagonal, tree)

    @classmethod
    def _frozen(cls, indptr, indices, spacing, positions, diagonal, tree=None) -> "NeighbourGraph":
        indptr.setflags(write=False)
        indices.setflags(write=False)
        graph = cls(indptr, indices, float(spacing), positions, float(diagonal))
        if tree is not None:
            object.__setattr__(graph, "tree", tree)      # the cached_property's slot
        return graph

    @cached_property
    def tree(self) -> cKDTree | None:
        """cKDTree of the positions (built on first use, e.g. by :meth:`warm`:
        closure's ray queries and the brush's ball queries), or None for a
        :meth:`subgraph`."""
        return None if self.positions is None else cKDTree(self.positions)

    def subgraph(self, index: np.ndarray) -> "NeighbourGraph":
        """The graph induced by the splats ``index`` (sorted unique int array),
        renumbered 0..len(index)-1 in that order (same spacing and
        diagonal, no tree)."""
        index = np.asarray(index, np.int64)
        lookup = np.full(self.n, -1, np.int32)
        lookup[index] = np.arange(len(index), dtype=np.int32)
        counts = np.zeros(len(index), np.int64)
        parts = []
        for lo in range(0, len(index), GRAPH_ROWS_CHUNK):     # bounded temporaries
            rows = index[lo:lo + GRAPH_ROWS_CHUNK]
            nb = lookup[self.neighbours_of(rows)]
            keep = nb >= 0
            counts[lo:lo + len(rows)] = _row_sums(keep, self.indptr[rows + 1] - self.indptr[rows])
            parts.append(nb[keep])
        indptr = np.zeros(len(index) + 1, np.int64)
        np.cumsum(counts, out=indptr[1:])
        indices = np.concatenate(parts) if parts else np.zeros(0, np.int32)
        return self._frozen(indptr, indices.astype(np.int32, copy=False), self.spacing, None, self.diagonal)

    @cached_property
    def coarse(self) -> tuple[np.ndarray, cKDTree, float]:
        """(indices, k-d tree, spacing) of an even subsample of every
        ``GRAPH_COARSE_STRIDE``-th splat (built on first use): for queries
        far from the surface, which the full tree answers slowly."""
        if self.positions is None:
            raise ValueError("a subgraph has no positions for a coarse tree")
        pts = self.positions
        index = np.arange(0, len(pts), GRAPH_COARSE_STRIDE)
        return index, cKDTree(pts[index]), self.spacing * GRAPH_COARSE_STRIDE ** 0.5

    def warm(self) -> "NeighbourGraph":
        """Build the lazily built search structures now (``tree``, ``coarse``,
        ``axis_orders``), e.g. in a background job, so the first closure or
        brush stroke after it does not pay for them; returns self."""
        self.tree
        self.coarse
        self.axis_orders
        return self

    @cached_property
    def axis_orders(self) -> tuple[np.ndarray, np.ndarray]:
        """(orders (3, n), sorted coordinates (3, n)): the splats sorted along
        x, y and z (built on first use), for box queries whose cost follows
        the box, not the cloud."""
        if self.positions is None:
            raise ValueError("a subgraph has no positions to sort")
        pts = self.positions
        # not a stable sort: in_box sorts what it returns, the order among equal
        # coordinates does not matter (3.7x less CPU at 2M splats: 0.25 s, not 0.9 s)
        orders = np.stack([np.argsort(pts[:, a]) for a in range(3)])
        return orders, np.stack([pts[orders[a], a] for a in range(3)])

    def in_box(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """Sorted indices of the splats inside the box [lo, hi] (3,) each: the
        thinnest of the three coordinate slabs, then the other two tested."""
        orders, coords = self.axis_orders
        a = np.searchsorted(coords[0], lo[0]), np.searchsorted(coords[1], lo[1]), \
            np.searchsorted(coords[2], lo[2])
        b = np.searchsorted(coords[0], hi[0], "right"), np.searchsorted(coords[1], hi[1], "right"), \
            np.searchsorted(coords[2], hi[2], "right")
        axis = int(np.argmin([b[k] - a[k] for k in range(3)]))
        cand = orders[axis, a[axis]:b[axis]]
        p = self.positions[cand]
        inside = np.all((p >= lo) & (p <= hi), axis=1)
        return np.sort(cand[inside])

    @property
    def n(self) -> int:
        return len(self.indptr) - 1

    def matrix(self) -> sparse.csr_matrix:
        """The adjacency as a scipy CSR matrix (n, n), unit weights."""
        data = np.ones(len(self.indices), np.int8)
        # int32 row pointers while they fit: scipy would copy the indices to int64 otherwise
        indptr = self.indptr.astype(np.int32) if len(self.indices) < 2 ** 31 else self.indptr
        return sparse.csr_matrix((data, self.indices, indptr), shape=(self.n, self.n))

    def neighbours_of(self, index: np.ndarray) -> np.ndarray:
        """Concatenated neighbour lists of the splats ``index`` (E',) int32
        (with repeats); its temporaries are bounded by GRAPH_ROWS_CHUNK rows."""
        index = np.asarray(index, np.int64)
        if len(index) == 0:
            return np.zeros(0, np.int32)
        start, stop = self.indptr[index], self.indptr[index + 1]
        counts = stop - start
        total = int(counts.sum())
        if total == 0:
            return np.zeros(0, np.int32)
        if len(index) <= GRAPH_ROWS_CHUNK:
            # positions start[r] .. stop[r] - 1 for every row r, vectorised
            offsets = np.repeat(start - np.concatenate([[0], np.cumsum(counts)[:-1]]), counts)
            return self.indices[np.arange(total) + offsets]
        out = np.empty(total, np.int32)
        at = 0
        for lo in range(0, len(index), GRAPH_ROWS_CHUNK):
            part = self.neighbours_of(index[lo:lo + GRAPH_ROWS_CHUNK])
            out[at:at + len(part)] = part
            at += len(part)
        return out

    def any_neighbour(self, index: np.ndarray, where: np.ndarray) -> np.ndarray:
        """(len(index),) bool: which splats ``index`` have a neighbour in
        ``where`` (n,) bool (temporaries bounded by GRAPH_ROWS_CHUNK rows)."""
        index = np.asarray(index, np.int64)
        out = np.zeros(len(index), bool)
        for lo in range(0, len(index), GRAPH_ROWS_CHUNK):
            rows = index[lo:lo + GRAPH_ROWS_CHUNK]
            hit = where[self.neighbours_of(rows)]
            out[lo:lo + len(rows)] = _row_sums(hit, self.indptr[rows + 1] - self.indptr[rows]) > 0
        return out

    def ring(self, mask: np.ndarray) -> np.ndarray:
        """Sorted indices of the splats not in ``mask`` with a neighbour in it (the one-ring)."""
        nb = self.neighbours_of(self._boundary(mask))
        nb = nb[~mask[nb]]
        return np.sort(unique_indices(nb, np.empty(self.n, np.int64)))

    def _boundary(self, mask: np.ndarray) -> np.ndarray:
        """Indices of ``mask`` splats with at least one neighbour outside it."""
        idx = np.flatnonzero(mask)
        if len(idx) == 0:
            return idx
        return idx[self.any_neighbour(idx, ~mask)]

    def grow(self, mask: np.ndarray, rings: int = 1, within: np.ndarray | None = None) -> np.ndarray:
        """``mask`` (n,) bool plus every splat at most ``rings`` edges from it
        (restricted to ``within`` when given); returns a new mask."""
        out = np.asarray(mask, bool).copy()
        frontier = np.flatnonzero(out)
        scratch = np.empty(self.n, np.int64)
        for _ in range(int(rings)):
            if len(frontier) == 0:
                break
            nb = self.neighbours_of(frontier)
            nb = unique_indices(nb[~out[nb]], scratch)
            if within is not None:
                nb = nb[within[nb]]
            out[nb] = True
            frontier = nb
        return out

    def shrink(self, mask: np.ndarray, rings: int = 1) -> np.ndarray:
        """``mask`` minus every splat at most ``rings`` edges from a splat
        outside it; returns a new mask."""
        out = np.asarray(mask, bool).copy()
        for _ in range(int(rings)):
            edge = self._boundary(out)
            if len(edge) == 0:
                break
            out[edge] = False
        return out

    def connected(self, seeds, allowed: np.ndarray | None = None) -> np.ndarray:
        """Flood fill: every splat reachable from ``seeds`` (int indices)
        through splats of ``allowed`` (n,) bool (default: all); the seeds are
        included when allowed.  Returns an (n,) bool mask."""
        seeds = np.atleast_1d(np.asarray(seeds, np.int64))
        out = np.zeros(self.n, bool)
        if allowed is not None:
            seeds = seeds[allowed[seeds]]
        out[seeds] = True
        return self.grow(out, rings=self.n, within=allowed)

    def components(self, index: np.ndarray) -> tuple[int, np.ndarray]:
        """Connected components of the subgraph induced by the splats
        ``index`` (sorted int array): ``(count, labels (len(index),))``."""
        index = np.asarray(index, np.int64)
        if len(index) == 0:
            return 0, np.zeros(0, np.int64)
        sub = self.subgraph(index).matrix()      # the whole graph's matrix would be 5 bytes an edge end
        from scipy.sparse.csgraph import connected_components
        count, labels = connected_components(sub, directed=False)
        return int(count), labels
