"""Stage times of one grab, handle to first frame, for whatever splatedit is importable.

Before/after comparisons across checkouts (issue 20 part 2, docs/PERFORMANCE.md):

    PYTHONPATH=CHECKOUT python data_tools/stage_times.py SPLATS SUPPORT [--plane]

The bunny resampled to SPLATS splats (Morton order), the SUPPORT splats nearest the ear
tip as the support, the splats within 5% of the diagonal of the tip as the handle (as
splatedit.bench.precompute.grab_scene); ``--plane``: the wavy plane of ``bench solve``'s
1M-support case instead (SPLATS = grid side, e.g. 1100).  Best of 2 of
``DeformationBasis.fit(fill_holes=False)`` + the first ``apply`` next to a float64 4096^3
GEMM (best of 2, before and after) in the same process; one JSON line.  Uses only APIs
that predate issue 20, so an older checkout runs it too.
"""

import json
import os
import sys
import time

import numpy as np

import splatedit
from splatedit.bench.editor import bunny_surface_cloud
from splatedit.model.cloud import SplatCloud
from splatedit.model.pca import morton_order
from splatedit.deform.basis import DeformationBasis
from splatedit.bench.solve import sample_transform
splats, support = int(sys.argv[1]), int(sys.argv[2])
if "--plane" in sys.argv:
    from splatedit.bench.solve import wavy_plane_cloud
    cloud = wavy_plane_cloud(splats)
    xy = cloud.positions[:, :2]
    sup = np.max(np.abs(xy), axis=1) <= 0.91
    hnd = np.linalg.norm(xy, axis=1) <= 0.2
else:
    raw = bunny_surface_cloud(splats)
    o = morton_order(raw.positions)
    cloud = SplatCloud(raw.positions[o], raw.u[o], raw.v[o], name=raw.name)
    p = cloud.positions
    tip = p[np.argmax(p[:, 1])]
    d = np.linalg.norm(p - tip, axis=1)
    r = float(np.partition(d, support)[support])
    sup = d < r
    hnd = (d < 0.05 * cloud.diagonal) & sup
def gemm():
    a = np.random.default_rng(0).random((4096, 4096)); b = a.copy(); best = 1e9
    for _ in range(2):
        t = time.perf_counter(); a @ b; best = min(best, time.perf_counter() - t)
    return best
load = os.getloadavg()[0]
g0 = gemm()
res = []
for rep in range(1 if "--once" in sys.argv else 2):
    t = time.perf_counter()
    b = DeformationBasis.fit(cloud, sup, [hnd], fill_holes=False)
    dc = b.displacement([sample_transform(cloud, hnd, sup)])
    t1 = time.perf_counter(); b.apply(cloud, dc); first = time.perf_counter() - t1
    st = b.stats
    res.append(dict(constraints_s=st["constraints_seconds"], fit_s=st["fit_seconds"], basis_s=st["basis_seconds"], first_frame_s=first, total_s=st["constraints_seconds"]+st["fit_seconds"]+st["basis_seconds"]+first, m=st["n_constraints"], centers=st["n_centers"], method=st["method"]))
    del b
g1 = gemm()
g = min(g0, g1)
best = min(res, key=lambda x: x["total_s"])
print(json.dumps(dict(code=os.path.dirname(splatedit.__file__), splats=splats, support=int(sup.sum()), load1=round(load, 2), gemm_s=round(g, 3), **{k: (round(v, 3) if isinstance(v, float) else v) for k, v in best.items()}, over_gemm=round(best["total_s"] / g, 2))))
