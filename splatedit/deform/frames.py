"""Control frames of handles and affine coordinates with respect to them
(paper Sect. 6: a handle's move ``dC`` of its 4 control points displaces a
point by its affine coordinates ``M`` times ``dC``).

Control frame (decision).  ``a`` = centroid of the handle splats,
``b, c, d = a + r e_x, a + r e_y, a + r e_z`` with ``r`` = RMS distance of
the handle splats to ``a`` (at least one point spacing).  Axis-aligned frames
are a regular tetrahedron corner, so the affine coordinates are
``(1 - sum(x - a) / r, (x - a) / r)``: bounded by O(1) on the handle and
well conditioned whatever the handle's shape (flat, a line, one splat) --
a PCA frame would degenerate for flat handles.
"""

from __future__ import annotations

import numpy as np

from splatedit.errors import ParameterError
from splatedit.tolerances import FRAME_MIN_DET_REL


def handle_frame(points: np.ndarray, spacing: float = 0.0) -> np.ndarray:
    """Control frame (4, 3) ``(a, b, c, d)`` of a handle: ``a`` its centroid,
    ``b, c, d`` = ``a + r e_x``, ``a + r e_y``, ``a + r e_z`` with ``r`` the RMS
    distance of ``points`` to the centroid, at least ``spacing`` (and > 0)."""
    pts = np.asarray(points, dtype=np.float64)
    a = pts.mean(axis=0)
    r = float(np.sqrt(np.mean(np.sum((pts - a) ** 2, axis=1))))
    r = max(r, float(spacing))
    if not r > 0.0:
        r = max(1.0, float(np.abs(a).max()))  # one splat and no spacing known
    return np.vstack([a, a + r * np.eye(3)])


def _frame_inverse(frame: np.ndarray) -> np.ndarray:
    """(3, 3) G with ``lambda_bcd(x) = G (x - a)`` for a non-degenerate frame."""
    c = np.asarray(frame, dtype=np.float64)
    if c.shape != (4, 3):
        raise ParameterError("frame", f"must be 4 points (4, 3), got shape {c.shape}")
    e = (c[1:] - c[0]).T  # columns b - a, c - a, d - a
    scale = max(float(np.abs(e).max()), 1e-300)
    if abs(np.linalg.det(e / scale)) < FRAME_MIN_DET_REL:
        raise ParameterError("frame", "its 4 points are (nearly) coplanar")
    return np.linalg.inv(e)


def affine_coordinates(points: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """Affine coordinates (p, 4) of ``points`` (p, 3) w.r.t. ``frame`` (4, 3).

    Rows sum to 1 and ``affine_coordinates(x, C) @ C == x``.
    """
    c = np.asarray(frame, dtype=np.float64)
    g = _frame_inverse(c)
    lam = (np.asarray(points, dtype=np.float64) - c[0]) @ g.T
    return np.column_stack([1.0 - lam.sum(axis=1), lam])


def affine_coordinate_gradients(frame: np.ndarray) -> np.ndarray:
    """(4, 3) constant gradients of the 4 affine coordinates w.r.t. ``frame``
    (row k = d lambda_k / d(x, y, z)); rows sum to 0."""
    g = _frame_inverse(frame)
    return np.vstack([-g.sum(axis=0), g])
