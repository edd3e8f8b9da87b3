"""Solver / basis / per-frame benchmark in the spirit of the paper's Table 1.

``bench_solve`` measures, for one edit (cloud, support, handles):

* constraints m and support size N (and the constraint-building time),
* exact LU fit (centers = m) and its basis precompute (positions + Jacobians),
* incremental QR fit (default tol) with its center count and basis precompute,
* the max deviation of the IQR deformation from the LU one on the free splats
  for a sample handle transform, relative to the handle's displacement,
* the CPU per-frame ``apply`` vs a plain numpy copy of the same bytes (the
  output arrays positions, u, v) and vs a copy of all the bytes apply reads,
* scipy's ``RBFInterpolator(kernel="cubic", degree=2)`` fit + evaluate on the
  same constraints (values at the support splats only, no gradients).

``bench_groups`` measures the constraint-group kinds (paper Sect. 3 and 6):
precompute (constraints + fit + basis) and CPU per-frame ``apply`` for one
control curve with 4, 8 and 16 picked points and for 1-4 simultaneous rigid
handles, on a ~160k-splat wavy plane.

Run ``python -m splatedit.bench.solve`` for the standard cases
(``--groups`` for the group cases): one JSON line each on stdout.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

from splatedit.deform.basis import DeformationBasis
from splatedit.deform.constraints import build_constraints
from splatedit.deform.curves import ControlCurve
from splatedit.deform.transform import compose, rotate, translate
from splatedit.model.cloud import SplatCloud

#: LU is skipped above this many constraints (O(m^3), minutes beyond)
LU_MAX_CONSTRAINTS = 7000
#: scipy's RBFInterpolator is skipped above this many constraints
SCIPY_MAX_CONSTRAINTS = 7000


# ------------------------------------------------------------ procedural clouds
def _tangent_frame(normals: np.ndarray):
    """Orthonormal tangents (t1, t2) with t1 x t2 = n."""
    a = np.where(np.abs(normals[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    t1 = np.cross(normals, a)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(normals, t1)
    return t1, t2


def sphere_cloud(n: int, radius: float = 1.0, name: str = "sphere") -> SplatCloud:
    """``n`` splats on a sphere (Fibonacci lattice, nearly uniform), circular
    splats of radius about one point spacing, normals pointing outwards."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    rho = np.sqrt(1.0 - z * z)
    phi = np.pi * (1.0 + 5 ** 0.5) * i
    nrm = np.column_stack([rho * np.cos(phi), rho * np.sin(phi), z])
    h = radius * np.sqrt(4.0 * np.pi / n)
    t1, t2 = _tangent_frame(nrm)
    return SplatCloud(radius * nrm, h * t1, h * t2, name=name)


def wavy_plane_cloud(nx: int, ny: int | None = None, size: float = 2.0,
                     amplitude: float = 0.15, waves: float = 1.5,
                     name: str = "wavy-plane") -> SplatCloud:
    """An ``nx`` x ``ny`` grid over ``[-size/2, size/2]^2`` lifted to
    ``z = amplitude sin(waves pi x) cos(waves pi y)``; splat axes are the
    scaled grid tangents (row-major order, so the file order is coherent)."""
    ny = nx if ny is None else ny
    xs = np.linspace(-size / 2, size / 2, nx)
    ys = np.linspace(-size / 2, size / 2, ny)
    x, y = (a.ravel() for a in np.meshgrid(xs, ys))
    w = waves * np.pi
    z = amplitude * np.sin(w * x) * np.cos(w * y)
    zx = amplitude * w * np.cos(w * x) * np.cos(w * y)
    zy = -amplitude * w * np.sin(w * x) * np.sin(w * y)
    h = size / (nx - 1)
    one, zero = np.ones_like(x), np.zeros_like(x)
    u = h * np.column_stack([one, zero, zx])
    v = h * np.column_stack([zero, one, zy])
    return SplatCloud(np.column_stack([x, y, z]), u, v, name=name)


def ball_selection(cloud: SplatCloud, center, radius: float) -> np.ndarray:
    """Mask of the splats within ``radius`` of ``center``."""
    d = np.linalg.norm(cloud.positions - np.asarray(center, dtype=np.float64), axis=1)
    return d <= radius


