"""Orbit camera for the editor: orbit about a pivot, pan, dolly to the cursor, frame.

Pure numpy.  The camera is a *turntable* like Blender's default: yaw about
the world up axis, pitch about the camera's right axis (clamped short of the
poles so "up" never flips).  State: ``target`` (the pivot), ``distance``,
``yaw``/``pitch`` in radians and the vertical field of view.

Screen conventions: pixel (0, 0) is the top-left corner, x to the right, y
down; NDC follows Vulkan (y down, depth 0..1).  ``view`` maps world to camera
space looking down -z (OpenGL-style right-handed camera space);
``projection`` includes the Vulkan y flip.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from splatedit.model.orientation import front_direction
from splatedit.render.camera import perspective
from splatedit.tolerances import (EDITOR_CLIP_RADII, EDITOR_DOLLY_STEP, EDITOR_FAR_MIN_NEAR,
                                  EDITOR_FRAME_MARGIN, EDITOR_MAX_DIST_REL, EDITOR_MIN_DIST_REL,
                                  EDITOR_NEAR_MIN, EDITOR_NEAR_MIN_REL, EDITOR_ORBIT_RAD_PER_PX,
                                  EDITOR_PITCH_LIMIT_DEG, RENDER_FOV_DEG)

#: pitch is kept within +-this (radians) of the horizon
PITCH_LIMIT = math.radians(EDITOR_PITCH_LIMIT_DEG)


def _normalize(v: np.ndarray) -> np.ndarray:
    n = float(np.linalg.norm(v))
    return v / n if n > 0 else v


@dataclass
class OrbitCamera:
    target: np.ndarray = field(default_factory=lambda: np.zeros(3))
    distance: float = 3.0
    yaw: float = 0.0
    pitch: float = 0.0
    fov_deg: float = RENDER_FOV_DEG
    up_axis: np.ndarray = field(default_factory=lambda: np.array([0.0, 1.0, 0.0]))
    scene_radius: float = 1.0
    #: where the orbit pivot sits on screen, as (x, y) view-plane tangents
    #: (right, up) off the view axis: (0, 0) is the window centre.  Framing into
    #: a part of the window (beside a side panel) sets it to that part's
    #: centre; orbit, the numpad views and the dolly drag turn / zoom about the
    #: point at the target's depth there, so the framed model stays put
    screen_offset: tuple = (0.0, 0.0)

    # -------------------------------------------------------------- frames
    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(right, up, back) unit vectors of the camera in world space; the
        camera looks along ``-back``."""
        up = _normalize(np.asarray(self.up_axis, float))
        ref = front_direction(up)        # the view from yaw 0, pitch 0: the model's front
        side = np.cross(up, ref)
        cy, sy = math.cos(self.yaw), math.sin(self.yaw)
        cp, sp = math.cos(self.pitch), math.sin(self.pitch)
        horiz = cy * ref + sy * side
        back = cp * horiz + sp * up
        right = _normalize(np.cross(up, back))
        cam_up = np.cross(back, right)
        return right, cam_up, back

    @property
    def eye(self) -> np.ndarray:
        return np.asarray(self.target, float) + self.distance * self.basis()[2]

    def view(self) -> np.ndarray:
        """(4, 4) world -> camera matrix."""
        r, u, b = self.basis()
        e = self.eye
        m = np.eye(4)
        m[0, :3], m[1, :3], m[2, :3] = r, u, b
        m[:3, 3] = -m[:3, :3] @ e
        return m

    def near_far(self) -> tuple[float, float]:
        near = max(self.distance - EDITOR_CLIP_RADII * self.scene_radius,
                   self.distance * EDITOR_NEAR_MIN_REL, EDITOR_NEAR_MIN)
        far = self.distance + EDITOR_CLIP_RADII * self.scene_radius
        return near, max(far, near * EDITOR_FAR_MIN_NEAR)

    def projection(self, aspect: float) -> np.ndarray:
        """(4, 4) Vulkan perspective (y down in NDC, depth 0..1)."""
        n, f = self.near_far()
        return perspective(self.fov_deg, aspect, n, f)

    def view_projection(self, w: int, h: int) -> np.ndarray:
        return self.projection(w / max(h, 1)) @ self.view()

    # ------------------------------------------------------------ projections
    def project(self, points: np.ndarray, w: int, h: int) -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates (n, 2) and camera-space depths (n,) (positive in
        front of the camera) of world points (n, 3)."""
        pts = np.atleast_2d(np.asarray(points, float))
        v = self.view()
        cam = pts @ v[:3, :3].T + v[:3, 3]
        depth = -cam[:, 2]
        t = 1.0 / math.tan(math.radians(self.fov_deg) / 2)
        aspect = w / max(h, 1)
        with np.errstate(divide="ignore", invalid="ignore"):
            ndc_x = (t / aspect) * cam[:, 0] / depth
            ndc_y = -t * cam[:, 1] / depth
        px = np.stack([(ndc_x + 1) * 0.5 * w, (ndc_y + 1) * 0.5 * h], axis=1)
        return px, depth

    def pixel_ray(self, x: float, y: float, w: int, h: int) -> tuple[np.ndarray, np.ndarray]:
        """(origin, unit direction) of the ray through pixel (x, y)."""
        r, u, b = self.basis()
        t = math.tan(math.radians(self.fov_deg) / 2)
        aspect = w / max(h, 1)
        nx = (2.0 * x / w - 1.0) * t * aspect
        ny = (1.0 - 2.0 * y / h) * t
        return self.eye, _normalize(nx * r + ny * u - b)

    def world_per_pixel(self, depth: float, h: int) -> float:
        """World length of one pixel at camera depth ``depth``."""
        return 2.0 * depth * math.tan(math.radians(self.fov_deg) / 2) / max(h, 1)

    def point_at_depth(self, x: float, y: float, w: int, h: int, depth: float) -> np.ndarray:
        """The world point under pixel (x, y) at camera depth ``depth``."""
        o, d = self.pixel_ray(x, y, w, h)
        back = self.basis()[2]
        cos = -float(d @ back)
        return o + d * (depth / max(cos, 1e-9))

    # --------------------------------------------------------------- motion
    def pivot(self) -> np.ndarray:
        """(3,) world point the camera orbits about: at the target's depth,
        under :attr:`screen_offset` (the target itself when it is (0, 0))."""
        r, u, _ = self.basis()
        ox, oy = self.screen_offset
        return np.asarray(self.target, float) + self.distance * (ox * r + oy * u)

    def turn_to(self, yaw: float, pitch: float) -> None:
        """Set the view angles (radians), keeping the :meth:`pivot` where it
        is in the world and on screen."""
        p = self.pivot()
        self.yaw = float(yaw)
        self.pitch = float(np.clip(pitch, -PITCH_LIMIT, PITCH_LIMIT))
        r, u, _ = self.basis()
        ox, oy = self.screen_offset
        self.target = p - self.distance * (ox * r + oy * u)

    def orbit(self, dx_px: float, dy_px: float) -> None:
        """Turntable orbit about the :meth:`pivot` by a mouse motion in pixels."""
        self.turn_to(self.yaw - dx_px * EDITOR_ORBIT_RAD_PER_PX, self.pitch + dy_px * EDITOR_ORBIT_RAD_PER_PX)

    def pan(self, dx_px: float, dy_px: float, h: int) -> None:
        """Move the pivot in the view plane so the pivot plane follows the mouse."""
        r, u, _ = self.basis()
        s = self.world_per_pixel(self.distance, h)
        self.target = np.asarray(self.target, float) - r * dx_px * s + u * dy_px * s

    def dolly(self, steps: float, x: float | None = None, y: float | None = None,
              w: int = 1, h: int = 1, depth: float | None = None) -> None:
        """Zoom by ``EDITOR_DOLLY_STEP ** steps`` (positive = closer).  With a cursor
        position, the world point under the cursor (at ``depth``, default the
        pivot's depth) stays under the cursor (dolly to cursor)."""
        f = EDITOR_DOLLY_STEP ** steps
        new_dist = float(np.clip(self.distance * f, EDITOR_MIN_DIST_REL * self.scene_radius,
                                 EDITOR_MAX_DIST_REL * self.scene_radius))
        f = new_dist / self.distance
        if x is None or y is None:        # about the pivot (it keeps its pixel)
            p = self.pivot()
            self.target = p + (np.asarray(self.target, float) - p) * f
            self.distance = new_dist
            return
        p = self.point_at_depth(x, y, w, h, self.distance if depth is None else depth)
        # scaling the eye and target about p keeps p's pixel (the view direction is unchanged)
        self.target = p + (np.asarray(self.target, float) - p) * f
        self.distance = new_dist

    def frame(self, center, radius: float, aspect: float = 1.0, margin: float = EDITOR_FRAME_MARGIN,
              area: tuple | None = None) -> None:
        """Look at a sphere (``center``, ``radius`` x ``margin``) so it fills
        the view, or, with ``area`` = (x0, y0, x1, y1) fractions of the window
        (0..1, y down), that part of it: the sphere's outline (exact under the
        perspective) is centred in the area and touches its nearer pair of
        sides; the :meth:`pivot` goes to the sphere's centre.

        In the x-z plane the tangents from the eye to a sphere at (X, z) (depth
        z) have the slopes (X z +- R sqrt(X^2 + z^2 - R^2)) / (z^2 - R^2): the
        outline's middle is X z / (z^2 - R^2) and, with X putting that middle at
        the area's middle m, its half-width is R sqrt(m^2 / z^2 + 1 / (z^2 - R^2)),
        which falls with z: the depth is where it equals the area's half-width
        (a quadratic in z^2), the larger of the x and y ones."""
        x0, y0, x1, y1 = (0.0, 0.0, 1.0, 1.0) if area is None else (float(v) for v in area)
        tv = math.tan(math.radians(self.fov_deg) / 2)
        th = tv * aspect
        # the area's middle and half-width as view-plane slopes (right, up)
        mx, hx = (x0 + x1 - 1) * th, max((x1 - x0) * th, 1e-9)
        my, hy = (1 - y0 - y1) * tv, max((y1 - y0) * tv, 1e-9)
        r2 = max(radius, 1e-9) ** 2 * margin ** 2

        def depth2(m: float, hw: float) -> float:
            b = r2 * (hw * hw + m * m + 1)
            return (b + math.sqrt(max(b * b - 4 * hw * hw * r2 * r2 * m * m, 0.0))) / (2 * hw * hw)

        z2 = max(depth2(mx, hx), depth2(my, hy))
        z = math.sqrt(z2)
        self.screen_offset = (mx * (z2 - r2) / z2, my * (z2 - r2) / z2)
        self.distance = z
        r, u, _ = self.basis()
        self.target = np.asarray(center, float) - z * (self.screen_offset[0] * r + self.screen_offset[1] * u)

    def frame_points(self, points: np.ndarray, aspect: float = 1.0, area: tuple | None = None) -> None:
        """Frame the bounding sphere of ``points`` (n, 3) (into ``area``, see :meth:`frame`)."""
        pts = np.atleast_2d(np.asarray(points, float))
        lo, hi = pts.min(0), pts.max(0)
        c = (lo + hi) / 2
        r = float(np.sqrt(((pts - c) ** 2).sum(1)).max()) if len(pts) else 1.0
        self.frame(c, max(r, 1e-6 * max(self.scene_radius, 1e-9)), aspect, area=area)

    def state(self) -> tuple:
        """A hashable snapshot of everything the view depends on (used to detect
        camera motion): the up axis and the pivot's place on screen included (U
        turned the camera but left the drawn frame, keyed without them, stale)."""
        return (tuple(np.round(np.asarray(self.target, float), 12)), round(self.distance, 12),
                round(self.yaw, 12), round(self.pitch, 12), self.fov_deg,
                tuple(np.round(np.asarray(self.up_axis, float), 12)),
                tuple(round(float(x), 12) for x in self.screen_offset))
