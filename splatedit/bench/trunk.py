"""Curve bend of an elephant-trunk-like part (issue 19 item 4).

A tapered, slightly curved open tube with a swelling half-way (so it is not
an exact quadric), running from a fixed stump (``z < 0``) to its tip at
``z = LENGTH``.  The support is the trunk (``z >= 0``); a control curve of
:data:`CURVE_POINTS` points runs along its front surface from base to tip and
the tip point is dragged sideways (+x) by :data:`DRAG` times the length.
Figures: the largest principal stretch of the support splats
(:func:`~splatedit.deform.distortion.distortion_from_axes`), how far the
moved picked points miss their targets, and the *knob*: how far the tip's
cross-section ring moved compared with the tip point itself (1 = the whole
tip follows the curve; the linear mode leaves the far side behind).

    python -m splatedit.bench.trunk                 # one JSON line per mode
    python -m splatedit.bench.trunk --images DIR    # and PNGs: before, linear, rotation
    python -m splatedit.bench.trunk --cost          # per-frame milliseconds, 31k splats
"""

from __future__ import annotations

import json
import sys

import numpy as np

from splatedit.deform.basis import DeformationBasis
from splatedit.deform.distortion import distortion_from_axes
from splatedit.deform.modes import DeformationMode
from splatedit.model.cloud import SplatCloud

#: trunk length, base radius (model units); the stump below z = 0 is fixed
LENGTH = 1.0
RADIUS = 0.12
STUMP = 0.25
#: picked curve points, base to tip; sideways drag of the tip (times LENGTH)
CURVE_POINTS = 5
DRAG = 0.4


def axis(z):
    """(n, 3) points of the trunk's (curved) centre line at heights z."""
    z = np.asarray(z, dtype=np.float64)
    return np.column_stack([np.zeros_like(z), 0.12 * np.clip(z, 0.0, None) ** 2, z])


def radius(z):
    """Tube radius at heights z: tapering to half at the tip, a 15 % swelling at z = 0.5."""
    z = np.clip(np.asarray(z, dtype=np.float64), 0.0, LENGTH)
    return RADIUS * (1.0 - 0.5 * z / LENGTH) * (1.0 + 0.15 * np.exp(-((z - 0.5) / 0.12) ** 2))


def trunk_cloud(spacing: float = 0.02) -> SplatCloud:
    """The trunk and its stump: an open tube of splats about ``spacing`` apart
    (about 3,000 splats at the default), axes tangent (u around, v along)."""
    z = np.arange(-STUMP, LENGTH + 1e-9, spacing)
    pos, us, vs = [], [], []
    for i, zi in enumerate(z):
        r = float(radius(zi))
        n = max(8, int(round(2.0 * np.pi * r / spacing)))
        a = 2.0 * np.pi * (np.arange(n) + 0.5 * (i % 2)) / n
        c = axis([zi])[0]
        ring = np.column_stack([r * np.cos(a), r * np.sin(a), np.zeros(n)]) + c
        pos.append(ring)
        us.append(0.75 * spacing * np.column_stack([-np.sin(a), np.cos(a), np.zeros(n)]))
        d = axis([zi + 1e-4])[0] - c
        vs.append(np.tile(0.75 * spacing * d / np.linalg.norm(d), (n, 1)))
    pos, u, v = np.concatenate(pos), np.concatenate(us), np.concatenate(vs)
    v = v - (v * u).sum(1, keepdims=True) / (u * u).sum(1, keepdims=True) * u   # orthogonal axes
    v *= 0.75 * spacing / np.linalg.norm(v, axis=1, keepdims=True)
    return SplatCloud(pos, u, v, name="trunk")


def curve_points(n: int = CURVE_POINTS, inset: float = 0.0) -> np.ndarray:
    """(n, 3) picked points on the trunk's front (+y) surface, base to tip
    (``inset``: how far inside the surface, times the local radius)."""
    z = np.linspace(0.02, LENGTH, n)
    return axis(z) + np.column_stack([np.zeros(n), (1.0 - inset) * radius(z), np.zeros(n)])


def trunk_edit(cloud: SplatCloud | None = None, method: str = "lu"):
    """``(cloud, basis, curve points, moves)``: the fitted trunk edit and the
    picked points' displacements (the tip dragged by DRAG * LENGTH along +x)."""
    cloud = trunk_cloud() if cloud is None else cloud
    support = cloud.positions[:, 2] >= 0.0
    q = curve_points()
    basis = DeformationBasis.fit(cloud, support, curves=[q], method=method)
    moves = np.zeros_like(q)
    moves[-1, 0] = DRAG * LENGTH
    return cloud, basis, q, moves


