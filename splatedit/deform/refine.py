"""Fewer needles in big grabs (issue 20.3): as-rigid-as-possible steps on the
support's neighbour graph, seeded by the RBF deformation.

When a handle is translated far, the paper's linear RBF moves a splat at
weight s by ``s t``; where the weight field falls steeply along the direction
of ``t`` (the handle moves towards the fixed band, or the closed back of a
part whose transition is narrower than its front) the Jacobian ``I + t grad
s^T`` nearly collapses a tangent direction and the splats become needles
(stretch ``max(s1, 1/s2)`` far beyond 4x).  Inferring a swing about the fixed
rim (the rotation mode's machinery, with the handle kept at ``p + t``) barely
changes that (measured: -20 % to +20 % splats beyond 4x, docs/PERFORMANCE.md):
the collapse is local.

This module refines the committed positions instead: a few local/global
iterations of as-rigid-as-possible deformation (Sorkine & Alexa 2007,
"As-rigid-as-possible surface modeling", here on a point graph):

* region: the free support splats within ARAP_REGION_SPACINGS point spacings
  of one stretched beyond ARAP_REGION_STRETCH (:func:`refine_edit`); the
  fixed band, the handles, the rest of the support and every other splat
  keep their RBF positions (exact control: handle splats at ``T_h(p)``, the
  band where it was, splats outside the support untouched);
* graph: the region's symmetrised ARAP_NEIGHBOURS-nearest-neighbour graph,
  with the neighbours outside the region as held nodes (uniform weights; no
  edge is cut, so close splats, of another part too, stay coupled);
* local step: per splat the rotation ``R_i`` closest to ``sum_j e_ij e'_ij^T``
  (SVD, det +1); global step: the graph Laplacian system
  ``L p' = sum_j (R_i + R_j) e_ij / 2`` for the free splats (factored once),
  with a weak anchor ``ARAP_ANCHOR`` to the seed so that graph components
  without a held splat stay where the RBF put them;
* splat axes: per splat the least-squares linear map of its tangent plane
  taking its edges' tangent coordinates to the deformed edges (``u' = J u``;
  so the distortion figures measure what was done); where that fit is
  degenerate (edges along one line) ``u' = R_i u``.

The rule (:func:`refine_committed`): rotation mode, every handle translated,
no curve, a needle in the committed result.  ``splatedit deform`` and the
editor's commit apply it; the live drag shows the RBF result.
Seeded by the RBF result, three iterations take the arm-lift and head-bend
edits of the bench below 0.1 % of moved splats beyond 4x
(``python -m splatedit.bench.needles``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.sparse.linalg import splu

from splatedit.tolerances import ARAP_ANCHOR, ARAP_ITERATIONS, ARAP_MIN_TANGENT_RANK_REL, ARAP_NEIGHBOURS


@dataclass(frozen=True)
class RefineResult:
    """What :func:`arap_refine` did.

    Attributes:
        positions, u, v: (n, 3) float64 the refined arrays of the whole cloud.
        iterations: local/global iterations run.
        n_free: support splats that were free to move.
        n_degenerate: free splats whose axes came from ``R_i`` (degenerate
            tangent fit).
    """
    positions: np.ndarray
    u: np.ndarray
    v: np.ndarray
    iterations: int
    n_free: int
    n_degenerate: int


def _graph(positions: np.ndarray, index: np.ndarray, k: int = ARAP_NEIGHBOURS, margin: float | None = None):
    """The refinement's nodes and edges: the support splats ``index`` and
    every other splat among their ``k`` nearest neighbours (those stay
    where they are), joined by the symmetrised k-nearest-neighbour edges
    (both directions, no duplicates).  No edge is cut (unlike the selection
    graph's): splats that are close are coupled, so the refinement cannot
    pull a support splat away from a close splat of another part.

    ``margin`` (model units): neighbours are searched among the splats
    within it of the bounding box of ``index`` only (None: all).

    Returns:
        (nodes (M,) cloud indices, support first; i, j (E,) node numbers)
    """
    from scipy.spatial import cKDTree
    pts = positions[index]
    cand = None
    if margin is not None:
        lo, hi = pts.min(axis=0) - margin, pts.max(axis=0) + margin
        cand = np.flatnonzero(np.all((positions >= lo) & (positions <= hi), axis=1))
    kk = min(k + 1, len(positions) if cand is None else len(cand))
    _, nb = cKDTree(positions if cand is None else positions[cand]).query(pts, k=kk)
    nb = nb[:, 1:].ravel()
    if cand is not None:
        nb = cand[nb]
    inside = np.zeros(len(positions), dtype=bool)
    inside[index] = True
    seen = np.zeros(len(positions), dtype=bool)
    seen[nb] = True
    extra = np.flatnonzero(seen & ~inside)
    nodes = np.concatenate([index, extra])
    local = np.full(len(positions), -1, dtype=np.int64)
    local[nodes] = np.arange(len(nodes))
    n = len(nodes)
    adj = sparse.csr_matrix((np.ones(len(nb)), (np.repeat(np.arange(len(index)), kk - 1), local[nb])),
                            shape=(n, n))
    adj = (adj + adj.T).tocoo()                 # symmetric, duplicates summed: one entry per edge
    return nodes, adj.row.astype(np.int64), adj.col.astype(np.int64)


def _rotations(agg: sparse.csr_matrix, e0: np.ndarray, e1: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotations R_i closest to ``S_i = sum_j e0 e1^T`` (``R = V U^T``)."""
    s = (agg @ (e0[:, :, None] * e1[:, None, :]).reshape(-1, 9)).reshape(-1, 3, 3)
    u, _, vt = np.linalg.svd(s)
    r = np.matmul(vt.transpose(0, 2, 1), u.transpose(0, 2, 1))
    flip = np.linalg.det(r) < 0.0
    if flip.any():
        u2 = u[flip].copy()
        u2[:, :, 2] *= -1.0
        r[flip] = np.matmul(vt[flip].transpose(0, 2, 1), u2.transpose(0, 2, 1))
    return r


def _solver(a: sparse.csr_matrix):
    """``solve(b (F, 3), x0 (F, 3)) -> x`` of the SPD system ``a``: a sparse LU
    up to ARAP_DIRECT_MAX_SPLATS unknowns, else conjugate gradients with a
    Jacobi preconditioner from the current positions (ARAP_CG_RTOL,
    ARAP_CG_MAXITER): the LU's fill grows faster than the region (50k
    unknowns: 12M entries, 3.2 s to factor on the loaded 2-core machine)."""
    from splatedit.tolerances import ARAP_CG_MAXITER, ARAP_CG_RTOL, ARAP_DIRECT_MAX_SPLATS
    if a.shape[0] <= ARAP_DIRECT_MAX_SPLATS:
        lu = splu(a.tocsc())
        return lambda b, x0: np.stack([lu.solve(np.ascontiguousarray(b[:, k])) for k in range(3)], axis=1)
    inv = (1.0 / a.diagonal())[:, None]

    def solve(b, x0):
        """Preconditioned CG on the three columns at once (one sparse
        product per step; column sums by elementwise products, no BLAS
        calls that start threads)."""
        x = x0.copy()
        r = b - a @ x
        z = inv * r
        d = z.copy()
        rz = (r * z).sum(axis=0)
        stop = (ARAP_CG_RTOL ** 2) * (b * b).sum(axis=0)
        for _ in range(ARAP_CG_MAXITER):
            if np.all((r * r).sum(axis=0) <= stop):
                break
            ad = a @ d
            alpha = rz / np.maximum((d * ad).sum(axis=0), 1e-300)
            x += alpha * d
            r -= alpha * ad
            z = inv * r
            rz_new = (r * z).sum(axis=0)
            d = z + (rz_new / np.maximum(rz, 1e-300)) * d
            rz = rz_new
        return x
    return solve


def arap_refine(cloud, index: np.ndarray, fixed: np.ndarray, positions: np.ndarray,
                u: np.ndarray, v: np.ndarray, *, iterations: int = ARAP_ITERATIONS,
                spacing: float | None = None) -> RefineResult:
    """As-rigid-as-possible refinement of a deformed support.

    Args:
        cloud: the base (undeformed) SplatCloud.
        index: (N,) cloud indices of the support.
        fixed: (N,) bool, support splats that keep their deformed position
            (the fixed band and the handles).
        positions, u, v: (n, 3) float64 the deformed cloud's arrays (the
            seed; not modified).
        iterations: local/global steps.
        spacing: the point spacing (model units): neighbours are searched
            within ARAP_GRAPH_MARGIN_SPACINGS of it around the support's
            bounding box (None: in the whole cloud).
    Returns:
        RefineResult with new arrays: rows outside ``index`` and the fixed
        rows are bitwise the inputs.
    """
    index = np.asarray(index, dtype=np.int64)
    out_p, out_u, out_v = positions.copy(), u.copy(), v.copy()
    if len(index) == 0 or not (~np.asarray(fixed, dtype=bool)).any() or iterations <= 0:
        return RefineResult(out_p, out_u, out_v, 0, 0, 0)
    from splatedit.tolerances import ARAP_GRAPH_MARGIN_SPACINGS
    margin = None if spacing is None else ARAP_GRAPH_MARGIN_SPACINGS * spacing
    index, i, j = _graph(cloud.positions, index, margin=margin)
    fixed = np.concatenate([np.asarray(fixed, dtype=bool), np.ones(len(index) - len(fixed), dtype=bool)])
    n = len(index)
    fi = np.flatnonzero(~fixed)
    p0 = cloud.positions[index]
    x = positions[index].copy()
    seed = x[fi].copy()
    ones = np.ones(len(i))
    agg = sparse.csr_matrix((ones, (i, np.arange(len(i)))), shape=(n, len(i)))
    adj = sparse.csr_matrix((ones, (i, j)), shape=(n, n))
    lap = (sparse.diags(np.asarray(adj.sum(axis=1)).ravel()) - adj).tocsr()
    ci = np.flatnonzero(fixed)
    lff = (lap[fi][:, fi] + ARAP_ANCHOR * sparse.identity(len(fi))).tocsr()
    lfc = lap[fi][:, ci]
    solve = _solver(lff)
    e0 = p0[i] - p0[j]
    const = ARAP_ANCHOR * seed - lfc @ x[ci]
    r = None
    for _ in range(iterations):
        r = _rotations(agg, e0, x[i] - x[j])
        rhs = agg @ (0.5 * np.einsum("nab,nb->na", r[i] + r[j], e0))
        b = rhs[fi] + const
        x[fi] = solve(b, x[fi])
    r = _rotations(agg, e0, x[i] - x[j])
    # splat axes: least-squares tangent-plane map of each free splat's edges
    rows = index[fi]
    uu, vv = cloud.u[index], cloud.v[index]
    lu_, lv_ = np.linalg.norm(uu, axis=1), np.linalg.norm(vv, axis=1)
    uh, vh = uu / lu_[:, None], vv / lv_[:, None]
    d0, d1 = -e0, x[j] - x[i]
    a = np.stack([(d0 * uh[i]).sum(1), (d0 * vh[i]).sum(1)], axis=1)          # (E, 2) tangent coords
    gram = (agg @ (a[:, :, None] * a[:, None, :]).reshape(-1, 4)).reshape(-1, 2, 2)
    mom = (agg @ (d1[:, :, None] * a[:, None, :]).reshape(-1, 6)).reshape(-1, 3, 2)
    ev = np.linalg.eigvalsh(gram)
    ok = ev[:, 0] > ARAP_MIN_TANGENT_RANK_REL * np.maximum(ev[:, 1], 1e-300)
    jt = np.zeros((n, 3, 2))
    jt[ok] = np.matmul(mom[ok], np.linalg.inv(gram[ok]))
    nu = np.where(ok[:, None], jt[:, :, 0] * lu_[:, None], np.einsum("nab,nb->na", r, uu))
    nv = np.where(ok[:, None], jt[:, :, 1] * lv_[:, None], np.einsum("nab,nb->na", r, vv))
    out_p[rows] = x[fi]
    out_u[rows] = nu[fi]
    out_v[rows] = nv[fi]
    return RefineResult(out_p, out_u, out_v, iterations, len(fi), int((~ok[fi]).sum()))


def needs_refine(stats) -> bool:
    """The rule: a rotation-mode edit is refined when more than
    NEEDLE_REFINE_MIN_SHARE of its support splats (``stats``: their
    :class:`~splatedit.deform.distortion.DistortionStats`) are stretched
    beyond DISTORTION_BROKEN_STRETCH."""
    from splatedit.tolerances import NEEDLE_REFINE_MIN_SHARE
    return stats.n > 0 and stats.n_above_broken > NEEDLE_REFINE_MIN_SHARE * stats.n


def refine_edit(basis, cloud, deformed, stretch: np.ndarray | None = None) -> tuple:
    """:func:`arap_refine` of a committed edit: the fixed band and the
    handles of ``basis`` (a fitted DeformationBasis of ``cloud``) keep their
    positions in ``deformed`` (the RBF result).  With ``stretch`` ((N,) the
    support splats' stretch under ``deformed``, in ``basis.indices`` order),
    only the free splats within ARAP_REGION_SPACINGS point spacings of one
    stretched beyond ARAP_REGION_STRETCH are refined (the needles are local:
    the cost follows them, not the support); without it, every free splat.
    An edit with control curves is returned unchanged (their samples are
    not splats the refinement could hold).

    Returns:
        (refined SplatCloud (validated), RefineResult), or (``deformed``, None)
        when the edit has curves or nothing is to be refined; a region of
        more than ARAP_MAX_REGION_SPLATS free splats is not refined either
        (``deformed`` and a RefineResult with 0 iterations).
    """
    from scipy.spatial import cKDTree
    from splatedit.tolerances import ARAP_MAX_REGION_SPLATS, ARAP_REGION_SPACINGS, ARAP_REGION_STRETCH
    con = basis.constraints
    if con.n_curves:
        return deformed, None
    idx = basis.indices
    keep = np.concatenate([con.fixed_index] + [np.asarray(h) for h in con.handle_index])
    free = ~np.isin(idx, keep)
    if stretch is not None:
        seeds = free & (np.asarray(stretch) > ARAP_REGION_STRETCH)
        if not seeds.any():
            return deformed, None
        p = cloud.positions[idx]
        near = cKDTree(p[seeds]).query(p[free], distance_upper_bound=ARAP_REGION_SPACINGS * con.spacing)[0]
        region = np.zeros(len(idx), dtype=bool)
        region[np.flatnonzero(free)[np.isfinite(near)]] = True
        free = region
    nodes = idx[free]                           # the rest of the support: neighbours held at the RBF result
    if len(nodes) > ARAP_MAX_REGION_SPLATS:     # too large to refine in a commit: keep the RBF result
        return deformed, RefineResult(deformed.positions, deformed.u, deformed.v, 0, len(nodes), 0)
    res = arap_refine(cloud, nodes, np.zeros(len(nodes), dtype=bool), deformed.positions, deformed.u,
                      deformed.v, spacing=con.spacing)
    return deformed.replace(positions=res.positions, u=res.u, v=res.v), res


def is_translation(matrices, n_curves: int = 0) -> bool:
    """Whether an edit moves its handles by pure translations: every (4, 4)
    map's linear part within NEEDLE_REFINE_LINEAR_TOL of the identity (largest
    entry of ``A - I``) and no control curve."""
    from splatedit.tolerances import NEEDLE_REFINE_LINEAR_TOL
    return n_curves == 0 and len(matrices) > 0 and all(
        float(np.abs(np.asarray(m, dtype=np.float64)[:3, :3] - np.eye(3)).max()) <= NEEDLE_REFINE_LINEAR_TOL
        for m in matrices)


def refine_committed(basis, cloud, deformed, mode, matrices, stats=None):
    """The rule of the rotation mode (issue 20.3): a committed ROTATION edit
    that translates its handles (:func:`is_translation`; rotations have the
    arc blend already) and has needles (:func:`needs_refine`) is refined by
    :func:`refine_edit`; LINEAR (the paper's deformation: the way to get its
    plain translation) and DETAIL are kept as they are.

    Args:
        basis: the fitted DeformationBasis of ``cloud``; deformed: its
            committed result; mode: the edit's DeformationMode; matrices:
            the handles' (4, 4) maps; stats: the support's DistortionStats
            of ``deformed`` (computed when None and the rule needs it).
    Returns:
        (cloud, DistortionStats of the support (``stats`` as given when the
        rule does not apply), note or "")
    """
    from splatedit.deform.distortion import distortion_from_axes
    from splatedit.deform.modes import DeformationMode
    from splatedit.errors import InputError
    idx = basis.indices

    def figures(c):
        return distortion_from_axes(cloud.u[idx], cloud.v[idx], c.u[idx], c.v[idx])

    if (DeformationMode(mode) is not DeformationMode.ROTATION
            or not is_translation(matrices, basis.constraints.n_curves)):
        return deformed, stats, ""
    stats = figures(deformed) if stats is None else stats
    if not needs_refine(stats):
        return deformed, stats, ""
    try:
        new, res = refine_edit(basis, cloud, deformed, stats.stretch)
    except InputError:          # a refined splat failed the model's checks: keep the RBF result
        return deformed, stats, ""
    if res is None:
        return deformed, stats, ""
    if res.iterations == 0:
        return deformed, stats, (f"needles not refined: {res.n_free} splats around them, more than "
                                 f"the refinement takes in a commit")
    after = figures(new)
    return new, after, (f"needles refined: {stats.n_above_broken} -> {after.n_above_broken} splats beyond "
                        f"{after.broken:g}x ({res.iterations} as-rigid-as-possible steps)")
