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
back of the tip (the user grabbed the tip).  Closure only adds splats.  It
is not idempotent in general (T and the handle margin grow with the
selection), so the editor closes after each stroke and fits the closed
selection as it is, and exported scripts say ``"fill_holes": false``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from splatedit.select.graph import NeighbourGraph
from splatedit.tolerances import (
    BAND_RINGS,
    CLOSURE_BACK_CONE_COS,
    CLOSURE_BACK_NEIGHBOURS,
    CLOSURE_GAP_RINGS,
    CLOSURE_HANDLE_MARGIN_MAX_REL,
    CLOSURE_HANDLE_MARGIN_REL,
    CLOSURE_ISLAND_RINGS,
    CLOSURE_OPPOSITE_COS,
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


def _rms_radius(points: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum((points - points.mean(axis=0)) ** 2, axis=1))))


def _back_sides(pos: np.ndarray, nrm: np.ndarray, sel: np.ndarray, allowed: np.ndarray,
                t: float) -> np.ndarray:
    """Indices of ``allowed`` unselected splats that are the back side of a
    thin part whose front ``sel`` (n,) bool was painted, at most ``t`` (model
    units) behind it (rule 1)."""
    sel_idx = np.flatnonzero(sel)
    if len(sel_idx) < 2:
        return np.zeros(0, np.int64)
    sp = pos[sel_idx]
    if not t > 0:
        return np.zeros(0, np.int64)
    lo, hi = sp.min(axis=0) - t, sp.max(axis=0) + t
    cand = np.flatnonzero(allowed & ~sel)
    if len(cand) == 0:
        return cand
    cand = cand[np.all((pos[cand] >= lo) & (pos[cand] <= hi), axis=1)]
    if len(cand) == 0:
        return cand
    kk = min(CLOSURE_BACK_NEIGHBOURS, len(sel_idx))
    d, j = cKDTree(sp).query(pos[cand], k=kk, distance_upper_bound=t, workers=-1)
    d, j = d.reshape(len(cand), kk), j.reshape(len(cand), kk)
    keep = np.zeros(len(cand), bool)
    for col in range(kk):  # any of the k nearest selected splats across the part
        hit = np.flatnonzero(np.isfinite(d[:, col]) & ~keep)
        if len(hit) == 0:
            break
        u, s = cand[hit], sel_idx[j[hit, col]]
        off = pos[u] - pos[s]
        cone = CLOSURE_BACK_CONE_COS * np.linalg.norm(off, axis=1)
        keep[hit] = ((np.einsum("ij,ij->i", nrm[u], nrm[s]) < -CLOSURE_OPPOSITE_COS)
                     & (np.einsum("ij,ij->i", off, nrm[s]) < -cone)
                     & (np.einsum("ij,ij->i", off, nrm[u]) > cone))
    u = cand[keep]
    return u


def _enclosed(graph: NeighbourGraph, sel: np.ndarray, allowed: np.ndarray) -> np.ndarray:
    """Indices of ``allowed`` unselected splats in components that stay
    within ``CLOSURE_ISLAND_RINGS`` rings of ``sel`` (rule 3)."""
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
    nb_counts = graph.indptr[shell + 1] - graph.indptr[shell]
    nb = graph.neighbours_of(shell)
    leaks = ~reach[nb]
    row = np.repeat(np.arange(len(shell)), nb_counts)
    open_[labels[row[leaks]]] = True
    return shell[~open_[labels]]


def _close(graph: NeighbourGraph, pos: np.ndarray, nrm: np.ndarray, sel: np.ndarray,
           allowed: np.ndarray, thickness: float) -> tuple[np.ndarray, ClosureCounts]:
    """Rules 1-3 for one mask inside ``allowed``; returns the closed mask and counts."""
    out = sel.copy()
    back = _back_sides(pos, nrm, out, allowed, thickness)
    out[back] = True
    closed = graph.shrink(graph.grow(out, CLOSURE_GAP_RINGS, within=allowed | out), CLOSURE_GAP_RINGS)
    gaps = int((closed & ~out).sum())
    out |= closed
    islands = _enclosed(graph, out, allowed)
    out[islands] = True
    return out, ClosureCounts(back_sides=len(back), gaps=gaps, islands=len(islands))