def measure(cloud, basis, q, moves, mode) -> dict:
    """Figures of one mode (see the module docstring)."""
    dc = basis.displacement([moves], mode=mode)
    pos, u, v = basis.apply_arrays(cloud, dc)
    idx = basis.indices
    st = distortion_from_axes(cloud.u[idx], cloud.v[idx], u[idx], v[idx])
    tip = cloud.positions[:, 2] >= LENGTH - 0.03            # the tip's last rings
    ring_move = np.linalg.norm(pos[tip] - cloud.positions[tip], axis=1)
    from splatedit.deform.curve_frames import deform_points
    landed = deform_points(basis, dc, q)
    miss = float(np.abs(landed - (q + moves)).max()) / cloud.diagonal
    return dict(mode=DeformationMode(mode).value, max_stretch=round(st.max_stretch, 3),
                p99_stretch=round(float(np.quantile(st.stretch, 0.99)), 3),
                over_4x=int(st.n_above_broken), tip_ring_follows=round(float(ring_move.min() / (DRAG * LENGTH)), 3),
                curve_point_miss_rel=miss, n_splats=int(cloud.n))


def render_figures(out_dir, cloud, basis, moves, size=(480, 480)) -> list:
    """PNGs of the trunk seen from the curve's side: undeformed, the linear
    mode and the rotation mode (curve frames).  Returns their paths."""
    from pathlib import Path

    from splatedit.render.camera import Camera
    from splatedit.render.splat.headless import render_to_png
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    cam = Camera((0.2, 3.2, 0.45), (0.2, 0.0, 0.45), up=(0.0, 0.0, 1.0), fov_deg=30.0)
    paths = [render_to_png(cloud, out_dir / "trunk-before.png", size=size, camera=cam)]
    for mode in (DeformationMode.LINEAR, DeformationMode.ROTATION):
        moved = basis.apply(cloud, basis.displacement([moves], mode=mode))
        paths.append(render_to_png(moved, out_dir / f"trunk-{mode.value}.png", size=size, camera=cam))
    return paths


def cost(spacing: float = 0.005, repeats: int = 5) -> dict:
    """Milliseconds (best of ``repeats``, same process) of one frame of the
    trunk edit at ``spacing``: ``displacement`` in the rotation mode (frame
    tables and residual solve), ``apply_arrays`` and ``jacobians`` with the
    curve frames and, side by side, with the linear mode's dC."""
    import os
    import time
    cloud, basis, _, moves = trunk_edit(trunk_cloud(spacing), method="auto")

    def best(f):
        ts = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            f()
            ts.append(time.perf_counter() - t0)
        return round(1e3 * min(ts), 2)
    lin = basis.displacement([moves], mode=DeformationMode.LINEAR)
    fr = basis.displacement([moves], mode=DeformationMode.ROTATION)
    basis.apply_arrays(cloud, lin)
    basis.apply_arrays(cloud, fr)
    return dict(splats=int(cloud.n), support=int(len(basis.indices)),
                displacement_ms=best(lambda: basis.displacement([moves], mode=DeformationMode.ROTATION)),
                apply_linear_ms=best(lambda: basis.apply_arrays(cloud, lin)),
                apply_frames_ms=best(lambda: basis.apply_arrays(cloud, fr)),
                jacobians_linear_ms=best(lambda: basis.jacobians(lin)),
                jacobians_frames_ms=best(lambda: basis.jacobians(fr)),
                load_average=round(os.getloadavg()[0], 1))


def main(argv=None) -> int:
    """``python -m splatedit.bench.trunk [--images DIR | --cost]``."""
    argv = sys.argv[1:] if argv is None else argv
    if argv == ["--cost"]:
        print(json.dumps(cost()))
        return 0
    cloud, basis, q, moves = trunk_edit()
    for mode in (DeformationMode.LINEAR, DeformationMode.ROTATION):
        print(json.dumps(measure(cloud, basis, q, moves, mode)))
    if argv[:1] == ["--images"] and len(argv) == 2:
        for p in render_figures(argv[1], cloud, basis, moves):
            print(f"wrote {p}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
