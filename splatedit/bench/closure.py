"""``splatedit bench closure``: neighbour graph and selection closure, 100k and 1M splats
(``--splats N ...`` for other sizes).

The scene is the bundled bunny resampled to ``n`` surface splats
(:func:`splatedit.bench.editor.bunny_surface_cloud`).  The selection is a user's
first strokes from one view (:func:`splatedit.select.view.one_view_disc`,
visible-only) over the tall ear, closed once; then one more stroke (a dab of
the same brush further down the ear, a thin part, or on the flank the view
faces, a thick one) is painted and closed again.  Measured, best of a
few repeats:

* ``stroke_ms``: closure of the stroke (``changed`` = the dab: only its
  neighbourhood is worked on), what the editor does after every stroke;
* ``full_ms``: closure of the whole selection from scratch (the obvious
  alternative, and what an edit script does once per edit);
* ``graph_s``: building the neighbour graph with its search structures
  (``build_s`` the tiled k-NN and edges, ``warm_s`` the global k-d tree,
  coarse subsample and axis orders; once per model, in the editor's
  background), its CPU seconds ``graph_cpu_s`` and the peak resident memory
  it added ``graph_peak_mb``, next to ``kdtree_knn_s``, one cKDTree build
  plus k-NN query over all splats (what the graph used to be built from);
* ``big_ms`` / ``big_peak_mb``: closing a large painted area from scratch
  (a one-view disc of 30% of the diagonal with a handle of 10%: about a
  quarter of the model, like a user's support for a large edit).

Peak memory is Linux's high-water mark of the process (``VmHWM``, reset
through ``/proc/self/clear_refs`` before each stage) minus the resident
size before it; -1 elsewhere.
"""

from __future__ import annotations

import os
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


def _rss_mb() -> tuple[int, int]:
    """(resident, high-water mark) of this process in MB, or (-1, -1)."""
    try:
        with open("/proc/self/status") as f:
            st = dict(line.split(":", 1) for line in f)
        return int(st["VmRSS"].split()[0]) // 1024, int(st["VmHWM"].split()[0]) // 1024
    except (OSError, KeyError, ValueError):
        return -1, -1


def _staged(fn) -> tuple[float, float, int, object]:
    """(wall s, CPU s, peak MB added, result) of ``fn()``."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")                     # reset the high-water mark
    except OSError:
        pass
    rss0, _ = _rss_mb()
    c0, t0 = time.process_time(), time.perf_counter()
    out = fn()
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    _, hwm = _rss_mb()
    return wall, cpu, (hwm - rss0 if rss0 >= 0 else -1), out


def _best(fn, repeats: int) -> tuple[float, object]:
    best, out = np.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def bench_closure(counts=(100_000, 1_000_000), repeats: int = 3):
    """Yield one dict per model size (see the module docstring)."""
    from splatedit.bench.editor import bunny_surface_cloud
    for n in counts:
        cloud = bunny_surface_cloud(n)
        pos = cloud.positions
        nrm = cloud.normals
        t_knn, _ = _best(lambda: cKDTree(pos).query(pos, k=GRAPH_NEIGHBOURS + 1, workers=-1), 1)
        t_build, c_build, m_build, graph = _staged(lambda: NeighbourGraph.build(pos))
        t_warm, c_warm, m_warm, _ = _staged(graph.warm)
        t_graph = t_build + t_warm
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
        big = one_view_disc(pos, nrm, _VIEW, pos.mean(axis=0), 0.3 * diag, cell)
        big_h = one_view_disc(pos, nrm, _VIEW, tip, 0.1 * diag, cell) & big
        t_big, c_big, m_big, r_big = _staged(lambda: close_selection(cloud, big, [big_h], graph=graph))
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
                   "graph_s": round(t_graph, 2), "build_s": round(t_build, 2), "warm_s": round(t_warm, 2),
                   "graph_cpu_s": round(c_build + c_warm, 2), "graph_peak_mb": max(m_build, m_warm),
                   "kdtree_knn_s": round(t_knn, 2), "graph_over_knn": round(t_graph / t_knn, 2),
                   "big_support": int(big.sum()), "big_added": int(r_big.n_added),
                   "big_ms": round(t_big * 1e3, 1), "big_cpu_s": round(c_big, 2), "big_peak_mb": m_big,
                   "load": round(os.getloadavg()[0], 1)}
