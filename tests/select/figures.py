"""Synthetic figures for the closure tests: surfaces sampled at a spacing
``h`` with outward normals (splat axes ``u x v`` point out of the material),
the way a scanner samples limbs and heads."""

from __future__ import annotations

import numpy as np

from splatedit.model.cloud import SplatCloud


def _tangents(normals: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
    """Splat axes (n, 3) each, half the spacing long, with u x v along ``normals``."""
    a = np.where(np.abs(normals[:, 1:2]) < 0.9, [[0.0, 1.0, 0.0]], [[1.0, 0.0, 0.0]])
    u = np.cross(a, normals)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(normals, u)
    return 0.6 * h * u, 0.6 * h * v


def limb(axis_xz, radius: float, y0: float, y1: float, h: float, cap_low: bool = True):
    """Points and outward normals of a vertical (along y) limb through
    ``axis_xz`` (2,), from ``y0`` to ``y1``, with a disc cap at ``y0``: a
    cylinder whose radius swells by 10% along it (a plain cylinder is a
    quadric, which the RBF's polynomial part must treat apart, see issue 20)."""
    k = max(8, int(round(2 * np.pi * radius / h)))
    t = 2 * np.pi * np.arange(k) / k
    ys = np.arange(y0, y1 + 1e-9, h)
    tt, yy = (a.ravel() for a in np.meshgrid(t, ys))
    s = (yy - y0) / (y1 - y0)
    rr = radius * (1 + 0.1 * np.sin(np.pi * s))
    drr = radius * 0.1 * np.pi * np.cos(np.pi * s) / (y1 - y0)           # d r / d y
    nrm = np.column_stack([np.cos(tt), -drr, np.sin(tt)])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    pts = np.column_stack([axis_xz[0] + rr * np.cos(tt), yy, axis_xz[1] + rr * np.sin(tt)])
    if cap_low:
        cp, cn = [], []
        for r in np.arange(radius - h, 0, -h):
            m = max(6, int(round(2 * np.pi * r / h)))
            s = 2 * np.pi * (np.arange(m) + 0.5) / m
            cp.append(np.column_stack([axis_xz[0] + r * np.cos(s), np.full(m, y0), axis_xz[1] + r * np.sin(s)]))
        cp.append([[axis_xz[0], y0, axis_xz[1]]])
        cp = np.vstack(cp)
        cn = np.tile([0.0, -1.0, 0.0], (len(cp), 1))
        pts, nrm = np.vstack([pts, cp]), np.vstack([nrm, cn])
    return pts, nrm


def sphere(center, radius: float, h: float):
    """Points and outward normals of a sphere sampled at spacing ``h``
    (Fibonacci lattice)."""
    n = int(round(4 * np.pi * radius ** 2 / h ** 2))
    i = np.arange(n) + 0.5
    y = 1 - 2 * i / n
    r = np.sqrt(1 - y * y)
    phi = np.pi * (1 + 5 ** 0.5) * i
    nrm = np.column_stack([r * np.cos(phi), y, r * np.sin(phi)])
    return np.asarray(center) + radius * nrm, nrm


def cloud_of(parts, h: float, name: str) -> SplatCloud:
    """A :class:`SplatCloud` of the (points, normals) ``parts``."""
    pts = np.vstack([p for p, _ in parts])
    nrm = np.vstack([n for _, n in parts])
    u, v = _tangents(nrm, h)
    return SplatCloud(pts, u, v, name=name)


def hand_next_to_thigh(h: float = 0.1, gap: float = 0.25):
    """An arm (radius 0.5, from y = 2 down to its capped hand end at y = -5)
    next to a thigh (radius 1, from y = -8 to 1) ``gap`` away, as a figure
    standing with its arms down.  Returns (cloud, arm mask, thigh mask)."""
    arm = limb((0.0, 0.0), 0.5, -5.0, 2.0, h)
    thigh = limb((0.5 + gap + 1.0, 0.0), 1.0, -8.0, 1.0, h)
    cloud = cloud_of([arm, thigh], h, "hand-next-to-thigh")
    is_arm = np.zeros(cloud.n, bool)
    is_arm[:len(arm[0])] = True
    return cloud, is_arm, ~is_arm


def head_on_neck(h: float = 0.06):
    """A head (sphere of radius 1 about (0, 1.5, 0)) on a neck (radius 0.4,
    y from -1 to where it meets the head); the parts' points inside each
    other are left out.  Returns (cloud, head mask)."""
    c = np.array([0.0, 1.5, 0.0])
    hp, hn = sphere(c, 1.0, h)
    keep = ~((np.hypot(hp[:, 0], hp[:, 2]) < 0.4) & (hp[:, 1] < c[1]))
    neck_top = c[1] - np.sqrt(1 - 0.4 ** 2)
    np_, nn = limb((0.0, 0.0), 0.4, -1.0, neck_top, h)
    cloud = cloud_of([(hp[keep], hn[keep]), (np_, nn)], h, "head-on-neck")
    head = np.zeros(cloud.n, bool)
    head[:int(keep.sum())] = True
    return cloud, head
