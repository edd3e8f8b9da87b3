"""The drawn-coverage estimate behind the status line's hint for views that
show (almost) nothing (:mod:`splatedit.app.view.coverage`)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from splatedit.app.view.camera_control import OrbitCamera
from splatedit.app.view.coverage import coverage_estimate
from splatedit.model import SplatCloud

W, H = 640, 400


def post_cloud(n_around: int = 120, n_up: int = 60, radius: float = 2.0, height: float = 4.0) -> SplatCloud:
    """A scanned post: the side of a vertical (Y) cylinder, no cap, normals
    horizontal and outward (as estimated normals of a raw scan of a post)."""
    th, y = np.meshgrid(np.linspace(0, 2 * np.pi, n_around, endpoint=False), np.linspace(0, height, n_up))
    th, y = th.ravel(), y.ravel()
    p = np.c_[radius * np.cos(th), y, radius * np.sin(th)]
    s = 0.7 * max(2 * np.pi * radius / n_around, height / (n_up - 1))
    u = np.tile([0.0, s, 0.0], (len(p), 1))
    v = s * np.c_[-np.sin(th), np.zeros_like(th), np.cos(th)]
    c = SplatCloud(p, u, v, name="post")
    n = np.cross(c.u, c.v)
    assert (np.einsum("ij,ij->i", n, p * [1, 0, 1]) > 0).all()      # outward
    return c


def _camera(c: SplatCloud, pitch: float) -> OrbitCamera:
    lo, hi = c.bounds()
    cam = OrbitCamera(target=(lo + hi) / 2, pitch=pitch, scene_radius=float(np.linalg.norm(hi - lo)) / 2)
    cam.frame((lo + hi) / 2, float(np.linalg.norm(hi - lo)) / 2, W / H)
    return cam


def test_a_post_seen_from_the_top_is_flagged_and_from_the_front_not():
    """From the top (89 degrees, as the editor's Shift+7) every splat of the
    post is back-facing: nothing can be drawn and every splat is in view,
    so the view is ``tiny``; from the front half of them face the eye and
    cover a good part of the view; without back-face culling the top view
    draws the low-pass discs of the splats (a ring), still a small share."""
    c = post_cloud()
    top = coverage_estimate(c.positions, c.u, c.v, _camera(c, math.radians(89)), W, H)
    assert top.in_view == c.n and top.front == 0 and top.share == 0.0 and top.tiny
    front = coverage_estimate(c.positions, c.u, c.v, _camera(c, 0.0), W, H)
    assert front.in_view == c.n and 0.4 * c.n < front.front < 0.6 * c.n
    assert front.share > 0.05 and not front.tiny
    nocull = coverage_estimate(c.positions, c.u, c.v, _camera(c, math.radians(89)), W, H, culling=False)
    assert nocull.front == c.n and 0 < nocull.share


def test_the_estimate_bounds_the_drawn_share_and_samples_big_clouds():
    """A sampled estimate (every 4th splat) is close to the full one, and a
    few splats in view are never ``tiny`` (nothing to hint about)."""
    c = post_cloud(240, 120)
    cam = _camera(c, 0.3)
    full = coverage_estimate(c.positions, c.u, c.v, cam, W, H)
    part = coverage_estimate(c.positions, c.u, c.v, cam, W, H, sample=c.n // 4)
    assert part.in_view == pytest.approx(full.in_view, rel=0.02)
    assert part.share == pytest.approx(full.share, rel=0.1)
    few = post_cloud(10, 5)
    assert not coverage_estimate(few.positions, few.u, few.v, _camera(few, math.radians(89)), W, H).tiny
