"""``splatedit bench closure``: selection closure per brush stroke, 100k and 1M splats.

The scene is the bundled bunny resampled to ``n`` surface splats
(:func:`splatedit.app.bench.bunny_surface_cloud`).  The selection is a user's
first strokes from one view (:func:`splatedit.select.view.one_view_disc`,
visible-only) over the tall ear, closed once; then one more stroke (a dab of
the same brush further down the ear, a thin part, or on the flank the view
faces, a thick one) is painted and closed again.  Measured, best of a
few repeats:

* ``stroke_ms``: closure of the stroke (``changed`` = the dab: only its
  neighbourhood is worked on), what the editor does after every stroke;
* ``full_ms``: closure of the whole selection from scratch (the obvious
  alternative, and what an edit script does once per edit);
* ``graph_s``: building the neighbour graph with its coarse subsample and
  axis orders (once per model, in the editor's background), next to
  ``kdtree_knn_s``, the cKDTree build plus k-NN query alone that it consists
  of (the floor for any graph).
"""

from __future__ import annotations

import time

import numpy as np
from scipy.spatial import cKDTree

from splatedit.select.closure import close_selection
from splatedit.select.graph import NeighbourGraph
from splatedit.select.view import one_view_disc
from splatedit.tolerances import GRAPH_NEIGHBOURS

#: the painting view (towards the model) and the brush radius (of the diagonal)
_VIEW = (1.0, 0.0, 0.0)
_BRUSH_REL = 0.05


def _best(fn, repeats: int) -> tuple[float, object]:
    best, out = np.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def bench_closure(counts=(100_000, 1_000_000), repeats: int = 3):
    """Yield one dict per model size (see the module docstring)."""
    from splatedit.app.bench import bunny_surface_cloud
    for n in counts:
        cloud = bunny_surface_cloud(n)
        pos = cloud.positions
        nrm = cloud.normals
        t_knn, _ = _best(lambda: cKDTree(pos).query(pos, k=GRAPH_NEIGHBOURS + 1, workers=-1), 1)
        t_graph, graph = _best(lambda: NeighbourGraph.build(pos).warm(), 1)
        diag = float(np.linalg.norm(pos.max(0) - pos.min(0)))
        cell = 2.0 * graph.spacing
        tip = pos[np.argmax(pos[:, 1])]
        radius = _BRUSH_REL * diag
        # earlier strokes: three dabs down the ear from its tip, closed
        sel = np.zeros(len(pos), bool)
        for k in range(3):
            sel |= one_view_disc(pos, nrm, _VIEW, tip - [0.0, k * radius, 0.0], radius, cell)
        handle = one_view_disc(pos, nrm, _VIEW, tip, 0.4 * radius, cell) & sel
        base = close_selection(cloud, sel, [handle], graph=graph)
        # the next stroke: a dab further down the ear (thin: its back side is
        # found and grown) or on the flank the view faces (thick: nothing behind)
        flank = np.abs(pos[:, 1] - np.median(pos[:, 1])) < 0.05 * diag
        strokes = {"ear": tip - [0.0, 3 * radius, 0.0],
                   "flank": pos[flank][np.argmin(pos[flank] @ np.asarray(_VIEW))]}
        for name, centre in strokes.items():
            dab = one_view_disc(pos, nrm, _VIEW, centre, radius, cell)
            changed = dab & ~base.support
            support = base.support | dab
            t_stroke, r_stroke = _best(lambda: close_selection(cloud, support, base.handles, graph=graph,
                                                               changed=changed), repeats)
            t_full, r_full = _best(lambda: close_selection(cloud, support, base.handles, graph=graph),
                                   max(1, repeats - 1))
            yield {"bench": "closure", "splats": int(n), "stroke": name, "support": int(support.sum()),
                   "stroke_splats": int(changed.sum()), "stroke_added": int(r_stroke.n_added),
                   "full_added": int(r_full.n_added),
                   "stroke_ms": round(t_stroke * 1e3, 1), "full_ms": round(t_full * 1e3, 1),
                   "full_over_stroke": round(t_full / t_stroke, 1),
                   "graph_s": round(t_graph, 2), "kdtree_knn_s": round(t_knn, 2),
                   "graph_over_knn": round(t_graph / t_knn, 2)}
