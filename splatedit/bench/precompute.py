"""``splatedit bench solve`` (precompute cases): handle to first frame of one grab.

Issue 20 part 2: a support of 400,000 splats on a 1M-splat scan must be ready
in about the time of one float64 4096^3 matrix product (measured in the same
run), a 1M support in under 5 s, and the deformation must stay within 0.5% of
the handle's move of the exact LU deformation.  The scene (:func:`grab_scene`)
is the bundled bunny resampled to ``splats`` surface splats (uniform random,
Morton order as a scan's coherent file order); the support is the ball around
the ear tip holding ``support`` splats, the handle the splats within 5% of the
diagonal of the tip (one grab, lifted and tilted by
:func:`~splatedit.bench.solve.sample_transform`).

One dict per case (times in seconds):

* ``gemm_s``: one float64 ``gemm_n``^3 product (4096; best of 2, before and
  after the case), the yardstick; ``load1``: the 1-minute load average at the
  start;
* ``closure_s``: closing the selection (``fill_holes=True``, the script
  path; the editor closes after each stroke instead), measured once;
* for the default path (``method="auto"``, far-field basis evaluation at
  :data:`~splatedit.tolerances.FAST_EVAL_TOL`), the exact path
  (``method="auto"``, ``eval_tol=0``: every splat against every centre, the
  state before issue 20; "auto" is the exact LU up to 3,000 constraints when
  the system is not numerically singular, see ``exact_method``) and the IQR
  (``method="iqr"``, far-field basis):
  ``*_constraints_s``, ``*_fit_s``, ``*_basis_s``, ``*_first_frame_s`` (the
  first ``apply``: building the hot-path arrays and applying), ``*_total_s``
  (constraints to first frame, the closure not included), ``*_over_gemm``
  (total / gemm_s), ``*_centers`` and ``*_pairs_fraction`` (splat-centre
  pairs evaluated / n_free n_centers);
* ``dev_rel``: largest displacement difference of the default path from the
  exact one over every free splat, relative to the largest handle
  displacement (target <= 0.005; the same solver, so this is the basis
  evaluation's error); ``jac_dev``: largest entry difference of the Jacobians
  (dimensionless); ``iqr_dev_rel``: the IQR's, when the exact path is the LU;
* ``scipy_s`` (up to ``scipy_max`` support splats): scipy's
  ``RBFInterpolator(kernel="cubic", degree=2)`` fitted to the same
  constraints and evaluated (values only) at every free splat in chunks, and
  ``scipy_dev_rel`` its displacement difference from the exact path (when
  that is the LU).
"""

from __future__ import annotations

import os
import time

import numpy as np

#: ball radius of the handle, of the diagonal
_HANDLE_REL = 0.05
#: evaluation points per call of scipy's interpolant
_SCIPY_CHUNK = 65536
#: the standard cases: (cloud splats, support splats)
CASES = ((1_000_000, 400_000), (1_250_000, 1_000_000))
#: the --quick case
QUICK_CASES = ((60_000, 25_000),)


def grab_scene(splats: int, support: int):
    """``(cloud, support mask, handle mask)``: the bunny resampled to
    ``splats`` splats, the ``support`` splats nearest the ear tip, and the
    splats within 5% of the diagonal of the tip."""
    from splatedit.bench.editor import bunny_surface_cloud
    from splatedit.model.cloud import SplatCloud
    from splatedit.model.pca import morton_order

    raw = bunny_surface_cloud(int(splats))
    order = morton_order(raw.positions)
    cloud = SplatCloud(raw.positions[order], raw.u[order], raw.v[order], name=raw.name)
    del raw, order
    p = cloud.positions
    tip = p[np.argmax(p[:, 1])]
    d = np.linalg.norm(p - tip, axis=1)
    k = min(int(support), len(d) - 1)
    radius = float(np.partition(d, k)[k])
    return cloud, d < radius, (d < _HANDLE_REL * cloud.diagonal) & (d < radius)


def gemm_seconds(size: int = 4096, repeats: int = 2) -> float:
    """Best of ``repeats`` float64 ``size^3`` matrix products (BLAS threads as set)."""
    rng = np.random.default_rng(0)
    a = rng.random((size, size))
    b = rng.random((size, size))
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        a @ b
        best = min(best, time.perf_counter() - t)
    return best


