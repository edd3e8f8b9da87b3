"""Box / lasso selection and mirror selection on a large cloud, each beside
the obvious baseline measured in the same run.

* lasso (through): the scanline polygon mask plus the lookup of every
  projected centre (:func:`splatedit.app.tools.region.polygon_mask`,
  :func:`~splatedit.app.tools.region.splats_through`) beside projecting the
  centres alone (:meth:`OrbitCamera.project`, which any region test needs);
* mirror of half the model (:func:`splatedit.select.mirror.mirror_indices`:
  push and pull) beside one nearest-neighbour query of the reflections
  (push only).

The cloud: ``n`` points of the unit sphere sampled at random (Poisson: the
worst case for matching reflections), a 1280x720 view, a 200-gon lasso
covering about half the model.

    python -m splatedit.bench.selection_tools [--n 100000 1000000]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np


def run(n: int, seed: int = 0) -> dict:
    from scipy.spatial import cKDTree

    from splatedit.app.view.camera_control import OrbitCamera
    from splatedit.app.tools.region import polygon_mask, splats_through
    from splatedit.select.mirror import mirror_indices, plane_centre, reflect
    from splatedit.tolerances import MIRROR_MATCH_SPACINGS
    rng = np.random.default_rng(seed)
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1)[:, None]
    tree = cKDTree(p)
    d, _ = tree.query(p[:2000], k=2)
    spacing = float(np.median(d[:, 1]))
    cam = OrbitCamera(np.zeros(3), 4.0, yaw=0.6, pitch=0.5, scene_radius=1.0)
    w, h = 1280, 720
    t = np.linspace(0.0, 2.0 * np.pi, 200, endpoint=False)
    lasso = np.c_[w / 2 + 250 * np.cos(t), h / 2 + 200 * np.sin(t)]
    t0 = time.perf_counter()
    px, depth = cam.project(p, w, h)
    t1 = time.perf_counter()
    inside = splats_through(polygon_mask(lasso, w, h), px, depth)
    t2 = time.perf_counter()
    half = np.flatnonzero(p[:, 0] > 0)
    t3 = time.perf_counter()
    got = mirror_indices(p, half, tree, spacing, 0)
    t4 = time.perf_counter()
    dd, jj = tree.query(reflect(p[half], 0, plane_centre(p, 0)), distance_upper_bound=MIRROR_MATCH_SPACINGS * spacing)
    t5 = time.perf_counter()
    return {"n": n, "project_s": t1 - t0, "lasso_mask_and_lookup_s": t2 - t1, "lasso_inside": int(len(inside)),
            "mirror_s": t4 - t3, "push_query_s": t5 - t4, "mirror_found": int(len(got)),
            "push_found": int(len(np.unique(jj[np.isfinite(dd)]))), "selected": int(len(half)),
            "load_average": round(os.getloadavg()[0], 1)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m splatedit.bench.selection_tools", description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, nargs="+", default=[100_000, 1_000_000])
    a = ap.parse_args(argv)
    for n in a.n:
        print(json.dumps({k: round(v, 4) if isinstance(v, float) else v for k, v in run(n).items()}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