def sample_transform(cloud: SplatCloud, handle: np.ndarray, support: np.ndarray) -> np.ndarray:
    """A realistic handle edit: lift the handle by 15% of the support's
    extent along its mean normal and tilt it 20 degrees about its centroid."""
    hp = cloud.positions[handle]
    c = hp.mean(axis=0)
    nrm = cloud.normals[handle].mean(axis=0)
    nrm /= max(np.linalg.norm(nrm), 1e-300)
    sp = cloud.positions[support]
    extent = float(np.linalg.norm(sp.max(0) - sp.min(0)))
    axis = np.cross(nrm, [0.3, 0.5, 0.8])
    if np.linalg.norm(axis) < 1e-9:
        axis = np.array([1.0, 0.0, 0.0])
    return compose(rotate(axis, 20.0, c), translate(0.15 * extent * nrm))


# ------------------------------------------------------------------ the bench
def _best_of(fn, repeats: int) -> float:
    fn()
    best = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def bench_solve(cloud: SplatCloud, support, handles, *, name: str, transforms=None,
                run_lu: bool | None = None, run_scipy: bool | None = None,
                apply_repeats: int = 5, fit_repeats: int = 2) -> dict:
    """Measure one edit (see the module docstring); returns a JSON-able dict.

    ``transforms``: one (4, 4) matrix per handle for the accuracy and apply
    measurements (default: :func:`sample_transform` of each handle).
    ``run_lu`` / ``run_scipy``: default True when m is at most
    ``LU_MAX_CONSTRAINTS`` / ``SCIPY_MAX_CONSTRAINTS``.
    Times are seconds: best of ``fit_repeats`` for fit and basis (IQR and LU
    fits alternate, so machine-load drift hits both alike), best of
    ``apply_repeats`` for per-frame numbers.
    """
    if isinstance(handles, np.ndarray) and handles.ndim == 1:
        handles = [handles]
    t = time.perf_counter()
    con = build_constraints(cloud, support, handles)
    t_con = time.perf_counter() - t
    m = con.n_constraints
    run_lu = m <= LU_MAX_CONSTRAINTS if run_lu is None else run_lu
    run_scipy = m <= SCIPY_MAX_CONSTRAINTS if run_scipy is None else run_scipy
    out = dict(name=name, n_points=int(len(cloud)), n_support=int(len(con.support_index)),
               n_free=int(len(con.free_index)), n_handles=len(con.groups),
               m=int(m), n_fixed_band=int(len(con.fixed_index)),
               constraints_s=round(t_con, 4))

    def best_fit(method):
        best = None
        for _ in range(fit_repeats):
            b = DeformationBasis.fit(cloud, support, handles, method=method)
            if best is None:
                best = b
            else:
                for key in ("constraints_seconds", "fit_seconds", "basis_seconds"):
                    best.stats[key] = min(best.stats[key], b.stats[key])
        return best

    iqr = best_fit("iqr")
    out.update(iqr_s=round(iqr.stats["fit_seconds"], 4), iqr_centers=iqr.stats["n_centers"],
               iqr_residual=iqr.stats["residual"],
               iqr_basis_s=round(iqr.stats["basis_seconds"], 4))
    if transforms is None:
        transforms = [sample_transform(cloud, np.asarray(h), np.asarray(support)) for h in handles]
    dc = iqr.displacement(transforms)
    free_rows = np.searchsorted(iqr.indices, con.free_index)
    disp_iqr = iqr.displacements(dc)

    if run_lu:
        lu = best_fit("lu")
        out.update(lu_s=round(lu.stats["fit_seconds"], 4), lu_centers=lu.stats["n_centers"],
                   lu_basis_s=round(lu.stats["basis_seconds"], 4))
        disp_lu = lu.displacements(dc)
        hmax = max(float(np.abs(disp_lu).max()), 1e-300)
        err = np.linalg.norm(disp_iqr[free_rows] - disp_lu[free_rows], axis=1)
        out.update(iqr_vs_lu_max_rel=float(err.max() / hmax) if len(err) else 0.0,
                   iqr_vs_lu_mean_rel=float(err.mean() / hmax) if len(err) else 0.0,
                   speedup_iqr_over_lu=round(
                       (out["lu_s"] + out["lu_basis_s"]) / (out["iqr_s"] + out["iqr_basis_s"]), 2))
        del lu

    # per-frame CPU apply vs plain copies
    iqr.apply(cloud, dc)  # builds the hot-path arrays once
    t_apply = _best_of(lambda: iqr.apply(cloud, dc), apply_repeats)
    srcs = (cloud.positions, cloud.u, cloud.v)
    t_copy = _best_of(lambda: [s.copy() for s in srcs], apply_repeats)
    read = iqr._cpu["arrays"]
    t_copy_read = _best_of(lambda: [a.copy() for a in read], apply_repeats)
    out.update(apply_s=round(t_apply, 5), copy_s=round(t_copy, 5),
               apply_over_copy=round(t_apply / t_copy, 2),
               copy_read_bytes_s=round(t_copy_read, 5),
               apply_over_copy_read_bytes=round(t_apply / t_copy_read, 2),
               bytes_written=int(sum(s.nbytes for s in srcs)),
               bytes_read_support=int(sum(a.nbytes for a in read)))

    if run_scipy:
        from scipy.interpolate import RBFInterpolator
        t = time.perf_counter()
        interp = RBFInterpolator(con.points, con.values, kernel="cubic", degree=2)
        interp(cloud.positions[con.free_index])
        out["scipy_fit_eval_s"] = round(time.perf_counter() - t, 4)
    return out


