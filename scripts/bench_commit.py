"""UI-thread time of an editor commit: synchronous vs background (start, job, landing).

    PYTHONPATH=$PWD python scripts/bench_commit.py bunny|big|gs

``bunny``: the bundled model; ``big``: the bunny resampled to 1M splats
(iqr solver); ``gs``: 100k Gaussians on the resampled bunny (SH degree 3).
Support: the third of the model nearest its top point; handle: the inner
30% of that ball, moved and turned (rotation mode).  Prints one markdown
row (docs/PERFORMANCE.md, "Editor commits in the background"): estimate,
synchronous commit (after a warm-up commit), background commit's UI time at
Enter, job time, UI time at landing, and whether both clouds are equal.
"""
import sys
import time

import numpy as np

from splatedit.app.document.session import Session


def rig(cloud, frac=1 / 3):
    p = cloud.positions
    c = p[np.argmax(p[:, 1])]
    d = np.linalg.norm(p - c, axis=1)
    r = np.quantile(d, frac)
    return d <= r, d <= 0.3 * r


def posed(cloud, method):
    s = Session(cloud, fit_sync=True, method=method)
    sup, hnd = rig(cloud)
    s.set_selection(sup, hnd); assert s.wait_fit(), s.fit_error
    s.fit.sync = False                       # the refit after landing runs in the background, as in the editor
    m = np.eye(4); m[:3, :3] = [[0.96, -0.28, 0], [0.28, 0.96, 0], [0, 0, 1]]; m[:3, 3] = [0.0, 0.02, 0.01]
    s.pose[0] = m
    return s, int(sup.sum())

def one(cloud, label, method="auto"):
    from splatedit.app.document.commit_job import estimate_ms
    s, sup = posed(cloud, method)
    est = estimate_ms(cloud, sup)
    s.commit(); s.close()                    # warm-up (first-call imports)
    s, _ = posed(cloud, method)
    t0 = time.perf_counter(); s.commit(); t_sync = time.perf_counter() - t0
    base = s.cloud; s.close()
    s, _ = posed(cloud, method); s.commit_sync_ms = 0.0
    t0 = time.perf_counter(); s.commit(); t_start = time.perf_counter() - t0
    s.committer.wait(); t_bg = time.perf_counter() - t0
    t0 = time.perf_counter(); s.poll(); t_land = time.perf_counter() - t0
    same = all(np.array_equal(getattr(s.cloud, k), getattr(base, k)) for k in ("positions", "u", "v"))
    s.close()
    print(f"| {label} | {cloud.n:,} | {sup:,} | {est:.0f} | {t_sync*1e3:.0f} | {t_start*1e3:.0f} | {t_bg*1e3:.0f} | {t_land*1e3:.0f} | {same} |", flush=True)

which = sys.argv[1]
if which == "bunny":
    from splatedit.io import read
    from splatedit.data import default_model_path
    one(read(default_model_path()), "bundled bunny")
elif which == "big":
    from splatedit.bench.editor import bunny_surface_cloud
    one(bunny_surface_cloud(1_000_000), "bunny resampled, splats", "iqr")
elif which == "gs":
    from splatedit.bench.editor import bunny_surface_cloud
    from splatedit.bench.gs_scenes import gaussians_from_splats
    from splatedit.app.document.gaussian import gaussian_document
    one(gaussian_document(gaussians_from_splats(bunny_surface_cloud(100_000))), "3DGS (bunny resampled, SH 3)")
