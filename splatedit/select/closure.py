"""Closed selections: add what a user painting from one view cannot reach.

A brush sees one side of the model.  The back of an ear or an arm, the rim
of a thin part seen edge-on and the crevices between fingers stay unpainted;
left alone they become *fixed* constraints inside or right next to the
moving region, and the RBF has to go from the handle's motion to zero within
a few point spacings: the edit tears and grows needle splats.  Closure adds
those splats before constraints are built (editor, edit scripts and the
Python API alike), by four rules, each on the neighbour graph of
:mod:`splatedit.select.graph` (h = its point spacing):

1. **Back sides of thin parts.**  An unselected splat u whose nearest
   selected splat s lies within the part's thickness bound T, with normals
   facing opposite ways (n_u . n_s < -``CLOSURE_OPPOSITE_COS``) and each
   behind the other's surface ((p_u - p_s) . n_s < 0 and (p_s - p_u) . n_u
   < 0: both inside the material between them; two surfaces facing each
   other across air, like fingers or an ear over the head, fail this), is
   the other side of a part whose one side was painted.  T =
   ``CLOSURE_THIN_MAX_REL`` times the selection's RMS radius: a stroke
   along an arm is longer than the arm is thick, while a patch painted on a
   belly is smaller than the torso is deep, so the back of the torso stays.
2. **Gaps.**  Morphological closing over the graph (grow by
   ``CLOSURE_GAP_RINGS`` rings, then shrink by as many): the rim of a thin
   part between its painted front and its back, slits and notches at most
   2 * ``CLOSURE_GAP_RINGS`` rings wide.
3. **Enclosed islands.**  Unselected connected components that lie within
   ``CLOSURE_ISLAND_RINGS`` rings of the selection and do not reach beyond
   that (they are surrounded by it): unpainted specks, crevices.
4. **Handle margin.**  Unselected splats closer to a handle than
   max(``BAND_RINGS`` h, ``CLOSURE_HANDLE_MARGIN_REL`` times the handle's RMS
   radius, at most ``CLOSURE_HANDLE_MARGIN_MAX_REL`` of the model's diagonal)
   join the support: no fixed constraint sits right next to a moving handle
   (the displacement would jump from the handle's to zero within a few
   spacings: tears and needles).

Handles are closed by rules 1-3 too, inside the closed support and outside
the other handles: a handle painted on the front of an ear's tip takes the
back of the tip (the user grabbed the tip).  A handle's thickness bound is
``CLOSURE_HANDLE_THIN_MAX_REL`` times its RMS radius (larger than the
support's: the support bounds it, and a handle painted over the face of a
head from one view, RMS radius about 0.87 of the head's, must reach the
back of the head two radii behind).  Closure only adds splats.  It
is not idempotent in general (T and the handle margin grow with the
selection), so the editor closes after each stroke and fits the closed
selection as it is, and exported scripts say ``"fill_holes": false``.

**What the user gave is kept.**  Closure adds only what the selection
encloses or hides, never beyond what the user marked:

* ``reach`` (support) and ``handle_reach`` (per handle): the region the user
  gave (a script's sphere, box or index list; in the editor, every splat
  whose centre projects into a brush dab's circle, at any depth: what the
  strokes covered on screen, the far side of the part included).  All four
  rules add only splats inside it, so the rim of a region never moves and
  the handle margin never reaches outside the user's support (rule 3 too:
  a sphere cut across a sparse scan leaves specks just outside it that its
  rim encloses).  The region of an index list is the list and
  the holes it encloses (:func:`enclosed_holes`).
* ``erased`` (support) and ``handle_erased`` (per handle): splats the user
  erased (the editor remembers every erase stroke in the
  :class:`~splatedit.select.selection.Selection`).  No rule adds them; they
  count as outside, so an island next to them is not enclosed.

None (the default) puts no limit: a Python caller closing a bare mask.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from splatedit.select.graph import NeighbourGraph
from splatedit.tolerances import (
    BAND_RINGS,
    CLOSURE_BACK_CONE_COS,
    CLOSURE_FRONT_RINGS,
    CLOSURE_GAP_RINGS,
    CLOSURE_HANDLE_MARGIN_MAX_REL,
    CLOSURE_HANDLE_THIN_MAX_REL,
    CLOSURE_HANDLE_MARGIN_REL,
    CLOSURE_ISLAND_RINGS,
    CLOSURE_REGION_RINGS,
    CLOSURE_RMS_SAMPLES,
    CLOSURE_OPPOSITE_COS,
    CLOSURE_PARALLEL_QUERIES,
    CLOSURE_RAY_COARSE_DEPTH,
    CLOSURE_RAY_HITS,
    CLOSURE_RAY_MAX,
    CLOSURE_RAY_RADIUS_REL,
    CLOSURE_RAY_START,
    CLOSURE_RAY_STEP,
    CLOSURE_THIN_MAX_REL,
)


@dataclass(frozen=True)
class ClosureCounts:
    """Splats added by each rule (support and handles together)."""
    back_sides: int = 0
    gaps: int = 0
    islands: int = 0
    handle_margin: int = 0

    @property
    def total(self) -> int:
        return self.back_sides + self.gaps + self.islands + self.handle_margin


@dataclass(frozen=True)
class ClosureResult:
    """A closed selection.

    Attributes:
        support: (n,) bool, the closed support (a superset of the input's).
        handles: the closed handles, (n,) bool each, disjoint, inside ``support``.
        added: (n,) bool, support splats that closure added.
        added_to_handles: (n,) bool, handle splats that closure added.
        counts: how many splats each rule added.
    """
    support: np.ndarray
    handles: list[np.ndarray]
    added: np.ndarray
    added_to_handles: np.ndarray
    counts: ClosureCounts = field(default_factory=ClosureCounts)

    @property
    def n_added(self) -> int:
        """Splats that joined the support or a handle."""
        return int((self.added | self.added_to_handles).sum())

    def summary(self) -> str:
        c = self.counts
        if self.n_added == 0:
            return "closure added nothing"
        return (f"closure added {int(self.added.sum())} support and {int(self.added_to_handles.sum())} "
                f"handle splats (back sides {c.back_sides}, gaps {c.gaps}, islands {c.islands}, "
                f"handle margin {c.handle_margin})")


def _workers(n_queries: int) -> int:
    """k-d tree query threads: starting threads costs more than small batches gain."""
    return -1 if n_queries >= CLOSURE_PARALLEL_QUERIES else 1


def _rms_radius(points: np.ndarray) -> float:
    """RMS distance of ``points`` (k, 3) to their centroid (model units)."""
    return float(np.sqrt(np.mean(np.sum((points - points.mean(axis=0)) ** 2, axis=1))))


def _mask_rms_radius(pos: np.ndarray, mask: np.ndarray) -> float:
    """RMS radius of the splats ``mask`` (n,) bool, from an even subsample of
    at most ``CLOSURE_RMS_SAMPLES`` of them (a bound, not a measurement)."""
    idx = np.flatnonzero(mask)
    if len(idx) == 0:
        return 0.0
    return _rms_radius(pos[idx[::max(1, len(idx) // CLOSURE_RMS_SAMPLES)]])


def _unit_normals(cloud, index: np.ndarray) -> np.ndarray:
    """(len(index), 3) unit normals u x v of the splats ``index``."""
    nrm = np.cross(cloud.u[index], cloud.v[index])
    nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)
    return nrm


def _back_sides(cloud, graph: NeighbourGraph, tree: cKDTree, fronts: np.ndarray,
                allowed: np.ndarray, t: float) -> np.ndarray:
    """Indices of ``allowed`` (n,) bool splats that are the back side of a thin
    part whose front splats ``fronts`` (indices) were painted, at most ``t``
    (model units) behind them (rule 1).

    From every front splat a ray goes into the material (along -n); the first
    surface it meets (the nearest splat to points at depths growing by
    ``CLOSURE_RAY_STEP`` from ``CLOSURE_RAY_START`` spacings, within
    ``CLOSURE_RAY_RADIUS_REL`` of the depth; its ``CLOSURE_RAY_HITS`` nearest
    splats there) is the back side where they pass
    the facing tests; the ray stops there either way, so a part further
    behind (the other ear) is never reached.  The hits are then grown over
    the graph (:func:`_grow_back_sides`).  Cost: a few nearest-neighbour
    queries per ray (deeper than ``CLOSURE_RAY_COARSE_DEPTH`` spacings in the
    graph's coarse subsample), plus a facing test per splat of the back side
    and its one-ring.
    """
    pos = cloud.positions
    spacing = graph.spacing
    if len(fronts) == 0 or not t > 0 or not spacing > 0:
        return np.zeros(0, np.int64)
    depths = []
    d = CLOSURE_RAY_START * spacing
    while d <= t:
        depths.append(d)
        d *= CLOSURE_RAY_STEP
    if not depths:
        return np.zeros(0, np.int64)
    depths = np.array(depths)
    n_front = _unit_normals(cloud, fronts)
    rays = np.arange(0, len(fronts), max(1, len(fronts) // CLOSURE_RAY_MAX)) if len(fronts) > CLOSURE_RAY_MAX \
        else np.arange(len(fronts))
    p_ray, n_ray = pos[fronts[rays]], n_front[rays]
    kk = CLOSURE_RAY_HITS
    rows_out, u_out = [], []
    live = np.arange(len(rays))
    for d in depths:   # march all live rays one step; a ray stops at the first surface it meets
        if len(live) == 0:
            break
        r = max(CLOSURE_RAY_RADIUS_REL * d, spacing)
        q = p_ray[live] - d * n_ray[live]
        if d > CLOSURE_RAY_COARSE_DEPTH * spacing:
            # deep inside a thick part a k-d query must search a wide ball of
            # empty space: the coarse subsample answers it with as few nodes
            coarse_index, coarse_tree, coarse_spacing = graph.coarse
            dist, hit = coarse_tree.query(q, k=kk, distance_upper_bound=max(r, coarse_spacing),
                                          workers=_workers(len(live)))
            dist, hit = dist.reshape(len(live), kk), hit.reshape(len(live), kk)
            hit = np.where(np.isfinite(dist), coarse_index[np.minimum(hit, len(coarse_index) - 1)], 0)
        else:
            dist, hit = tree.query(q, k=kk, distance_upper_bound=r, workers=_workers(len(live)))
            dist, hit = dist.reshape(len(live), kk), hit.reshape(len(live), kk)
        met = np.isfinite(dist[:, 0])
        within = np.isfinite(dist[met])
        rows_out.append(np.repeat(live[met], kk)[within.ravel()])
        u_out.append(hit[met].ravel()[within.ravel()])
        live = live[~met]
    rows = np.concatenate(rows_out) if rows_out else np.zeros(0, np.int64)
    u = np.concatenate(u_out) if u_out else np.zeros(0, np.int64)
    ok = allowed[u]
    rows, u = rows[ok], u[ok]
    if len(u) == 0:
        return u.astype(np.int64)
    n_u = _unit_normals(cloud, u)
    off = pos[u] - p_ray[rows]
    cone = CLOSURE_BACK_CONE_COS * np.linalg.norm(off, axis=1)
    keep = ((np.einsum("ij,ij->i", n_u, n_ray[rows]) < -CLOSURE_OPPOSITE_COS)
            & (np.einsum("ij,ij->i", off, n_ray[rows]) < -cone)
            & (np.einsum("ij,ij->i", off, n_u) > cone))
    seeds, first = np.unique(u[keep], return_index=True)
    seed_fronts = fronts[rays[rows[keep][first]]]
    return _grow_back_sides(cloud, graph, fronts, n_front, allowed, seeds.astype(np.int64), seed_fronts, t)


def _across(pos: np.ndarray, cand: np.ndarray, n_c: np.ndarray, front: np.ndarray, n_f: np.ndarray,
            t: float) -> tuple[np.ndarray, np.ndarray]:
    """Facing test of candidate/front pairs (same-length index arrays, with
    their unit normals): at most ``t`` apart, normals opposite, each behind
    the other's surface within the cone.  Returns (passes (p,) bool, lateral
    offset of the candidate from the front's normal line (p,), model units)."""
    off = pos[cand] - pos[front]
    along = np.einsum("ij,ij->i", off, n_f)
    dist = np.linalg.norm(off, axis=1)
    cone = CLOSURE_BACK_CONE_COS * dist
    ok = ((dist <= t) & (np.einsum("ij,ij->i", n_c, n_f) < -CLOSURE_OPPOSITE_COS) & (along < -cone)
          & (np.einsum("ij,ij->i", off, n_c) > cone))
    lateral = np.sqrt(np.maximum(dist * dist - along * along, 0.0))
    return ok, lateral


def _grow_back_sides(cloud, graph: NeighbourGraph, fronts: np.ndarray, n_front: np.ndarray,
                     allowed: np.ndarray, seeds: np.ndarray, seed_fronts: np.ndarray, t: float) -> np.ndarray:
    """Grow the rays' hits over the neighbour graph (rays bunch up behind
    curved fronts and leave parts of the back unreached): an allowed
    neighbour of a back splat b joins the back side when it faces one of the
    painted splats around b's own front (that front and its
    ``CLOSURE_FRONT_RINGS`` rings on the graph) across the part, at most
    ``t`` away; it takes the
    one most straight across as its own front.  Cost: a few dozen vector
    operations per ring of the back side, no k-d tree.  Returns sorted
    indices."""
    if len(seeds) == 0:
        return seeds
    n = graph.n
    slot = np.full(n, -1, np.int64)          # row of a front splat in n_front
    slot[fronts] = np.arange(len(fronts))
    pos = cloud.positions
    back = np.zeros(n, bool)
    back[seeds] = True
    tested = back.copy()
    frontier, frontier_front = seeds, seed_fronts
    scratch = np.empty(n, np.int64)
    while len(frontier):
        counts = graph.indptr[frontier + 1] - graph.indptr[frontier]
        cand = graph.neighbours_of(frontier)
        parent_front = np.repeat(frontier_front, counts)
        keep = ~tested[cand] & allowed[cand]
        cand, parent_front = cand[keep], parent_front[keep]
        order = np.arange(len(cand))
        scratch[cand] = order
        first = scratch[cand] == order
        cand, parent_front = cand[first], parent_front[first]
        tested[cand] = True
        if len(cand) == 0:
            break
        # the fronts to try: the parent's front and its rings (painted splats only)
        pair_c, pair_f = np.arange(len(cand)), parent_front
        ring_c, ring_f = pair_c, pair_f
        for _ in range(CLOSURE_FRONT_RINGS):
            k = graph.indptr[ring_f + 1] - graph.indptr[ring_f]
            ring_c, ring_f = np.repeat(ring_c, k), graph.neighbours_of(ring_f)
            pair_c, pair_f = np.concatenate([pair_c, ring_c]), np.concatenate([pair_f, ring_f])
        on = slot[pair_f] >= 0
        pair_c, pair_f = pair_c[on], pair_f[on]
        n_cand = _unit_normals(cloud, cand)
        ok, lateral = _across(pos, cand[pair_c], n_cand[pair_c], pair_f, n_front[slot[pair_f]], t)
        pair_c, pair_f, lateral = pair_c[ok], pair_f[ok], lateral[ok]
        if len(pair_c) == 0:
            break
        best = np.lexsort((lateral, pair_c))            # per candidate, the straightest front first
        pair_c, pair_f = pair_c[best], pair_f[best]
        lead = np.ones(len(pair_c), bool)
        lead[1:] = pair_c[1:] != pair_c[:-1]
        frontier, frontier_front = cand[pair_c[lead]], pair_f[lead]
        back[frontier] = True
    return np.flatnonzero(back)


def _enclosed(graph: NeighbourGraph, sel: np.ndarray, allowed: np.ndarray,
              edge: np.ndarray | None = None) -> np.ndarray:
    """Indices of ``allowed`` unselected splats in components that stay
    within ``CLOSURE_ISLAND_RINGS`` rings of ``sel`` (rule 3) and do not
    touch ``edge`` (splats with neighbours outside a region's graph)."""
    reach = graph.grow(sel, CLOSURE_ISLAND_RINGS, within=allowed | sel)
    last = graph.ring(graph.grow(sel, CLOSURE_ISLAND_RINGS - 1, within=allowed | sel))
    shell = np.flatnonzero(reach & ~sel)
    if len(shell) == 0:
        return shell
    count, labels = graph.components(shell)
    open_ = np.zeros(count, bool)
    open_[labels[np.isin(shell, last)]] = True
    # a component with a neighbour outside the reach (not allowed, or beyond)
    # that is not selected is not enclosed either
    open_[labels[graph.any_neighbour(shell, ~reach)]] = True
    if edge is not None:
        open_[labels[edge[shell]]] = True
    return shell[~open_[labels]]


def _close_graph(graph: NeighbourGraph, sel: np.ndarray, allowed: np.ndarray,
                 edge: np.ndarray | None = None) -> tuple[np.ndarray, int, int]:
    """Rules 2 and 3 for one mask inside ``allowed`` (the splats closure may
    add: inside the reach, not erased; for a handle also inside the support
    and outside the other handles): (closed mask, gaps, islands).  ``edge``:
    splats of a region's graph with neighbours outside it; what lies beyond
    is unknown, so nothing is added near them."""
    out = sel.copy()
    closed = graph.shrink(graph.grow(out, CLOSURE_GAP_RINGS, within=allowed | out), CLOSURE_GAP_RINGS)
    if edge is not None and edge.any():
        closed &= ~graph.grow(edge, 2 * CLOSURE_GAP_RINGS)
    gaps = int((closed & ~out).sum())
    out |= closed
    islands = _enclosed(graph, out, allowed, edge)
    out[islands] = True
    return out, gaps, len(islands)


def _limit(mask: np.ndarray | None, n: int, name: str) -> np.ndarray | None:
    """A caller's (n,) bool limit mask, or None."""
    if mask is None:
        return None
    m = np.asarray(mask, bool)
    if m.shape != (n,):
        raise ValueError(f"{name} must be an ({n},) bool mask, got shape {m.shape}")
    return m


def close_selection(cloud, support: np.ndarray, handles=(), *, graph: NeighbourGraph | None = None,
                    changed: np.ndarray | None = None, reach: np.ndarray | None = None,
                    erased: np.ndarray | None = None, handle_reach=None,
                    handle_erased=None) -> ClosureResult:
    """Close a painted selection (see the module docstring).

    Args:
        cloud: the :class:`~splatedit.model.cloud.SplatCloud` (positions, normals).
        support: (n,) bool mask.
        handles: (n,) bool masks, disjoint, inside the support.
        graph: the cloud's :class:`NeighbourGraph` (built when None; the
            editor keeps one per base cloud).
        changed: (n,) bool, the splats painted or erased since the selection
            was last closed (the editor's stroke), or None.  The rest of the
            selection is taken as closed already and only a neighbourhood of
            the change is closed (the thickness bound T and the handle margin
            still come from the whole selection): the cost follows the
            stroke, not the model (see ``splatedit bench closure``).
        reach: (n,) bool, the region the user gave the support (a script's
            region, the editor's stroke reach), or None: back sides, gaps and
            the handle margin join the support only inside it.
        erased: (n,) bool, splats the user erased from the support, or None:
            closure never adds them (to the support nor to a handle).
        handle_reach, handle_erased: the same per handle (a list as long as
            ``handles``, entries None), or None.
    Returns:
        A :class:`ClosureResult`; the input masks are not modified.
    Raises:
        ValueError: a limit mask of the wrong shape, a graph of another cloud.
    """
    pos = cloud.positions
    n = len(pos)
    sup_in = np.asarray(support, bool)
    hs_in = [np.asarray(h, bool) for h in handles]
    nothing = np.zeros(n, bool)
    if not sup_in.any():
        return ClosureResult(sup_in.copy(), [h.copy() for h in hs_in], nothing, nothing.copy())
    reach = _limit(reach, n, "reach")
    erased = _limit(erased, n, "erased")
    h_reach = [_limit(m, n, f"handle_reach[{i}]") for i, m in enumerate(handle_reach or [None] * len(hs_in))]
    h_erased = [_limit(m, n, f"handle_erased[{i}]") for i, m in enumerate(handle_erased or [None] * len(hs_in))]
    if len(h_reach) != len(hs_in) or len(h_erased) != len(hs_in):
        raise ValueError(f"handle_reach and handle_erased need one entry per handle ({len(hs_in)})")
    graph = NeighbourGraph.build(pos) if graph is None else graph
    if graph.n != n:
        raise ValueError(f"the neighbour graph has {graph.n} splats, the cloud {n}")
    changed = None if changed is None else np.asarray(changed, bool)
    if changed is not None and not changed.any():
        return ClosureResult(sup_in.copy(), [h.copy() for h in hs_in], nothing, nothing.copy())
    tree = graph.tree if graph.tree is not None else cKDTree(pos)
    diag = graph.diagonal
    thickness = [CLOSURE_THIN_MAX_REL * _mask_rms_radius(pos, sup_in)] + \
        [CLOSURE_HANDLE_THIN_MAX_REL * _mask_rms_radius(pos, m) for m in hs_in]

    def fronts(mask):
        return np.flatnonzero(mask if changed is None else mask & changed)

    # rule 1 for the support, then rules 2-3 on the graph around the change
    sup = sup_in.copy()
    inside = ~sup if erased is None else ~sup & ~erased        # what closure may add at all ...
    if reach is not None:
        inside &= reach                                        # ... inside the user's region
    back = _back_sides(cloud, graph, tree, fronts(sup), inside, thickness[0])
    sup[back] = True
    n_back = len(back)
    if changed is None:
        region, sub, edge = np.arange(n), graph, None
    else:
        touched = changed.copy()
        touched[back] = True
        region = _box_region(graph, pos, touched, CLOSURE_REGION_RINGS * graph.spacing)
        sub = graph.subgraph(region)
        edge = (graph.indptr[region + 1] - graph.indptr[region]) != np.diff(sub.indptr)
    sup_r, n_gaps, n_islands = _close_graph(sub, sup[region], inside[region] | sup[region], edge)
    sup[region] = sup_r

    # the handles: rules 1-3 inside the closed support, outside the other handles
    hs = [h & sup for h in hs_in]
    for i, h in enumerate(hs):
        if not fronts(h).size:
            continue
        others = np.zeros(n, bool)
        for k, o in enumerate(hs):
            if k != i:
                others |= o
        allowed = sup & ~others
        if h_erased[i] is not None:
            allowed &= ~h_erased[i]
        inside_h = allowed if h_reach[i] is None else allowed & h_reach[i]
        back = _back_sides(cloud, graph, tree, fronts(h), inside_h & ~h, thickness[1 + i])
        h[back] = True
        n_back += len(back)
        h_r, g, isl = _close_graph(sub, h[region], (inside_h | h)[region], edge)
        h[region] = h_r
        n_gaps, n_islands = n_gaps + g, n_islands + isl

    # rule 4: a margin of support around every handle (where a handle changed),
    # inside the user's support region, never onto erased splats
    n_margin = 0
    for i, h in enumerate(hs):
        if not h.any() or (changed is not None and not (hs_in[i] & changed).any()):
            continue
        hp = pos[h]    # the closed handle: its back side counts for its size
        width = max(BAND_RINGS * graph.spacing,
                    min(CLOSURE_HANDLE_MARGIN_REL * _rms_radius(hp), CLOSURE_HANDLE_MARGIN_MAX_REL * diag))
        lo, hi = hp.min(axis=0) - width, hp.max(axis=0) + width
        if graph.positions is pos:      # the graph's sorted axes: the cost follows the box
            cand = graph.in_box(lo, hi)
        else:
            cand = np.flatnonzero(np.all((pos >= lo) & (pos <= hi), axis=1))
        cand = cand[~sup[cand]]
        if reach is not None:
            cand = cand[reach[cand]]
        if erased is not None:
            cand = cand[~erased[cand]]
        if len(cand) == 0:
            continue
        d, _ = cKDTree(hp).query(pos[cand], k=1, distance_upper_bound=width, workers=_workers(len(cand)))
        near = cand[np.isfinite(d)]
        sup[near] = True
        n_margin += len(near)

    any_h = np.zeros(n, bool)
    for h in hs:
        any_h |= h
    added_h = any_h.copy()
    for h in hs_in:
        added_h &= ~h
    counts = ClosureCounts(n_back, n_gaps, n_islands, n_margin)
    return ClosureResult(sup, hs, sup & ~sup_in, added_h, counts)


def enclosed_holes(graph: NeighbourGraph, mask: np.ndarray) -> np.ndarray:
    """(n,) bool: the splats outside ``mask`` (n,) bool in pieces it encloses
    (rule 3's islands: within ``CLOSURE_ISLAND_RINGS`` rings of it and
    reaching no farther).  ``mask | enclosed_holes(graph, mask)`` is the
    region an explicit list of splats covers (a script's ``indices``)."""
    mask = np.asarray(mask, bool)
    out = np.zeros(graph.n, bool)
    if mask.any():
        out[_enclosed(graph, mask, ~mask)] = True
    return out


def closed_masks(cloud, support: np.ndarray, handles=(), **kw) -> tuple[np.ndarray, list, ClosureResult]:
    """:func:`close_selection` for callers that fit next: (closed support
    (n,) bool, closed handles, the result).  Handle splats outside the given
    support stay in their handle (the fit refuses them with its own error);
    keyword arguments go to :func:`close_selection`."""
    n = len(cloud.positions)
    if isinstance(handles, np.ndarray) and handles.ndim == 1 and handles.dtype == bool:
        handles = [handles]

    def as_bool(sel):    # a mask, or an index array within range; else left to the fit's checks
        a = np.asarray(sel)
        if a.dtype != bool and a.ndim == 1 and np.issubdtype(a.dtype, np.integer) and \
                (not a.size or (a.min() >= 0 and a.max() < n)):
            m = np.zeros(n, bool)
            m[a] = True
            return m
        return a

    sup = as_bool(support)
    hs = [as_bool(h) for h in handles]
    if any(m.dtype != bool or m.shape != (n,) for m in [sup] + hs):
        return sup, hs, ClosureResult(sup.copy(), [h.copy() for h in hs], np.zeros(n, bool), np.zeros(n, bool))
    res = close_selection(cloud, sup, [h & sup for h in hs], **kw)
    return res.support, [c | (h & ~sup) for c, h in zip(res.handles, hs)], res


def _box_region(graph: NeighbourGraph, pos: np.ndarray, touched: np.ndarray, reach: float) -> np.ndarray:
    """Sorted indices of the splats within the box of ``touched`` grown by
    ``reach`` (model units); the cost follows the box, not the cloud."""
    tp = pos[touched]
    return graph.in_box(tp.min(axis=0) - reach, tp.max(axis=0) + reach)
