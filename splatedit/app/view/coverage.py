"""How much of the view the model can cover, estimated on the CPU: the
status line's hint for views that show (almost) nothing although the model
is in front of the camera.

A raw scan's normals are estimated from its points: on a post, a wall or a
facade they are (almost) all horizontal, so from the top every splat is
seen edge-on, and with the renderer's back-face culling the splats whose
normal points away from the eye (on a vertical post seen from above in
perspective: nearly all of them) are not drawn at all.  The top view of
``poste_france.xyz`` (9,031 splats, 98.6 % with |n_y| < 0.2) draws no pixel.

:func:`coverage_estimate` bounds the share of the view the splats can cover
from above: the sum over the front-facing splats whose centres are in view
of their projected ellipse areas (``pi |u x v| cos / depth^2``, in pixels)
plus the renderer's low-pass disc (every drawn splat covers at least the
disc of RENDER_LOWPASS_RADIUS_PX around its centre), divided by the view's
pixels.  Overlaps only make the true share smaller, so a small bound means
a nearly empty frame.  Back-facing splats add nothing (culled), which is
what the renderer does.  Pure numpy over at most ``sample`` splats (a fixed
stride of the cloud), so it costs a few milliseconds on a 1M-splat model.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from splatedit.tolerances import (EDITOR_COVERAGE_HINT_MIN_IN_VIEW, EDITOR_COVERAGE_HINT_SHARE,
                                  EDITOR_COVERAGE_SAMPLE, RENDER_LOWPASS_RADIUS_PX)


@dataclass(frozen=True)
class Coverage:
    """``in_view``: splats (of the whole cloud, scaled up from the sample)
    whose centres project into the view area; ``front``: those of them
    facing the camera; ``share``: upper bound of the view's pixels they
    cover (0..1)."""
    in_view: int
    front: int
    share: float

    @property
    def tiny(self) -> bool:
        """Many splats in view, (almost) nothing drawn: worth a hint."""
        return self.in_view >= EDITOR_COVERAGE_HINT_MIN_IN_VIEW and self.share < EDITOR_COVERAGE_HINT_SHARE


def coverage_estimate(positions: np.ndarray, u: np.ndarray, v: np.ndarray, cam, w: int, h: int,
                      area=(0.0, 0.0, 1.0, 1.0), splat_scale: float = 1.0, culling: bool = True,
                      sample: int = EDITOR_COVERAGE_SAMPLE) -> Coverage:
    """The :class:`Coverage` of a view.

    Args:
        positions, u, v: (n, 3) splat centres and tangent axes (model units).
        cam: the :class:`~splatedit.app.view.camera_control.OrbitCamera`.
        w, h: the framebuffer (pixels).
        area: the free part of the window as fractions (x0, y0, x1, y1) (:func:`~splatedit.app.tools.camera.free_area`).
        splat_scale: the display's splat size factor (axes drawn this much longer).
        culling: back-facing splats are not drawn (the renderer's default).
        sample: at most this many splats are looked at (a fixed stride).
    """
    n = len(positions)
    if n == 0 or w <= 0 or h <= 0:
        return Coverage(0, 0, 0.0)
    stride = max(1, -(-n // max(int(sample), 1)))
    p = np.asarray(positions[::stride], float)
    a, b = np.asarray(u[::stride], float), np.asarray(v[::stride], float)
    px, depth = cam.project(p, w, h)
    x0, y0, x1, y1 = area
    inside = ((depth > 0) & (px[:, 0] >= x0 * w) & (px[:, 0] < x1 * w)
              & (px[:, 1] >= y0 * h) & (px[:, 1] < y1 * h))
    view_px = max((x1 - x0) * w * (y1 - y0) * h, 1.0)
    scale_up = n / len(p)
    if not inside.any():
        return Coverage(0, 0, 0.0)
    p, a, b, depth = p[inside], a[inside], b[inside], depth[inside]
    nrm = np.cross(a, b)
    nlen = np.linalg.norm(nrm, axis=1)
    ray = p - cam.eye
    dist = np.linalg.norm(ray, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        cos = -np.einsum("ij,ij->i", ray, nrm) / (dist * nlen)      # > 0: facing the eye
    cos = np.nan_to_num(cos, nan=0.0)
    drawn = cos > 0 if culling else np.ones(len(p), bool)
    f = h / (2.0 * math.tan(math.radians(cam.fov_deg) / 2))          # pixels per unit at depth 1
    ellipse = math.pi * nlen * np.abs(cos) * (splat_scale ** 2) * (f / np.maximum(depth, 1e-300)) ** 2
    disc = math.pi * RENDER_LOWPASS_RADIUS_PX ** 2
    share = float(np.sum(ellipse[drawn] + disc)) * scale_up / view_px
    return Coverage(int(round(inside.sum() * scale_up)), int(round(drawn.sum() * scale_up)), min(share, 1.0))


def hint(cov: Coverage, view_keys: str) -> str:
    """The status line's hint for a view with (almost) nothing drawn."""
    return (f"most splats are seen edge-on or from behind here ({cov.in_view:,} in view, "
            f"{cov.front:,} facing it): try another view ({view_keys})")