# ---------------------------------------------------------------- groups
def wavy_plane_point(xy, amplitude: float = 0.15, waves: float = 1.5) -> np.ndarray:
    """Points (p, 3) of :func:`wavy_plane_cloud`'s surface above ``xy`` (p, 2)."""
    xy = np.atleast_2d(np.asarray(xy, dtype=np.float64))
    w = waves * np.pi
    return np.column_stack([xy, amplitude * np.sin(w * xy[:, 0]) * np.cos(w * xy[:, 1])])


def group_cases(cloud: SplatCloud, *, support_radius: float = 0.6,
                curve_points=(4, 8, 16), handle_counts=(1, 2, 3, 4)):
    """Yield ``(name, support, handles, curves, inputs)`` on a wavy plane:
    one S-shaped curve through ``k + 1`` picked surface points (moved by a
    smooth lift), and ``h`` disc handles (radius 0.1) on a circle of radius
    0.35 (lifted and tilted by :func:`sample_transform`)."""
    xy = cloud.positions[:, :2]
    sup = np.linalg.norm(xy, axis=1) <= support_radius
    for n in curve_points:
        s = np.linspace(-0.4, 0.4, n)
        curve = ControlCurve.through(wavy_plane_point(np.column_stack([s, 0.25 * np.sin(4 * s)])))
        dq = np.zeros((n, 3))
        dq[:, 2] = 0.1 * np.sin(np.linspace(0.0, np.pi, n))
        yield f"curve-{n}", sup, [], [curve], [curve.control_displacement(dq)]
    for h in handle_counts:
        ang = 2 * np.pi * np.arange(h) / h
        hs = [np.linalg.norm(xy - 0.35 * np.array([np.cos(a), np.sin(a)]), axis=1) <= 0.1
              for a in ang]
        yield f"handles-{h}", sup, hs, [], [sample_transform(cloud, m, sup) for m in hs]


