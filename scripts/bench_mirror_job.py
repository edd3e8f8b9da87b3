"""Ctrl+M's main-thread time before and after it became a background job:
the mirror of half a fibonacci sphere (the editor's MirrorTool work) run
synchronously (the old path: matching + closure + history on the main
thread) and as the job does it (copy the selection, match + close in the
worker, install), side by side in one run; checks both give the same selection.

    .venv/bin/python scripts/bench_mirror_job.py [N]      # from the repository root; default 1,000,000
"""

from __future__ import annotations

import os
import sys
import time

import numpy as np

from splatedit.app.document.selection import SelectionTools
from splatedit.app.document.session import Session
from splatedit.bench.render import sphere_cloud
from splatedit.select.mirror import mirror_indices


def main(n: int) -> None:
    c = sphere_cloud(n)

    def fresh():
        s = Session(c, fit_sync=True)
        t = SelectionTools(None)
        g = t.graph(c)
        s.set_selection(c.positions[:, 0] > 0.02, np.zeros(n, bool))
        t.close(s)
        return s, t, g

    s, t, g = fresh()
    t0 = time.perf_counter()
    mask = s.selection.support.copy()
    m = mirror_indices(c.positions, np.flatnonzero(mask), g.tree, g.spacing, 0)
    mask[m] = True
    t.apply(s, "support", mask, "mirror support")
    sync = time.perf_counter() - t0
    ref = s.selection.support.copy()
    s.close()

    s, t, g = fresh()
    t0 = time.perf_counter()
    job = t.background_apply(s)
    t1 = time.perf_counter()
    mask = job.target_mask().copy()
    m = mirror_indices(c.positions, np.flatnonzero(mask), g.tree, g.spacing, 0)
    mask[m] = True
    job.compute(mask)
    t2 = time.perf_counter()
    t.install(job, "mirror support")
    t3 = time.perf_counter()
    same = np.array_equal(s.selection.support, ref)
    s.close()
    print(f"{n:,} splats, load {os.getloadavg()[0]:.1f}: synchronous {sync:.2f} s on the main thread; "
          f"job {1e3 * (t1 - t0):.0f} ms (start) + {1e3 * (t3 - t2):.0f} ms (install) on the main thread, "
          f"{t2 - t1:.2f} s in the worker; same selection: {same}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000)
