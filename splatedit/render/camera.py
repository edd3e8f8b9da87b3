"""Pinhole camera with Vulkan clip conventions (y down, depth 0..1).

Eye space is right-handed with the camera looking down -z and +y up; the
projection flips y so that NDC y = -1 is the top row of the image.
"""

from __future__ import annotations

import math

import numpy as np

from splatedit.errors import ParameterError
from splatedit.tolerances import (RENDER_CAMERA_MIN_UP_SINE, RENDER_CLIP_MARGIN_REL, RENDER_CLIP_MIN_RADIUS_REL,
                                  RENDER_FOV_DEG, RENDER_FRAME_MARGIN, RENDER_FRAME_MIN_RADIUS_REL,
                                  RENDER_NEAR_FAR_RATIO, RENDER_CAMERA_MAX_ABS)


def _vec3(name, value) -> np.ndarray:
    arr = np.asarray(value, dtype=np.float64).reshape(-1)
    if arr.shape != (3,) or not np.isfinite(arr).all():
        raise ParameterError(name, f"must be 3 finite numbers, got {value!r}")
    return arr


def perspective(fov_deg: float, aspect: float, near: float, far: float) -> np.ndarray:
    """4x4 eye -> clip perspective for Vulkan (x right, y down in NDC, depth 0
    at ``near``, 1 at ``far``) for a vertical field of view ``fov_deg``."""
    f = 1.0 / math.tan(math.radians(fov_deg) / 2.0)
    p = np.zeros((4, 4))
    p[0, 0] = f / aspect
    p[1, 1] = -f
    p[2, 2] = far / (near - far)
    p[2, 3] = near * far / (near - far)
    p[3, 2] = -1.0
    return p