def bench_groups(cloud: SplatCloud | None = None, *, quick: bool = False, method: str = "iqr",
                 apply_repeats: int = 5, fit_repeats: int = 1, **case_kw):
    """Yield one JSON-ready dict per group case (see :func:`group_cases`):
    ``m``, ``n_columns``, centers, ``precompute_s`` (= ``fit_s``, which
    includes building the constraints and curve samples, + ``basis_s``), the
    CPU per-frame ``apply_s`` (best of ``apply_repeats``) and a plain copy of
    the output arrays for scale; the precompute is the best of ``fit_repeats``
    fits (timings on a shared machine are noisy).  Default cloud: ``wavy_plane_cloud(400)``
    (160k splats; ``quick``: 200, 40k)."""
    if cloud is None:
        cloud = wavy_plane_cloud(200 if quick else 400)
    srcs = (cloud.positions, cloud.u, cloud.v)
    t_copy = _best_of(lambda: [a.copy() for a in srcs], apply_repeats)
    for name, sup, hs, curves, inputs in group_cases(cloud, **case_kw):
        b = None
        for _ in range(max(1, fit_repeats)):
            nb = DeformationBasis.fit(cloud, sup, hs, curves=curves, method=method)
            if b is None or (nb.stats["fit_seconds"] + nb.stats["basis_seconds"]
                             < b.stats["fit_seconds"] + b.stats["basis_seconds"]):
                b = nb
            del nb
        st = b.stats
        dc = b.displacement(inputs)
        t = time.perf_counter()
        b.apply(cloud, dc)  # first frame builds the hot-path arrays
        t_first = time.perf_counter() - t
        t_apply = _best_of(lambda basis=b: basis.apply(cloud, dc), apply_repeats)
        yield dict(name=name, n_points=int(len(cloud)), n_support=st["n_support"],
                   n_free=st["n_free"], n_handles=len(hs), n_curves=len(curves),
                   curve_points=[c.n_controls for c in curves],
                   curve_samples=st["n_curve_samples"], curve_dropped=st["n_curve_dropped"],
                   n_columns=int(b.n_columns), m=st["n_constraints"], method=st["method"],
                   centers=st["n_centers"], residual=st["residual"],
                   fit_s=round(st["fit_seconds"], 4), basis_s=round(st["basis_seconds"], 4),
                   precompute_s=round(st["fit_seconds"] + st["basis_seconds"], 4),
                   first_apply_s=round(t_first, 5), apply_s=round(t_apply, 5),
                   copy_s=round(t_copy, 5), apply_over_copy=round(t_apply / t_copy, 2),
                   max_displacement=float(np.abs(b.displacements(dc)).max()))
        del b


# ------------------------------------------------------------ standard cases
def bundled_model():
    """The bundled bunny model (:class:`~splatedit.model.SplatCloud`), or None
    when it is missing or cannot be read."""
    path = Path(__file__).resolve().parent.parent / "data" / "bunny.ply"
    if not path.is_file():
        return None
    try:
        from splatedit.io import read  # written by another engineer
    except ImportError:
        return None
    return read(path)


def standard_cases(large: bool = True):
    """Yield ``(name, cloud, support, handles)`` of the standard benchmarks:

    * ``bunny-sphere``: a sphere-shaped support (radius 25% of the diagonal)
      around the highest splat of the bundled model, handle = its inner 35%
      (only when ``splatedit/data/bunny.ply`` and ``splatedit.io.read`` exist);
    * ``plane-m5000``: 445k-splat wavy plane, disc support, disc handle,
      m about 5000 (the paper's Table 1 regime);
    * ``plane-2handles``: the same with two handles;
    * ``plane-1M-support`` (``large``): 1.21M splats, 1.0M support splats,
      IQR only (m ~ 13000) -- the per-frame apply target.
    """
    bunny = bundled_model()
    if bunny is not None:
        top = bunny.positions[np.argmax(bunny.positions[:, 1])]
        r = 0.25 * bunny.diagonal
        sup = ball_selection(bunny, top, r)
        yield "bunny-sphere", bunny, sup, [ball_selection(bunny, top, 0.35 * r)]
    plane = wavy_plane_cloud(667)
    sup = np.linalg.norm(plane.positions[:, :2], axis=1) <= 0.6
    hnd = np.linalg.norm(plane.positions[:, :2], axis=1) <= 0.2
    yield "plane-m5000", plane, sup, [hnd]
    xy = plane.positions[:, :2]
    sup2 = np.linalg.norm(xy, axis=1) <= 0.8
    h1 = np.linalg.norm(xy - [0.4, 0.0], axis=1) <= 0.15
    h2 = np.linalg.norm(xy + [0.4, 0.0], axis=1) <= 0.15
    yield "plane-2handles", plane, sup2, [h1, h2]
    if large:
        big = wavy_plane_cloud(1100)
        xy = big.positions[:, :2]
        sup = np.max(np.abs(xy), axis=1) <= 0.91
        hnd = np.linalg.norm(xy, axis=1) <= 0.2
        yield "plane-1M-support", big, sup, [hnd]


def main(argv=None) -> int:
    args = sys.argv[1:] if argv is None else argv
    large = "--small" not in args
    if "--groups" in args:
        for line in bench_groups(quick=not large):
            print(json.dumps(line), flush=True)
        return 0
    for name, cloud, sup, hs in standard_cases(large=large):
        print(json.dumps(bench_solve(cloud, sup, hs, name=name)), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
