"""The default camera of an offscreen render (``splatedit render`` without
camera flags, :func:`~splatedit.render.splat.headless.render_to_png` without a
camera): the editor's first view.

It frames the model's main body (:func:`splatedit.model.extent.framing_extent`:
far outlier clumps are left out) from the front about the model's up axis
(:func:`splatedit.model.orientation.detect_cloud_up_axis`, as the editor detects
it; :func:`~splatedit.model.orientation.front_direction`): a Y-up model is
seen from +Z, a Z-up scan (LAS/LAZ/E57, a floor) from -Y with Z up on
screen, not from above.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from splatedit.io.formats import is_z_up
from splatedit.model.extent import FramingExtent, framing_extent
from splatedit.model.orientation import UpAxis, detect_cloud_up_axis, front_direction
from splatedit.render.camera import Camera
from splatedit.tolerances import RENDER_CAMERA_MIN_UP_SINE, RENDER_FOV_DEG


@dataclass(frozen=True)
class DefaultView:
    """A default camera and what it was chosen from.

    Attributes:
        camera: the :class:`Camera`.
        extent: the framed extent (its :meth:`~FramingExtent.note` says
            when far points are left out of the view).
        up: the detected up axis (None when an up vector was given).
    """

    camera: Camera
    extent: FramingExtent
    up: UpAxis | None


def _unit(v: np.ndarray) -> np.ndarray:
    """``v`` (3,) scaled to length 1 (unit-size first: no underflow for |v| of 1e-300)."""
    v = v / np.abs(v).max()
    return v / np.linalg.norm(v)


def _largest_semi_axis(cloud) -> float:
    """The largest splat semi-axis (model units; einsum: no (n,) norms)."""
    return float(np.sqrt(max(np.einsum("ij,ij->i", cloud.u, cloud.u).max(),
                             np.einsum("ij,ij->i", cloud.v, cloud.v).max())))


def default_view(cloud, size, *, path=None, up=None, fov_deg: float | None = None) -> DefaultView:
    """The editor's first view of ``cloud`` for an image of ``size`` pixels.

    Args:
        cloud: a :class:`~splatedit.model.cloud.SplatCloud` (a Gaussian
            scene's splat proxy).
        size: (width, height) pixels.
        path: the file the model came from (its header / format names the
            up axis), or None.
        up: (3,) up vector to use instead of the detected axis (``--up``).
        fov_deg: vertical field of view (degrees), default ``RENDER_FOV_DEG``.
    """
    w, h = size
    extent = framing_extent(cloud.positions)
    axis = None
    if up is None:
        axis = detect_cloud_up_axis(cloud, path, z_up_format=is_z_up(path))
    up_vec = axis.vector if up is None else np.asarray(up, dtype=np.float64)
    if not np.any(up_vec) or not np.all(np.isfinite(up_vec)):
        direction = np.array([0.0, 0.0, 1.0])       # a bad --up: Camera names it
    elif np.any(extent.hi > extent.lo):
        direction = front_direction(up_vec)
    else:
        # all centres in one point: look at the splat face-on (from the front it may be edge-on)
        direction = cloud.normals[0]
        if np.linalg.norm(np.cross(direction, _unit(up_vec))) <= RENDER_CAMERA_MIN_UP_SINE:
            if up is None:
                up_vec = front_direction(direction)     # any up across the splat's normal
            else:
                direction = front_direction(up_vec)     # the given up wins: seen edge-on
    camera = Camera.frame(extent.lo, extent.hi, aspect=w / h, direction=direction, up=up_vec,
                          fov_deg=RENDER_FOV_DEG if fov_deg is None else fov_deg,
                          min_radius=_largest_semi_axis(cloud))
    return DefaultView(camera, extent, axis)


def screen_up(up, eye, target) -> np.ndarray:
    """The up hint for a camera at ``eye`` looking at ``target`` (both (3,))
    about the model's up vector ``up`` (3,): ``up`` itself, unless the view
    is along it (straight down or up, where it gives no screen direction):
    then the editor's top / bottom view's screen up, away from / towards the
    model's front (:func:`~splatedit.model.orientation.front_direction`): a
    Z-up scan seen from above has +Y (north) up on screen."""
    u = np.asarray(up, dtype=np.float64)
    look = np.asarray(target, dtype=np.float64) - np.asarray(eye, dtype=np.float64)
    if not np.any(u) or not np.any(look):
        return u                        # Camera names the bad parameter
    f, un = _unit(look), _unit(u)
    if np.linalg.norm(np.cross(f, un)) > RENDER_CAMERA_MIN_UP_SINE:
        return u
    return -front_direction(u) if f @ un < 0 else front_direction(u)