class Camera:
    """A perspective camera.

    Args:
        eye, target, up: world-space position, look-at point and up hint.
        fov_deg: vertical field of view in degrees (0 < fov < 180).
        near, far: clip distances along the view axis; ``None`` means chosen
            from the model bounds at render time (:meth:`clip_range`).
    """

    def __init__(self, eye, target, up=(0.0, 1.0, 0.0), fov_deg: float = RENDER_FOV_DEG,
                 near: float | None = None, far: float | None = None):
        self.eye = _vec3("eye", eye)
        self.target = _vec3("target", target)
        self.up = _vec3("up", up)
        if not 0.0 < float(fov_deg) < 179.0:
            raise ParameterError("fov_deg", f"must be in (0, 179), got {fov_deg}")
        self.fov_deg = float(fov_deg)
        for name, vec in (("eye", self.eye), ("target", self.target)):
            if np.abs(vec).max() > RENDER_CAMERA_MAX_ABS:
                raise ParameterError(name, f"{vec.tolist()} is beyond the supported magnitude "
                                           f"{RENDER_CAMERA_MAX_ABS:g}")
        fwd = self.target - self.eye
        if not np.any(fwd):
            raise ParameterError("target", "must differ from eye")
        if not np.any(self.up):
            raise ParameterError("up", "must not be the zero vector")
        # directions scaled to unit size first: |fwd| of 1e300 or |up| of 1e-300
        # must not overflow / underflow the test into a false "parallel"
        f = fwd / np.abs(fwd).max()
        f /= np.linalg.norm(f)
        u = self.up / np.abs(self.up).max()
        u /= np.linalg.norm(u)
        if np.linalg.norm(np.cross(f, u)) <= RENDER_CAMERA_MIN_UP_SINE:
            raise ParameterError("up", "must not be parallel to the view direction")
        if near is not None and far is not None and not 0.0 < near < far:
            raise ParameterError("near", f"need 0 < near < far, got near={near}, far={far}")
        self.near = near
        self.far = far

    def __repr__(self):
        return (f"Camera(eye={self.eye.tolist()}, target={self.target.tolist()}, up={self.up.tolist()}, "
                f"fov_deg={self.fov_deg}, near={self.near}, far={self.far})")

    # ---------------------------------------------------------------- matrices
    def view_matrix(self) -> np.ndarray:
        """4x4 world -> eye (float64), right-handed, looking down -z."""
        f = self.target - self.eye
        f = f / np.abs(f).max()          # unit-size first: no overflow / underflow
        f /= np.linalg.norm(f)
        r = np.cross(f, self.up / np.abs(self.up).max())
        r /= np.linalg.norm(r)
        u = np.cross(r, f)
        m = np.eye(4)
        m[0, :3], m[1, :3], m[2, :3] = r, u, -f
        m[:3, 3] = -m[:3, :3] @ self.eye
        return m

    def clip_range(self, bounds_min=None, bounds_max=None) -> tuple[float, float]:
        """(near, far): the given values, or the depth range of the bounding
        sphere of the box, widened by ``RENDER_CLIP_MARGIN_REL``."""
        if self.near is not None and self.far is not None:
            return float(self.near), float(self.far)
        if bounds_min is None:
            raise ParameterError("near", "near/far not given and no model bounds to choose them from")
        lo, hi = np.asarray(bounds_min, float), np.asarray(bounds_max, float)
        c, r = 0.5 * (lo + hi), 0.5 * float(np.linalg.norm(hi - lo))
        f = (self.target - self.eye) / np.linalg.norm(self.target - self.eye)
        d = float(np.dot(c - self.eye, f))
        r = max(r, RENDER_CLIP_MIN_RADIUS_REL * max(1.0, abs(d)))
        far = self.far if self.far is not None else max(d + r * (1 + RENDER_CLIP_MARGIN_REL), r)
        near = self.near if self.near is not None else max(d - r * (1 + RENDER_CLIP_MARGIN_REL),
                                                           far * RENDER_NEAR_FAR_RATIO)
        if not near < far:
            near = far * RENDER_NEAR_FAR_RATIO
        return float(near), float(far)

    def projection_matrix(self, aspect: float, near: float, far: float) -> np.ndarray:
        """4x4 eye -> clip for Vulkan: x right, y down in NDC, depth 0 at near, 1 at far."""
        return perspective(self.fov_deg, aspect, near, far)

    # ----------------------------------------------------------------- framing
    @classmethod
    def frame(cls, bounds_min, bounds_max, aspect: float = 1.0, *, direction=(0.0, 0.0, 1.0),
              up=(0.0, 1.0, 0.0), fov_deg: float = RENDER_FOV_DEG,
              min_radius: float = 0.0) -> "Camera":
        """A camera looking at the box centre from ``direction`` (pointing from
        the centre to the eye) at the distance where the box's bounding sphere
        fits the narrower field of view.

        ``min_radius`` (model units): frame at least a sphere this large (pass
        the largest splat radius, so that a single point or a pile of
        identical points is framed by its splat).  Without it a degenerate box
        gets RENDER_FRAME_MIN_RADIUS_REL of its centre's largest coordinate
        (relative: a model of any scale keeps its size on screen)."""
        lo, hi = _vec3("bounds_min", bounds_min), _vec3("bounds_max", bounds_max)
        if aspect <= 0:
            raise ParameterError("aspect", f"must be positive, got {aspect}")
        c = 0.5 * (lo + hi)
        r = max(0.5 * float(np.linalg.norm(hi - lo)), float(min_radius),
                RENDER_FRAME_MIN_RADIUS_REL * float(np.abs(c).max()), np.finfo(np.float64).tiny)
        half_v = math.radians(fov_deg) / 2.0
        half_h = math.atan(math.tan(half_v) * aspect)
        dist = r / math.sin(min(half_v, half_h)) * RENDER_FRAME_MARGIN
        d = _vec3("direction", direction)
        d = d / np.linalg.norm(d)
        return cls(c + dist * d, c, up=up, fov_deg=fov_deg)
