"""How far the incremental QR's deformation lies from the exact one, per tolerance.

``bench_accuracy`` fits one edit's constraints exactly (LU, all m constraints
as centres) and by IQR at several stopping tolerances ``||r|| / ||b||`` and
reports, for a realistic handle transform (:func:`sample_transform`), the
largest deviation of the IQR displacement from the exact one over (a sample
of) the free splats, relative to the largest exact displacement (about the
handle's displacement), plus the centre count and the achieved residual.
This is the measurement behind ``IQR_DEFAULT_TOL``.

The cases grow m from about 600 to about 20,000 constraints; the LU at
m = 20,000 needs about 6.4 GB and minutes on two cores, so the large cases run
only on request (``python -m splatedit.bench.accuracy --large``).
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from splatedit.bench.solve import (
    bundled_model,
    ball_selection,
    sample_transform,
    wavy_plane_cloud,
)
from splatedit.deform.constraints import build_constraints
from splatedit.deform.rbf import TriharmonicRBF
from splatedit.deform.transform import apply_affine

#: tolerances tried per case
TOLS = (1e-4, 3e-5, 1e-5, 3e-6, 1e-6)
#: free splats the deviation is measured on (evenly strided sample)
_EVAL_SPLATS = 40_000


def accuracy_cases(large: bool = False):
    """Yield ``(name, cloud, support, handles)``: the bundled bunny's ear, a
    wavy plane with one and two handles at growing resolution (m about 1,000
    to 6,000), and with ``large`` square supports with two big handles
    (m about 8,500, 14,000 and 20,000)."""
    bunny = bundled_model()
    if bunny is not None:
        top = bunny.positions[np.argmax(bunny.positions[:, 1])]
        r = 0.25 * bunny.diagonal
        yield "bunny-sphere", bunny, ball_selection(bunny, top, r), [ball_selection(bunny, top, 0.35 * r)]
    for n in (160, 667):
        plane = wavy_plane_cloud(n)
        xy = plane.positions[:, :2]
        rad = np.linalg.norm(xy, axis=1)
        yield f"plane{n}-1handle", plane, rad <= 0.6, [rad <= 0.2]
        if n == 667:
            h1 = np.linalg.norm(xy - [0.4, 0.0], axis=1) <= 0.15
            h2 = np.linalg.norm(xy + [0.4, 0.0], axis=1) <= 0.15
            yield f"plane{n}-2handles", plane, rad <= 0.8, [h1, h2]
    if large:
        for n in (700, 1100, 1570):
            plane = wavy_plane_cloud(n)
            xy = plane.positions[:, :2]
            sup = np.max(np.abs(xy), axis=1) <= 0.91
            h1 = np.linalg.norm(xy - [0.45, 0.0], axis=1) <= 0.33
            h2 = np.linalg.norm(xy + [0.45, 0.0], axis=1) <= 0.33
            yield f"plane{n}-square-2handles", plane, sup, [h1, h2]


def bench_accuracy(cloud, support, handles, *, name: str, tols=TOLS, log=None) -> dict:
    """One case (see the module docstring); a JSON-ready dict.  ``log``: an
    optional callable given one dict per tolerance as it is measured."""
    con = build_constraints(cloud, support, handles)
    m = con.n_constraints
    pos = cloud.positions
    free = con.free_index[:: max(1, len(con.free_index) // _EVAL_SPLATS)]
    dc = np.concatenate([apply_affine(t, g.controls) - g.controls for t, g in
                         zip([sample_transform(cloud, h, support) for h in handles], con.groups)])
    t = time.perf_counter()
    lu = TriharmonicRBF.fit(con.points, con.values, method="lu")
    t_lu = time.perf_counter() - t
    exact = lu(pos[free]) @ dc
    hmax = float(np.abs(con.values @ dc).max())
    out = dict(name=name, m=int(m), n_free=int(len(con.free_index)), lu_s=round(t_lu, 2),
               lu_residual=lu.residual, max_handle_displacement=hmax, iqr=[])
    del lu
    for tol in tols:
        t = time.perf_counter()
        f = TriharmonicRBF.fit(con.points, con.values, method="iqr", tol=tol)
        dt = time.perf_counter() - t
        err = np.linalg.norm(f(pos[free]) @ dc - exact, axis=1)
        out["iqr"].append(dict(tol=tol, centers=int(f.n_centers), seconds=round(dt, 3),
                               residual=f.residual, max_rel=float(err.max() / hmax),
                               mean_rel=float(err.mean() / hmax)))
        if log is not None:
            log(dict(name=name, m=int(m), **out["iqr"][-1]))
    return out


def main(argv=None) -> int:
    """``[--large] [--only NAME ...] [--tols T,T,...]``: one JSON line per case."""
    args = sys.argv[1:] if argv is None else argv
    tols = TOLS
    if "--tols" in args:
        tols = tuple(float(x) for x in args[args.index("--tols") + 1].split(","))
    for name, cloud, sup, hs in accuracy_cases(large="--large" in args):
        if "--only" in args and name not in args:
            continue
        line = bench_accuracy(cloud, sup, hs, name=name, tols=tols,
                              log=lambda d: print(json.dumps(d), file=sys.stderr, flush=True))
        print(json.dumps(line), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
