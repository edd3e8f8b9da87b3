"""Shared scenes of the edit-session tests: a flat grid of splats and a fixed view."""

from __future__ import annotations

import numpy as np

from splatedit.app.document.session import ViewInfo
from splatedit.model import SplatCloud


def plane_cloud(k: int = 30) -> SplatCloud:
    """k x k splats on the z = 0 square [-1, 1]^2, axes one grid step long."""
    xs, ys = np.meshgrid(np.linspace(-1, 1, k), np.linspace(-1, 1, k))
    p = np.c_[xs.ravel(), ys.ravel(), np.zeros(k * k)]
    r = 2.0 / (k - 1)
    n = len(p)
    return SplatCloud(p, np.tile([r, 0, 0], (n, 1)), np.tile([0, r, 0], (n, 1)), name="plane")


def view() -> ViewInfo:
    """Looking down -z, pivot at pixel (100, 100), 0.01 model units per pixel."""
    return ViewInfo(right=np.array([1.0, 0, 0]), up=np.array([0, 1.0, 0]), back=np.array([0, 0, 1.0]),
                    pivot_px=(100.0, 100.0), world_per_px=0.01)
