"""Needles in big grabs (issue 20.3): splats stretched beyond 4x by far
translations, the paper's linear deformation against the rotation mode
(which refines a committed edit with needles, :mod:`splatedit.deform.refine`).

Each case paints a support and a handle from one view with a visible-only
brush (like ``/work/shared/tools/one_view_edit.py``: splats facing the
viewer, not occluded, inside screen discs around the visible splat farthest
along ``target``), closes the selection as the editor does, and translates
the handle by a share of the bounding-box diagonal:

  arm lift   a limb-like part (the bunny's ear, the hippo's leg, the kitten's
             ear) grabbed at its end and moved 14.5 % of the diagonal
  head bend  the bunny's head (stroke from the side) moved 8 %

and reports, over the support splats that moved, the distortion figures of
the editor's heat map (:mod:`splatedit.deform.distortion`: stretch
``max(s1, 1/s2)`` of the principal stretches): how many are beyond 4x (and
their share), the largest and the 99th percentile; the tears of the stroke
tool (neighbours closer than 2 h pulled more than 8 h apart); the handle's
error (largest ``|p' - (p + t)|`` over the handle splats) and the largest
motion of a fixed-band splat, both relative to the diagonal; and the
seconds of the commit (with the refinement).

    python -m splatedit.bench.needles [--cases arm-bunny,head-bunny,...]
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from splatedit.deform.modes import DeformationMode


@dataclass(frozen=True)
class Case:
    """One grab: model ("bunny" = the bundled model, else a path), viewing
    direction, target direction, brush radii (shares of the diagonal), move
    direction and length (share of the diagonal)."""
    model: str
    view: tuple
    target: tuple
    support_frac: float
    handle_frac: float
    move: tuple
    move_frac: float


HIPPO = "/work/shared/data/hippo1.ply"
KITTEN = "/work/shared/data/kitten.xyz"
CASES = {
    "arm-bunny-ear": Case("bunny", (1, 0, 0), (0, 1, 0), 0.30, 0.06, (0, 0, 1), 0.145),
    "arm-bunny-ear-down": Case("bunny", (1, 0, 0), (0, 1, 0), 0.25, 0.05, (0, -1, 0), 0.145),
    "arm-hippo-leg": Case(HIPPO, (0, 0, -1), (0, -1, 0), 0.16, 0.045, (1, 0.5, 0), 0.145),
    "arm-hippo-leg-big": Case(HIPPO, (0, 0, -1), (0, -1, 0), 0.25, 0.06, (1, 0.5, 0), 0.145),
    "arm-kitten-ear": Case(KITTEN, (0, 0, 1), (0, 1, 0), 0.16, 0.045, (1, 0, 0), 0.145),
    "head-bunny": Case("bunny", (1, 0, 0), (0, 0, 1), 0.30, 0.08, (0, 1, 0), 0.08),
    "head-hippo": Case(HIPPO, (0, 0, -1), (-1, 0, 0), 0.16, 0.045, (0, 1, 0), 0.08),
}


def load(model: str):
    from splatedit.data import default_model_path
    from splatedit.io import read
    return read(str(default_model_path()) if model == "bunny" else model)


def paint(cloud, case: Case):
    """(support, handle) (n,) bool masks painted from ``case.view`` around
    the visible splat farthest along ``case.target``; and the spacing h and
    the diagonal (model units)."""
    p = cloud.positions
    n = np.cross(cloud.u, cloud.v)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    h = float(np.median(cKDTree(p).query(p[:: max(1, len(p) // 5000)], k=2)[0][:, 1]))
    diag = float(np.linalg.norm(p.max(0) - p.min(0)))
    view = np.asarray(case.view, dtype=np.float64)
    view /= np.linalg.norm(view)
    ax = np.cross(view, [0.0, 1.0, 0.0] if abs(view[1]) < 0.9 else [1.0, 0.0, 0.0])
    ax /= np.linalg.norm(ax)
    ay = np.cross(view, ax)
    x, y, depth = p @ ax, p @ ay, p @ view
    ix = np.floor((x - x.min()) / (2.0 * h)).astype(int)
    iy = np.floor((y - y.min()) / (2.0 * h)).astype(int)
    key = ix * (iy.max() + 1) + iy
    zmin = np.full(key.max() + 1, np.inf)
    np.minimum.at(zmin, key, depth)
    visible = (depth <= zmin[key] + 3.0 * h) & ((n @ view) < 0.2)
    target = int(np.argmax(np.where(visible, p @ np.asarray(case.target, dtype=np.float64), -np.inf)))
    dxy = np.hypot(x - x[target], y - y[target])
    return visible & (dxy < case.support_frac * diag), visible & (dxy < case.handle_frac * diag), h, diag


@dataclass(frozen=True)
class NeedleResult:
    case: str
    mode: str
    moved: int
    broken: int             # moved support splats stretched beyond 4x (heat-map stretch)
    max_stretch: float
    p99_stretch: float
    tears: int
    handle_error: float     # relative to the diagonal
    fixed_error: float      # relative to the diagonal
    seconds: float          # commit (+ refinement)

    @property
    def share(self) -> float:
        return self.broken / max(self.moved, 1)


def prepare(name: str):
    """(cloud, basis, translation (4, 4), spacing h, diagonal) of a case."""
    from splatedit.deform.basis import DeformationBasis
    from splatedit.deform.transform import translate
    from splatedit.select.closure import closed_masks
    case = CASES[name]
    cloud = load(case.model)
    sup, hd, h, diag = paint(cloud, case)
    sup, hs, _ = closed_masks(cloud, sup, [hd])
    basis = DeformationBasis.fit(cloud, sup, hs)
    d = np.asarray(case.move, dtype=np.float64)
    return cloud, basis, translate(case.move_frac * diag * d / np.linalg.norm(d)), h, diag


def measure(name: str, cloud, basis, m: np.ndarray, h: float, diag: float, mode: DeformationMode,
            pairs=None) -> NeedleResult:
    """Commit the translation ``m`` in ``mode`` as ``splatedit deform`` does
    (the rotation mode's refinement included) and measure it."""
    from splatedit.deform.distortion import distortion_from_axes
    from splatedit.deform.refine import refine_committed
    t0 = time.perf_counter()
    new = basis.commit(cloud, basis.displacement([m], mode=mode))
    new = refine_committed(basis, cloud, new, mode, [m])[0]
    seconds = time.perf_counter() - t0
    idx = basis.indices
    st = distortion_from_axes(cloud.u[idx], cloud.v[idx], new.u[idx], new.v[idx]).stretch
    moved = np.linalg.norm(new.positions - cloud.positions, axis=1) > 1e-9 * diag
    st = st[moved[idx]] if moved.any() else np.ones(1)
    if pairs is None:
        pairs = cKDTree(cloud.positions).query_pairs(2.0 * h, output_type="ndarray")
    q = new.positions
    tears = int((np.linalg.norm(q[pairs[:, 0]] - q[pairs[:, 1]], axis=1) > 8.0 * h).sum())
    con = basis.constraints
    hi = np.concatenate(con.handle_index)
    herr = float(np.abs(q[hi] - (cloud.positions[hi] + m[:3, 3])).max()) / diag
    fi = con.fixed_index
    ferr = float(np.abs(q[fi] - cloud.positions[fi]).max()) / diag if len(fi) else 0.0
    return NeedleResult(name, DeformationMode(mode).value, int(moved.sum()), int((st > 4.0).sum()),
                        float(st.max()), float(np.percentile(st, 99)), tears, herr, ferr, seconds)


def run(names) -> list[NeedleResult]:
    out = []
    for name in names:
        cloud, basis, m, h, diag = prepare(name)
        pairs = cKDTree(cloud.positions).query_pairs(2.0 * h, output_type="ndarray")
        for mode in (DeformationMode.LINEAR, DeformationMode.ROTATION):
            r = measure(name, cloud, basis, m, h, diag, mode, pairs)
            out.append(r)
            print(f"| {r.case} | {r.mode} | {r.moved} | {r.broken} ({100 * r.share:.2f} %) | {r.max_stretch:.1f} "
                  f"| {r.p99_stretch:.2f} | {r.tears} | {r.handle_error:.1e} | {r.fixed_error:.1e} "
                  f"| {r.seconds:.2f} |", flush=True)
    return out


def main(argv=None) -> int:
    from pathlib import Path
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", default=",".join(CASES))
    a = ap.parse_args(argv)
    names = [n for n in a.cases.split(",") if n]
    bad = [n for n in names if n not in CASES]
    if bad:
        ap.error(f"unknown case {bad[0]!r} (expected one of {', '.join(CASES)})")
    names = [n for n in names if CASES[n].model == "bunny" or Path(CASES[n].model).exists()]
    print("| case | mode | moved | beyond 4x | max | p99 | tears | handle error | fixed error | commit s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    run(names)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
