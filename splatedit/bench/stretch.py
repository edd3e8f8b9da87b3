"""Worst splat stretch of rotated one-view edits: rotation-aware vs linear mode.

A user paints the support and the handle from one view with a visible-only
brush (like ``/work/shared/tools/one_view_edit.py``: splats that face the
viewer and are not occluded, inside a screen disc around the model's highest
point) and turns the handle with the gizmo about an axis along the view
direction, through a pivot at some distance from the handle's centroid
(0: through the handle; 1: at the handle's edge; larger: far away, towards
the model's centre).  For each angle, pivot distance and mode it reports

  tears       input neighbours closer than 2 h that end up more than 8 h apart
              (h: median spacing)
  stretch     per splat max(|u'|/|u|, |u|/|u'|, |v'|/|v|, |v|/|v'|): the
              largest and the 99th percentile over the splats that moved

in the linear mode, the rotation mode, and the rotation mode with every handle
turned about its pivot (before :mod:`splatedit.deform.rotation_centre`).

    python -m splatedit.bench.stretch [MODEL ...] [--axes view,towards,side] [--table]
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import asdict, dataclass

import numpy as np
from scipy.spatial import cKDTree

from splatedit.deform.basis import DeformationBasis
from splatedit.deform.modes import DeformationMode
from splatedit.deform.transform import rotate

#: the sweep: gizmo angles (degrees) and pivot distances (handle radii)
ANGLES = (30.0, 60.0, 90.0, 120.0, 150.0, 180.0)
DISTANCES = (0.0, 1.0, 3.0, 8.0)
#: brush radii as fractions of the bounding-box diagonal (one_view_edit.py's defaults)
SUPPORT_FRAC = 0.16
HANDLE_FRAC = 0.045


@dataclass(frozen=True)
class OneViewEdit:
    """Support and handle painted from one view.

    Attributes:
        support, handle: (n,) bool masks.
        view: (3,) unit viewing direction (towards the model).
        centroid: (3,) the handle's centroid (model units).
        radius: the handle brush's radius (model units).
        towards: (3,) unit vector perpendicular to ``view`` from the handle's
            centroid towards the model's centre (where far pivots are put).
        spacing: median splat spacing h (model units).
    """
    support: np.ndarray
    handle: np.ndarray
    view: np.ndarray
    centroid: np.ndarray
    radius: float
    towards: np.ndarray
    spacing: float


def one_view_edit(cloud, view=(1.0, 0.0, 0.0), support_frac: float = SUPPORT_FRAC,
                  handle_frac: float = HANDLE_FRAC) -> OneViewEdit:
    """Paint support and handle around the highest point (largest y) of
    ``cloud`` from ``view`` with a visible-only brush (orthographic, z-buffer
    of 2 h cells, splats facing the viewer)."""
    p = cloud.positions
    n = np.cross(cloud.u, cloud.v)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    tree = cKDTree(p)
    h = float(np.median(tree.query(p[:: max(1, len(p) // 5000)], k=2)[0][:, 1]))
    diag = float(np.linalg.norm(p.max(0) - p.min(0)))
    view = np.asarray(view, dtype=np.float64)
    view = view / np.linalg.norm(view)
    ax = np.cross(view, [0.0, 1.0, 0.0] if abs(view[1]) < 0.9 else [1.0, 0.0, 0.0])
    ax /= np.linalg.norm(ax)
    ay = np.cross(view, ax)
    x, y, depth = p @ ax, p @ ay, p @ view
    cell = 2.0 * h
    ix = np.floor((x - x.min()) / cell).astype(int)
    iy = np.floor((y - y.min()) / cell).astype(int)
    key = ix * (iy.max() + 1) + iy
    zmin = np.full(key.max() + 1, np.inf)
    np.minimum.at(zmin, key, depth)
    visible = (depth <= zmin[key] + 3.0 * h) & ((n @ view) < 0.2)
    target = int(np.argmax(p[:, 1]))
    dxy = np.hypot(x - x[target], y - y[target])
    support = visible & (dxy < support_frac * diag)
    handle = visible & (dxy < handle_frac * diag)
    g = p[handle].mean(axis=0)
    to = p.mean(axis=0) - g
    to -= (to @ view) * view
    return OneViewEdit(support, handle, view, g, handle_frac * diag, to / np.linalg.norm(to), h)


#: the gizmo axes of the sweep: axis direction and the direction in which the
#: pivot is moved away from the handle (both relative to the one-view edit)
AXES = ("view", "towards", "side")


@dataclass(frozen=True)
class StretchResult:
    mode: str                  # linear, rotation, or rotation-pivot (every handle turned about its pivot)
    axis: str                  # one of AXES
    degrees: float
    distance: float            # pivot distance from the handle's centroid, handle radii
    tears: int
    max_stretch: float
    p99_stretch: float
    stretched: int             # splats stretched more than 4x


def stretch_figures(cloud, out, spacing: float, pairs=None) -> tuple[int, float, float, int]:
    """(tears, max stretch, 99th-percentile stretch, splats > 4x) of a
    deformed copy ``out`` of ``cloud`` (stretch over the splats that moved)."""
    if pairs is None:
        pairs = cKDTree(cloud.positions).query_pairs(2.0 * spacing, output_type="ndarray")
    q = out.positions
    tears = int((np.linalg.norm(q[pairs[:, 0]] - q[pairs[:, 1]], axis=1) > 8.0 * spacing).sum())
    ru = np.linalg.norm(out.u, axis=1) / np.linalg.norm(cloud.u, axis=1)
    rv = np.linalg.norm(out.v, axis=1) / np.linalg.norm(cloud.v, axis=1)
    r = np.maximum.reduce([ru, 1.0 / ru, rv, 1.0 / rv])
    diag = float(np.linalg.norm(cloud.positions.max(0) - cloud.positions.min(0)))
    moved = np.linalg.norm(q - cloud.positions, axis=1) > 1e-9 * diag
    r = r[moved] if moved.any() else np.ones(1)
    return tears, float(r.max()), float(np.percentile(r, 99)), int((r > 4.0).sum())


def pivot_transform(edit: OneViewEdit, degrees: float, distance: float, axis: str = "view") -> np.ndarray:
    """(4, 4) gizmo rotation by ``degrees`` about an axis through a pivot
    ``distance`` handle radii from the handle's centroid.  ``axis``: "view"
    (the view direction, pivot towards the model's centre), "towards" (the
    screen direction towards the model's centre, pivot sideways), "side"
    (the screen direction across it, pivot towards the centre)."""
    side = np.cross(edit.view, edit.towards)
    direction, away = {"view": (edit.view, edit.towards), "towards": (edit.towards, side),
                       "side": (side, edit.towards)}[axis]
    return rotate(direction, degrees, edit.centroid + distance * edit.radius * away)


def sweep(cloud, basis: DeformationBasis, edit: OneViewEdit, angles=ANGLES, distances=DISTANCES,
          axes=("view",), pivot_too: bool = True) -> list[StretchResult]:
    """Stretch figures of every axis x distance x angle in the linear and the
    rotation mode (and, with ``pivot_too``, the rotation mode with every
    handle turned about its pivot: the behaviour before the arc centre was
    chosen, :mod:`splatedit.deform.rotation_centre`)."""
    pairs = cKDTree(cloud.positions).query_pairs(2.0 * edit.spacing, output_type="ndarray")
    probe = basis.stretch_probe
    out = []
    runs = [("linear", DeformationMode.LINEAR, probe), ("rotation", DeformationMode.ROTATION, probe)]
    if pivot_too:
        runs.append(("rotation-pivot", DeformationMode.ROTATION, None))
    try:
        for ax in axes:
            for dist in distances:
                for deg in angles:
                    m = pivot_transform(edit, deg, dist, ax)
                    for name, mode, pr in runs:
                        basis.stretch_probe = pr        # None: no probe, the pivot is kept
                        res = basis.apply(cloud, basis.displacement([m], mode=mode))
                        out.append(StretchResult(name, ax, deg, dist,
                                                 *stretch_figures(cloud, res, edit.spacing, pairs)))
    finally:
        basis.stretch_probe = probe
    return out


def fit_one_view(cloud, view=(1.0, 0.0, 0.0)) -> tuple[OneViewEdit, DeformationBasis]:
    """The one-view edit of ``cloud`` and its fitted basis."""
    edit = one_view_edit(cloud, view)
    from splatedit.select.closure import closed_masks
    sup, hs, _ = closed_masks(cloud, edit.support, [edit.handle])
    return edit, DeformationBasis.fit(cloud, sup, hs)


def table(results: list[StretchResult], model: str) -> list[str]:
    """Markdown rows: per case the linear, rotation and rotation-pivot figures
    (tears / max / 99th percentile)."""
    rows, by = [], {}
    for r in results:
        by.setdefault((r.axis, r.distance, r.degrees), {})[r.mode] = r
    for (ax, dist, deg), m in by.items():
        cells = [f"{m[k].tears} / {m[k].max_stretch:.1f} / {m[k].p99_stretch:.2f}"
                 for k in ("linear", "rotation", "rotation-pivot") if k in m]
        rows.append(f"| {model} | {ax} | {dist:g} | {deg:g} | " + " | ".join(cells) + " |")
    return rows


def main(argv=None) -> int:
    from splatedit.data import default_model_path
    from splatedit.io import read
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("models", nargs="*", default=[str(default_model_path())])
    ap.add_argument("--view", default="1,0,0", help="viewing direction (towards the model)")
    ap.add_argument("--angles", default=",".join(f"{a:g}" for a in ANGLES))
    ap.add_argument("--distances", default=",".join(f"{d:g}" for d in DISTANCES))
    ap.add_argument("--axes", default="view", help=f"comma-separated, of {', '.join(AXES)}")
    ap.add_argument("--table", action="store_true", help="markdown rows instead of JSON lines")
    a = ap.parse_args(argv)
    view = [float(x) for x in a.view.split(",")]
    angles = [float(x) for x in a.angles.split(",")]
    dists = [float(x) for x in a.distances.split(",")]
    axes = [x.strip() for x in a.axes.split(",")]
    if any(x not in AXES for x in axes):
        ap.error(f"--axes: expected names of {', '.join(AXES)}, got {a.axes!r}")
    if a.table:
        print("| model | axis | pivot distance (handle radii) | degrees | linear | rotation | "
              "rotation, pivot centre |\n|---|---|---|---|---|---|---|")
    for path in a.models:
        cloud = read(path)
        edit, basis = fit_one_view(cloud, view)
        results = sweep(cloud, basis, edit, angles, dists, axes)
        name = str(path).rsplit("/", 1)[-1]
        if a.table:
            print("\n".join(table(results, name)), flush=True)
        else:
            for r in results:
                print(json.dumps({"model": name, **asdict(r)}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
