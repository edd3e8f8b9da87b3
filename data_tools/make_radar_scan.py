#!/usr/bin/env python3
"""Synthetic scans of a rotating range sensor (lidar or scanning radar), xyz only.

The held-out scan of issue 23 ("a radar-like scan, xyz only") is not available;
these scans reproduce what makes such data hard for splat sizing:

* a rotating sensor's pattern: returns along beams at fixed elevations and a
  fixed azimuth step, so the spacing grows linearly with range and is very
  anisotropic far away (dense along a ring, sparse across rings); rings are
  dense next to the sensor;
* thin structures: poles (vertical cylinders) and sagging wires between them,
  hit by a few beams only;
* open borders: the ground ends at the maximum range, walls end at their edges;
* outliers: multipath ghosts (a second return behind a wall, further along
  the same beam: a mirrored, sparser copy of the wall), isolated far returns
  and dust next to the sensor;
* range noise, a radar's range bins, and coordinates quantised to a millimetre
  grid and stored as float32, as scan files are.

The scene is ray cast exactly (ground plane, axis-aligned boxes, vertical
poles, wires as cylinders about a polyline).  Everything is seeded.

Usage: python data_tools/make_radar_scan.py OUT.xyz [--kind lidar|radar] [--seed S]
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Sensor:
    """A rotating range sensor.

    Attributes:
        elevations_deg: beam elevations (degrees above the horizon).
        azimuth_step_deg: angle between two firings of one beam (degrees).
        max_range: returns beyond this are lost (metres).
        range_noise: standard deviation of the range (metres).
        range_bin: ranges are rounded to multiples of this (metres; 0: none).
        ghost_share: share of wall returns that also give a multipath ghost.
        far_returns: isolated returns 1.5-5 max ranges away.
        dust: returns 0.3-2 m from the sensor in random directions.
    """

    elevations_deg: tuple
    azimuth_step_deg: float
    max_range: float
    range_noise: float
    range_bin: float
    ghost_share: float
    far_returns: int
    dust: int


def lidar() -> Sensor:
    """A 32-beam spinning lidar (rings denser near the horizon), 0.2 degree steps."""
    el = np.concatenate([np.linspace(-25.0, -8.0, 10), np.linspace(-7.0, 3.0, 18),
                         np.linspace(5.0, 15.0, 4)])
    return Sensor(tuple(el), 0.2, 80.0, 0.01, 0.0, 0.02, 12, 20)


def radar() -> Sensor:
    """A scanning radar: 12 coarse beams, 0.8 degree steps, 5 cm range bins,
    more multipath."""
    return Sensor(tuple(np.linspace(-20.0, 8.0, 12)), 0.8, 60.0, 0.03, 0.05, 0.08, 20, 30)


SENSORS = {"lidar": lidar, "radar": radar}


def _scene(rng):
    """Boxes (lo, hi), poles (x, y, radius, height) and wires (polyline, radius)."""
    boxes = []
    for _ in range(6):
        c = rng.uniform(-45, 45, 2)
        while np.linalg.norm(c) < 10:
            c = rng.uniform(-45, 45, 2)
        half = rng.uniform([2, 2], [8, 12])
        h = rng.uniform(3, 12)
        boxes.append((np.array([c[0] - half[0], c[1] - half[1], 0.0]),
                      np.array([c[0] + half[0], c[1] + half[1], h])))
    poles = []
    x0, y0 = rng.uniform(-30, -10), rng.uniform(4, 8)
    for i in range(6):                        # a row of poles along a street
        poles.append((x0 + 9.0 * i, y0, rng.uniform(0.08, 0.15), 7.0))
    for _ in range(4):
        poles.append((*rng.uniform(-30, 30, 2), rng.uniform(0.05, 0.3), rng.uniform(2, 9)))
    wires = []
    for a, b in zip(poles[:5], poles[1:6]):   # sagging wires between the row's tops
        s = np.linspace(0, 1, 17)
        xy = np.outer(1 - s, a[:2]) + np.outer(s, b[:2])
        z = a[3] - 0.3 - 1.2 * 4 * s * (1 - s)
        wires.append((np.column_stack([xy, z]), 0.03))
    return boxes, poles, wires


def _hit_ground(o, d):
    t = np.full(len(d), np.inf)
    down = d[:, 2] < -1e-9
    t[down] = -o[2] / d[down, 2]
    return t


def _hit_boxes(o, d, boxes):
    t = np.full(len(d), np.inf)
    wall = np.zeros(len(d), dtype=bool)
    inv = 1.0 / np.where(np.abs(d) < 1e-12, 1e-12, d)
    for lo, hi in boxes:
        a, b = (lo - o) * inv, (hi - o) * inv
        tmin = np.minimum(a, b).max(axis=1)
        tmax = np.maximum(a, b).min(axis=1)
        ok = (tmax >= tmin) & (tmin > 0) & (tmin < t)
        t[ok] = tmin[ok]
        wall |= ok
    return t


def _hit_poles(o, d, poles):
    t = np.full(len(d), np.inf)
    for x, y, r, h in poles:
        ox, oy = o[0] - x, o[1] - y
        a = d[:, 0] ** 2 + d[:, 1] ** 2
        b = 2 * (ox * d[:, 0] + oy * d[:, 1])
        c = ox * ox + oy * oy - r * r
        disc = b * b - 4 * a * c
        ok = disc >= 0
        s = np.where(ok, (-b - np.sqrt(np.maximum(disc, 0))) / (2 * np.maximum(a, 1e-12)), np.inf)
        z = o[2] + s * d[:, 2]
        ok &= (s > 0) & (z >= 0) & (z <= h) & (s < t)
        t[ok] = s[ok]
    return t


def _hit_wires(o, d, wires):
    """A hit where a ray passes closer than the wire's radius to one of its
    segments (thin wires: the ray's distance to the segment)."""
    t = np.full(len(d), np.inf)
    for line, r in wires:
        p, e = line[:-1], line[1:] - line[:-1]                 # (s, 3) segment starts, vectors
        w0 = o - p                                             # (s, 3)
        b = d @ e.T                                            # (n, s); |d| = 1
        c = np.einsum("sj,sj->s", e, e)
        dd = d @ w0.T
        ee = np.einsum("sj,sj->s", e, w0)
        den = np.maximum(c - b * b, 1e-12)
        u = np.clip((ee - b * dd) / den, 0.0, 1.0)             # on the segment
        s = u * b - dd                                         # along the ray
        gap2 = (np.einsum("sj,sj->s", w0, w0) + s * s + u * u * c + 2 * s * dd
                - 2 * u * ee - 2 * s * u * b)
        ok = (gap2 < r * r) & (s > 0)
        near = np.where(ok, s, np.inf).min(axis=1)
        t = np.minimum(t, near)
    return t


def _beams(el, az):
    """(len(el) * len(az), 3) unit directions, elevation-major (radians in)."""
    E, A = np.meshgrid(el, az, indexing="ij")
    return np.column_stack([(np.cos(E) * np.cos(A)).ravel(), (np.cos(E) * np.sin(A)).ravel(),
                            np.sin(E).ravel()])


def _cast(o, d, boxes, poles, wires):
    """Range of the first hit of every beam (inf: none) and of the boxes alone."""
    tb = _hit_boxes(o, d, boxes)
    t = np.minimum.reduce([_hit_ground(o, d), tb, _hit_poles(o, d, poles), _hit_wires(o, d, wires)])
    return t, tb


def surface_probes(kind: str = "lidar", seed: int = 0, origins=((0.0, 0.0, 1.8),),
                   fine: int = 4) -> np.ndarray:
    """Points of the scene's surfaces that :func:`rotating_scan` (same kind,
    seed and origins) sees, sampled ``fine`` times more densely in azimuth
    and elevation (between its beams), exact (no noise): probes of which
    surface a scan's splats should cover.  Returns (m, 3) float64 (metres)."""
    boxes, poles, wires = _scene(np.random.default_rng(seed))
    sensor = SENSORS[kind]()
    el = np.asarray(sensor.elevations_deg)
    el = np.radians(np.interp(np.arange((len(el) - 1) * fine + 1) / fine, np.arange(len(el)), el))
    az = np.radians(np.arange(0.0, 360.0, sensor.azimuth_step_deg / fine))
    out = []
    for origin in origins:
        o = np.asarray(origin, dtype=np.float64)
        d = _beams(el, az)
        t, _ = _cast(o, d, boxes, poles, wires)
        hit = t < sensor.max_range
        out.append(o + t[hit, None] * d[hit])
    return np.vstack(out)


#: what :func:`rotating_scan` labels every point as
SURFACE, GHOST, FAR, DUST = 0, 1, 2, 3


def rotating_scan(kind: str = "lidar", seed: int = 0, origins=((0.0, 0.0, 1.8),), *,
                  labels: bool = False):
    """A synthetic scan of a rotating sensor.

    Args:
        kind: ``"lidar"`` or ``"radar"`` (:data:`SENSORS`).
        seed: scene, noise and outliers.
        origins: sensor positions (metres); one sweep from each.
    Returns:
        (n, 3) float64 positions (metres) that are float32 values of a
        millimetre grid, in firing order (beam by beam, as scan files are);
        with ``labels``, also (n,) int8: :data:`SURFACE`, :data:`GHOST`,
        :data:`FAR` or :data:`DUST`.
    """
    rng = np.random.default_rng(seed)
    sensor = SENSORS[kind]()
    boxes, poles, wires = _scene(rng)
    el = np.radians(np.asarray(sensor.elevations_deg))
    az = np.radians(np.arange(0.0, 360.0, sensor.azimuth_step_deg))
    out, tags = [], []
    for origin in origins:
        o = np.asarray(origin, dtype=np.float64)
        azj = az + rng.uniform(0, np.radians(sensor.azimuth_step_deg))   # sweeps do not align
        d = _beams(el, azj)
        t, tb = _cast(o, d, boxes, poles, wires)
        hit = t < sensor.max_range
        on_wall = hit & (tb == t)
        rng_t = t + rng.normal(0.0, sensor.range_noise, len(t))
        if sensor.range_bin:
            rng_t = np.round(rng_t / sensor.range_bin) * sensor.range_bin
        pts = [o + rng_t[hit, None] * d[hit]]
        # multipath: the beam bounces off the wall onto something and back,
        # seen further along the same beam
        ghost = on_wall & (rng.random(len(t)) < sensor.ghost_share)
        extra = rng.uniform(2.0, 15.0, int(ghost.sum()))
        pts.append(o + (rng_t[ghost] + extra)[:, None] * d[ghost])
        # isolated far returns along random beams, dust next to the sensor
        far = rng.choice(len(d), sensor.far_returns, replace=False)
        pts.append(o + rng.uniform(1.5, 5.0, (len(far), 1)) * sensor.max_range * d[far])
        dd = rng.normal(size=(sensor.dust, 3))
        dd /= np.linalg.norm(dd, axis=1, keepdims=True)
        pts.append(o + rng.uniform(0.3, 2.0, (sensor.dust, 1)) * dd)
        out.append(np.vstack(pts))
        tags.append(np.repeat(np.array([SURFACE, GHOST, FAR, DUST], dtype=np.int8),
                              [len(x) for x in pts]))
    p = np.round(np.vstack(out), 3).astype(np.float32).astype(np.float64)
    return (p, np.concatenate(tags)) if labels else p


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("--kind", choices=sorted(SENSORS), default="lidar")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--sweeps", type=int, default=1,
                    help="sensor positions 6 m apart along x (one sweep each)")
    a = ap.parse_args(argv)
    origins = [(6.0 * i, 0.0, 1.8) for i in range(a.sweeps)]
    p = rotating_scan(a.kind, a.seed, origins)
    np.savetxt(a.out, p, fmt="%.3f")
    print(f"{a.out}: {len(p):,} points ({a.kind}, seed {a.seed}, {a.sweeps} sweep(s))")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
