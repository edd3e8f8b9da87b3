"""The one interface the editor's viewport drives: :class:`SceneRenderer`
(issue 18, item 1).

Both renderers implement it: :class:`splatedit.render.splat.renderer.Renderer`
(EWA surface splats) and :class:`splatedit.render.gaussian.renderer.GaussianRenderer`
(3D Gaussian Splatting scenes).  The viewport
(:mod:`splatedit.app.view.viewport`) keeps a renderer in step with the document
only through these members (:func:`splatedit.app.view.scenes.sync_slot`), so
a new kind of scene is a new renderer with this interface plus a scene
adapter (:mod:`splatedit.app.view.scenes`) for its level-of-detail policy.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np

from splatedit.render.camera import Camera


@runtime_checkable
class SceneRenderer(Protocol):
    """A renderer of one scene, deformable on the GPU.

    Attributes:
        dev: its :class:`splatedit.render.vk.Device` (a second renderer of
            the same view shares it).
        distortion_map, grey_shading, splat_scale, background: display
            options (heat map of the deformation's stretch, grey colours,
            footprint scale, display-referred RGB background).
        last_timings_ms: GPU (or wall) milliseconds per pass of the last
            frame, at least ``total`` or the pass buckets of its frame.
        supports_detail: :meth:`set_detail` applies the detail mode's rows
            (splats: yes; Gaussians: no).
        resident_frames: :meth:`render_resident` returns an image the
            presenter may blit (splats); False: the viewport reads pixels back.
        edl, supports_edl: eye-dome lighting on / off, where the renderer
            has it (splats: :class:`~splatedit.render.frame_passes.EyeDomeResolve`;
            Gaussians: no, ``edl`` stays False).
    """

    dev: Any
    distortion_map: bool
    grey_shading: bool
    splat_scale: float
    background: tuple
    last_timings_ms: dict
    supports_detail: bool
    resident_frames: bool
    supports_edl: bool
    edl: bool

    def set_cloud(self, cloud) -> None:
        """Upload a scene (a SplatCloud or a GaussianCloud, as the renderer draws)."""

    def set_selection(self, support_mask=None, handle_mask=None, inactive_mask=None) -> None:
        """Tint masks (n,) or index arrays: support, active handle, inactive handles; None clears."""

    def set_basis(self, indices, B, Bx, By, Bz) -> None:
        """Deformation basis rows (N, K) of the elements ``indices`` (N,)."""

    def set_detail(self, indices, detail) -> None:
        """The detail mode's rows (n_b, lambda) of the elements ``indices``,
        where ``supports_detail``; others raise ParameterError."""

    def clear_basis(self) -> None:
        """Nothing deformed."""

    def set_displacement(self, dC) -> None:
        """Control-frame displacement (K, 3) or a RotationDisplacement."""

    def render(self, camera: Camera, width: int, height: int) -> np.ndarray:
        """(height, width, 4) uint8 RGBA."""

    def render_resident(self, camera: Camera, width: int, height: int):
        """The frame left on the device (an rgba8 image in TRANSFER_SRC layout)."""

    def pick(self, camera: Camera, width: int, height: int, rect=None):
        """(index map (h, w) int64, -1 background; depth (h, w), NaN background)."""

    def close(self) -> None:
        """Free every Vulkan object (idempotent)."""
