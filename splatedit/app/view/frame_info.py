"""What the viewport reports about a frame, and the camera conversion its scenes share."""

from __future__ import annotations

from dataclasses import dataclass

from splatedit.app.view.camera_control import OrbitCamera
from splatedit.render.camera import Camera


def render_camera(cam: OrbitCamera) -> Camera:
    """The renderer's camera of the editor's orbit camera."""
    r, u, b = cam.basis()
    return Camera(cam.eye, cam.target, up=u, fov_deg=cam.fov_deg)


@dataclass(frozen=True)
class FrameInfo:
    """The last frame the viewport drew."""
    ms: float            # GPU time of the frame (milliseconds)
    splats: int          # splats drawn (a level of detail: fewer)
    div: int             # resolution divisor (1: full resolution)
    lod: bool            # a level of detail was drawn
    interactive: bool    # drawn as a fast frame while moving
    gaussians: bool = False   # drawn by the Gaussian renderer (a Gaussian Splatting document)


@dataclass(frozen=True)
class ResidentFrame:
    """A frame left on the device: the ``width`` x ``height`` top-left part of
    ``image`` (rgba8, TRANSFER_SRC layout), valid until its renderer draws again."""
    image: object
    width: int
    height: int
