"""What a visible-only brush selects from one view (tests and benchmarks).

A user's first stroke paints from one view and reaches only the splats that
face the viewer and are not hidden: :func:`one_view_disc` reproduces it for an
orthographic view without a renderer (a z-buffer of ``cell``-sized pixels).
The editor's own brush works on the renderer's pick map instead
(:mod:`splatedit.app.tools.pick_brush`).
"""

from __future__ import annotations

import numpy as np

#: a splat is visible when it is at most this many cells behind the z-buffer
_DEPTH_TOL_CELLS = 1.5
#: and its normal makes n . view below this (faces the viewer, or edge-on)
_FACING_MAX = 0.2


def view_axes(view) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit (right, up, view) for a viewing direction ``view`` (3,) (towards the model)."""
    d = np.asarray(view, np.float64)
    d = d / np.linalg.norm(d)
    right = np.cross(d, [0.0, 1.0, 0.0] if abs(d[1]) < 0.9 else [1.0, 0.0, 0.0])
    right /= np.linalg.norm(right)
    return right, np.cross(d, right), d


def visible_splats(positions: np.ndarray, normals: np.ndarray, view, cell: float) -> np.ndarray:
    """(n,) bool: splats facing an orthographic viewer looking along ``view``
    and not hidden behind others (z-buffer with pixels of ``cell`` model units)."""
    right, up, d = view_axes(view)
    x, y, depth = positions @ right, positions @ up, positions @ d
    ix = np.floor((x - x.min()) / cell).astype(np.int64)
    iy = np.floor((y - y.min()) / cell).astype(np.int64)
    key = ix * (iy.max() + 1) + iy
    zmin = np.full(key.max() + 1, np.inf)
    np.minimum.at(zmin, key, depth)
    return (depth <= zmin[key] + _DEPTH_TOL_CELLS * cell) & ((normals @ d) < _FACING_MAX)


def one_view_disc(positions: np.ndarray, normals: np.ndarray, view, center: np.ndarray,
                  radius: float, cell: float) -> np.ndarray:
    """(n,) bool: the visible splats (see :func:`visible_splats`) whose
    projection lies within ``radius`` (model units) of ``center``'s projection:
    one dab of a visible-only brush of that radius."""
    right, up, _ = view_axes(view)
    c = np.asarray(center, np.float64)
    dxy = np.hypot((positions - c) @ right, (positions - c) @ up)
    return visible_splats(positions, normals, view, cell) & (dxy <= radius)