def _timed_fit(cloud, support, handle, dc_fn, **kw):
    """Fit without closing, then the first frame; returns (basis, dict)."""
    from splatedit.deform.basis import DeformationBasis
    b = DeformationBasis.fit(cloud, support, [handle], fill_holes=False, **kw)
    dc = dc_fn(b)
    t = time.perf_counter()
    b.apply(cloud, dc)
    first = time.perf_counter() - t
    st = b.stats
    n_pairs = max(1, st["n_free"] * st["n_centers"])
    total = st["constraints_seconds"] + st["fit_seconds"] + st["basis_seconds"] + first
    return b, dict(constraints_s=st["constraints_seconds"], fit_s=st["fit_seconds"],
                   basis_s=st["basis_seconds"], first_frame_s=first, total_s=total,
                   centers=st["n_centers"], method=st["method"],
                   pairs_fraction=st["eval_pairs"] / n_pairs)


def precompute_case(splats: int, support: int, *, scipy_max: int = 500_000,
                    run_exact: bool = True, run_iqr: bool = True, gemm_size: int = 4096) -> dict:
    """One case (see the module docstring); ``gemm_size``: the yardstick
    product's size (the quick case uses 1024)."""
    from splatedit.bench.solve import sample_transform
    from splatedit.select.closure import close_selection

    cloud, sup, hnd = grab_scene(splats, support)
    load = os.getloadavg()[0]
    g0 = gemm_seconds(gemm_size)
    transform = sample_transform(cloud, hnd, sup)
    out = {"bench": "solve", "name": f"grab-{support // 1000}k-on-{splats // 1000}k",
           "splats": int(cloud.n), "support": int(sup.sum()), "load1": round(load, 2)}

    t = time.perf_counter()
    close_selection(cloud, sup, [hnd])
    out["closure_s"] = round(time.perf_counter() - t, 3)

    def dc_fn(b):
        return b.displacement([transform])

    def put(prefix, d):
        for key, val in d.items():
            out[prefix + key] = round(val, 4) if isinstance(val, float) else val

    fast, info = _timed_fit(cloud, sup, hnd, dc_fn, method="auto")
    put("", info)
    st = fast.stats
    out.update(m=st["n_constraints"], n_free=st["n_free"])
    con = fast.constraints
    dc = dc_fn(fast)
    free = np.searchsorted(fast.indices, con.free_index)
    disp_fast = fast.displacements(dc)
    hmax = max(float(np.linalg.norm(disp_fast, axis=1).max()), 1e-300)
    jac_fast = fast.jacobians(dc)[free]
    del fast
    if run_exact:
        exact, info = _timed_fit(cloud, sup, hnd, dc_fn, method="auto", eval_tol=0.0)
        put("exact_", info)
        disp_exact = exact.displacements(dc)
        out["dev_rel"] = float(np.linalg.norm(disp_fast[free] - disp_exact[free], axis=1).max() / hmax)
        out["jac_dev"] = float(np.abs(exact.jacobians(dc)[free] - jac_fast).max())
        del exact, jac_fast
    if run_iqr:
        iqr, info = _timed_fit(cloud, sup, hnd, dc_fn, method="iqr")
        put("iqr_", info)
        if run_exact and out["exact_method"] == "lu":
            d = np.linalg.norm(iqr.displacements(dc)[free] - disp_exact[free], axis=1)
            out["iqr_dev_rel"] = float(d.max() / hmax)
        del iqr
    if int(sup.sum()) <= scipy_max:
        from scipy.interpolate import RBFInterpolator
        pts = cloud.positions[con.free_index]
        t = time.perf_counter()
        interp = RBFInterpolator(con.points, con.values, kernel="cubic", degree=2)
        vals = np.empty((len(pts), con.values.shape[1]))
        for s in range(0, len(pts), _SCIPY_CHUNK):
            vals[s:s + _SCIPY_CHUNK] = interp(pts[s:s + _SCIPY_CHUNK])
        out["scipy_s"] = round(time.perf_counter() - t, 3)
        if run_exact and out["exact_method"] == "lu":
            d = np.linalg.norm(vals @ dc - disp_exact[free], axis=1)
            out["scipy_dev_rel"] = float(d.max() / hmax)
    g1 = gemm_seconds(gemm_size)
    gemm = min(g0, g1)
    out.update(gemm_n=int(gemm_size), gemm_s=round(gemm, 5))
    for key in ("total_s", "exact_total_s", "iqr_total_s"):
        if key in out:
            out[key.replace("total_s", "over_gemm")] = round(out[key] / gemm, 2)
    if "exact_total_s" in out:
        out["speedup"] = round(out["exact_total_s"] / out["total_s"], 2)
    return out


def bench_precompute(cases=CASES, *, scipy_max: int = 500_000, gemm_size: int = 4096):
    """Yield one dict per ``(splats, support)`` case."""
    for splats, support in cases:
        yield precompute_case(splats, support, scipy_max=scipy_max, gemm_size=gemm_size)
