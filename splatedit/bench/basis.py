"""``splatedit bench basis``: basis precompute and CPU apply of a multi-million-splat support.

Issue 11 part 5: the basis precompute and the CPU apply must stay
bounded-memory for a 5M-splat support.  The scene is the bundled bunny
resampled to ``support / 0.79`` surface splats (:func:`support_scene`, in
Morton order like a scan's coherent file order); the edit holds the feet (the
bottom 10% of the height) fixed and drags a handle ball at the ear tip (5%
of the diagonal, lifted and tilted by
:func:`~splatedit.bench.solve.sample_transform`): about 79% of the cloud
moves.  The selection is used as painted (``fill_holes=False``; the closure
has its own bench, ``splatedit bench closure``).  Every case runs in a fresh
Python process (:func:`bench_basis`) so that its peak resident memory is its
own; each stage's peak is read from
``VmHWM`` after resetting it (``/proc/self/clear_refs``) at the stage's start.
Fields of one case (times in seconds, memory in MB):

* ``splats``, ``support``, ``m`` (constraints), ``centers``, ``method``;
  ``blas_threads`` (the OpenBLAS thread setting of the environment);
* ``cloud_mb``: the cloud's positions and axes; ``kept_mb``: what the basis
  keeps (its (N, 4, K) rows plus the CPU apply's cached arrays);
* ``constraints_s`` / ``fit_s`` / ``basis_s`` (the RBF values and gradients
  at every free splat) and ``basis_ns_per_pair`` (per splat and centre);
  ``basis_pairs_fraction``: the splat-centre pairs the far-field evaluation
  computed, of n_free x centres;
* ``hot_build_s``: building the apply's cached arrays (the first apply);
  ``apply_s``: one more apply (best of ``repeats``); ``copy_s``: a plain copy
  of the cloud's positions and axes; ``jacobians_s``: the (N, 3, 3) Jacobians;
* ``*_peak_mb``: each stage's peak resident memory above its start
  (``constraints``, ``fit``, ``basis``: the basis rows it keeps,
  ``basis_kept_mb``, are part of its peak), with ``*_over_kept`` /
  ``*_over_output`` the ratios to what the stage keeps or returns;
* up to ``scipy_max`` requested support splats, the obvious alternative on the same
  points: ``scipy_eval_s`` / ``scipy_peak_mb``, scipy's
  ``RBFInterpolator(kernel="cubic", degree=2)`` fitted to the same
  constraints and evaluated (values only, it has no gradients) at every free
  splat in chunks, next to ``rbf_eval_s``, this fit's values alone.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import numpy as np

#: fraction of the scene's splats in the support (feet fixed below 10% height)
_SUPPORT_FRACTION = 0.787
#: the fixed feet: below this fraction of the height
_FEET = 0.10
#: handle ball radius, of the diagonal
_HANDLE_REL = 0.05
#: glibc mmap threshold of the measuring process (bytes; its default 128 KiB, fixed)
_MMAP_THRESHOLD = 131072
#: evaluation points per call when evaluating scipy's interpolant
_SCIPY_CHUNK = 65536


def _status_mb() -> dict:
    out = {}
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(("VmHWM:", "VmRSS:")):
                key, val = line.split(":")
                out[key] = int(val.split()[0]) / 1024.0
    return out


class _Peak:
    """Peak resident memory above the start of a stage (MB), from VmHWM."""

    def __enter__(self):
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")          # resets VmHWM to the current RSS
        self.start = _status_mb()["VmRSS"]
        self.t0 = time.perf_counter()
        return self

    def __exit__(self, *exc):
        self.seconds = time.perf_counter() - self.t0
        self.mb = _status_mb()["VmHWM"] - self.start
        return False


class _Stages:
    """Peak resident memory (MB) of consecutive stages, each above its own
    start, marked from a progress callback."""

    def __init__(self):
        self.mb: dict[str, float] = {}

    def start(self) -> None:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        self._start = _status_mb()["VmRSS"]

    def mark(self, name: str) -> None:
        self.mb[name] = _status_mb()["VmHWM"] - self._start
        self.start()


def support_scene(support_splats: int):
    """``(cloud, support, handle)`` of the bench: the bunny with about
    ``support_splats`` support splats (Morton order)."""
    from splatedit.bench.editor import bunny_surface_cloud
    from splatedit.model.cloud import SplatCloud
    from splatedit.model.pca import morton_order

    n = int(round(support_splats / _SUPPORT_FRACTION))
    raw = bunny_surface_cloud(n)
    order = morton_order(raw.positions)
    cloud = SplatCloud(raw.positions[order], raw.u[order], raw.v[order], name=raw.name)
    del raw, order
    p = cloud.positions
    lo, hi = p[:, 1].min(), p[:, 1].max()
    support = p[:, 1] > lo + _FEET * (hi - lo)
    tip = p[np.argmax(p[:, 1])]
    handle = np.linalg.norm(p - tip, axis=1) < _HANDLE_REL * cloud.diagonal
    return cloud, support, handle


def basis_case(support_splats: int, *, scipy_max: int = 1_000_000, repeats: int = 3) -> dict:
    """One case, in this process (see the module docstring)."""
    from splatedit.bench.solve import sample_transform
    from splatedit.deform.basis import PROGRESS_STAGE as BASIS_STAGE
    from splatedit.deform.basis import DeformationBasis
    from splatedit.deform.rbf import PROGRESS_STAGE as FIT_STAGE

    cloud, support, handle = support_scene(support_splats)
    out = {"bench": "basis", "splats": int(cloud.n), "support": int(support.sum()),
           "blas_threads": os.environ.get("OPENBLAS_NUM_THREADS") or os.environ.get("OMP_NUM_THREADS")
           or "default",
           "cloud_mb": round(sum(a.nbytes for a in (cloud.positions, cloud.u, cloud.v)) / 2**20, 1)}
    stages = _Stages()

    def progress(stage, fraction):
        if fraction == 0.0 and stage == FIT_STAGE and "constraints" not in stages.mb:
            stages.mark("constraints")
        elif fraction == 0.0 and stage == BASIS_STAGE and "fit" not in stages.mb:
            stages.mark("fit")

    stages.start()
    basis = DeformationBasis.fit(cloud, support, [handle], method="iqr", fill_holes=False,
                                 progress=progress)
    stages.mark("basis")
    st = basis.stats
    n_free, centers = st["n_free"], st["n_centers"]
    pack_mb = basis._pack.nbytes / 2**20
    out.update(m=st["n_constraints"], centers=centers, method=st["method"],
               constraints_s=round(st["constraints_seconds"], 2), fit_s=round(st["fit_seconds"], 2),
               basis_s=round(st["basis_seconds"], 2),
               basis_ns_per_pair=round(1e9 * st["basis_seconds"] / max(1, n_free * centers), 2),
               basis_pairs_fraction=round(st["eval_pairs"] / max(1, n_free * centers), 4),
               constraints_peak_mb=round(stages.mb["constraints"], 1),
               fit_peak_mb=round(stages.mb["fit"], 1),
               basis_peak_mb=round(stages.mb["basis"], 1), basis_kept_mb=round(pack_mb, 1),
               basis_peak_over_kept=round(stages.mb["basis"] / pack_mb, 2))
    dc = basis.displacement([sample_transform(cloud, handle, support)])
    with _Peak() as build:
        basis.apply_arrays(cloud, dc)
    hot_mb = sum(a.nbytes for a in basis._cpu["arrays"]) / 2**20
    out_mb = sum(a.nbytes for a in (cloud.positions, cloud.u, cloud.v)) / 2**20
    out.update(kept_mb=round(pack_mb + hot_mb, 1), hot_build_s=round(build.seconds, 2),
               hot_build_peak_mb=round(build.mb, 1),
               hot_build_peak_over_kept=round(build.mb / (hot_mb + out_mb), 2))
    best, peak = np.inf, 0.0
    for _ in range(repeats):
        with _Peak() as ap:
            res = basis.apply_arrays(cloud, dc)
        del res
        best, peak = min(best, ap.seconds), max(peak, ap.mb)
    srcs = (cloud.positions, cloud.u, cloud.v)
    copy_s = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        cp = [s.copy() for s in srcs]
        copy_s = min(copy_s, time.perf_counter() - t0)
        del cp
    out.update(apply_s=round(best, 4), copy_s=round(copy_s, 4), apply_over_copy=round(best / copy_s, 2),
               apply_peak_mb=round(peak, 1), apply_peak_over_output=round(peak / out_mb, 2))
    with _Peak() as jac:
        j = basis.jacobians(dc)
    out.update(jacobians_s=round(jac.seconds, 2), jacobians_peak_mb=round(jac.mb, 1),
               jacobians_peak_over_output=round(jac.mb / (j.nbytes / 2**20), 2))
    del j
    if support_splats <= scipy_max:
        from scipy.interpolate import RBFInterpolator
        con, rbf = basis.constraints, basis.rbf
        pts = cloud.positions[con.free_index]
        with _Peak() as ours:
            for s in range(0, len(pts), _SCIPY_CHUNK):
                rbf(pts[s:s + _SCIPY_CHUNK])
        with _Peak() as theirs:
            interp = RBFInterpolator(con.points, con.values, kernel="cubic", degree=2)
            for s in range(0, len(pts), _SCIPY_CHUNK):
                interp(pts[s:s + _SCIPY_CHUNK])
        out.update(rbf_eval_s=round(ours.seconds, 2), rbf_eval_peak_mb=round(ours.mb, 1),
                   scipy_eval_s=round(theirs.seconds, 2), scipy_peak_mb=round(theirs.mb, 1),
                   scipy_centers=int(len(con.points)))
    return out


def bench_basis(counts=(1_000_000, 2_000_000, 5_000_000), *, scipy_max: int = 1_000_000,
                repeats: int = 3):
    """Yield one dict per support size, each measured in a fresh process."""
    env = dict(os.environ)
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
    # a fixed mmap threshold: glibc's dynamic one would keep freed arrays of
    # earlier stages on its heap, and RSS would then miss later stages' peaks
    env.setdefault("MALLOC_MMAP_THRESHOLD_", str(_MMAP_THRESHOLD))
    env.setdefault("NUMPY_MADVISE_HUGEPAGE", "0")      # as `splatedit` itself runs
    for n in counts:
        cmd = [sys.executable, "-m", "splatedit.bench.basis", str(int(n)),
               "--scipy-max", str(int(scipy_max)), "--repeats", str(int(repeats))]
        res = subprocess.run(cmd, capture_output=True, text=True, env=env)
        if res.returncode != 0:
            tail = (res.stderr or res.stdout).strip().splitlines()[-1:] or ["no output"]
            yield {"bench": "basis", "support_requested": int(n), "error": tail[0]}
            continue
        yield json.loads(res.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    """``python -m splatedit.bench.basis N [--scipy-max M] [--repeats R]``: one case."""
    import argparse
    ap = argparse.ArgumentParser(prog="python -m splatedit.bench.basis")
    ap.add_argument("support", type=int)
    ap.add_argument("--scipy-max", type=int, default=1_000_000)
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args(argv)
    print(json.dumps(basis_case(a.support, scipy_max=a.scipy_max, repeats=a.repeats)), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