def close_selection(cloud, support: np.ndarray, handles=(), *, graph: NeighbourGraph | None = None,
                    changed: np.ndarray | None = None) -> ClosureResult:
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
    Returns:
        A :class:`ClosureResult`; the input masks are not modified.
    """
    pos = cloud.positions
    n = len(pos)
    sup_in = np.asarray(support, bool)
    hs_in = [np.asarray(h, bool) for h in handles]
    if not sup_in.any():
        empty = np.zeros(n, bool)
        return ClosureResult(sup_in.copy(), [h.copy() for h in hs_in], empty, empty.copy())
    graph = NeighbourGraph.build(pos) if graph is None else graph
    if graph.n != n:
        raise ValueError(f"the neighbour graph has {graph.n} splats, the cloud {n}")
    thickness = [CLOSURE_THIN_MAX_REL * _rms_radius(pos[m]) if m.any() else 0.0
                 for m in [sup_in] + hs_in]
    diag = float(np.linalg.norm(pos.max(axis=0) - pos.min(axis=0)))
    margins = [max(BAND_RINGS * graph.spacing,
                   min(CLOSURE_HANDLE_MARGIN_REL * t / CLOSURE_THIN_MAX_REL, CLOSURE_HANDLE_MARGIN_MAX_REL * diag))
               for t in thickness[1:]]
    if changed is None:
        region = np.arange(n)
        sub_graph = graph
    else:
        region = _neighbourhood(pos, np.asarray(changed, bool), sup_in, hs_in,
                                max(thickness + margins) + CLOSURE_ISLAND_RINGS * 2 * graph.spacing)
        if len(region) == 0:
            empty = np.zeros(n, bool)
            return ClosureResult(sup_in.copy(), [h.copy() for h in hs_in], empty, empty.copy())
        sub_graph = graph.subgraph(region)
    sub_pos = pos[region]
    u, v = cloud.u[region], cloud.v[region]
    nrm = np.cross(u, v)
    nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)
    sup_r, c_sup = _close(sub_graph, sub_pos, nrm, sup_in[region], np.ones(len(region), bool),
                          thickness[0])
    hs_r = [h[region] & sup_r for h in hs_in]
    c_h = ClosureCounts()
    for i, h in enumerate(hs_r):
        if not h.any():
            continue
        others = np.zeros(len(region), bool)
        for k, o in enumerate(hs_r):
            if k != i:
                others |= o
        closed, c = _close(sub_graph, sub_pos, nrm, h, sup_r & ~others, thickness[1 + i])
        hs_r[i] = closed
        c_h = ClosureCounts(c_h.back_sides + c.back_sides, c_h.gaps + c.gaps, c_h.islands + c.islands)

    margin = 0
    for h, width in zip(hs_r, margins):
        if not h.any() or not width > 0:
            continue
        hp = sub_pos[h]
        cand = np.flatnonzero(~sup_r)
        lo, hi = hp.min(axis=0) - width, hp.max(axis=0) + width
        cand = cand[np.all((sub_pos[cand] >= lo) & (sub_pos[cand] <= hi), axis=1)]
        if len(cand) == 0:
            continue
        d, _ = cKDTree(hp).query(sub_pos[cand], k=1, distance_upper_bound=width, workers=-1)
        near = cand[np.isfinite(d)]
        sup_r[near] = True
        margin += len(near)

    counts = ClosureCounts(c_sup.back_sides + c_h.back_sides, c_sup.gaps + c_h.gaps,
                           c_sup.islands + c_h.islands, margin)
    sup = sup_in.copy()
    sup[region] |= sup_r
    hs = []
    for h, hr in zip(hs_in, hs_r):
        out = h.copy()
        out[region] |= hr
        hs.append(out)
    any_h = np.zeros(n, bool)
    for h in hs:
        any_h |= h
    added_h = any_h.copy()
    for h in hs_in:
        added_h &= ~h
    return ClosureResult(sup, hs, sup & ~sup_in, added_h, counts)


def _neighbourhood(pos: np.ndarray, changed: np.ndarray, support: np.ndarray, handles: list,
                   reach: float) -> np.ndarray:
    """Sorted indices of the splats within the box of the changed splats (and
    of the handles, whose margin depends on their whole extent) grown by
    ``reach`` (model units)."""
    parts = [changed] + [h for h in handles if (h & changed).any()]
    boxes = [(pos[m].min(axis=0), pos[m].max(axis=0)) for m in parts if m.any()]
    if not boxes:
        return np.zeros(0, np.int64)
    lo = np.min([b[0] for b in boxes], axis=0) - reach
    hi = np.max([b[1] for b in boxes], axis=0) + reach
    return np.flatnonzero(np.all((pos >= lo) & (pos <= hi), axis=1))
