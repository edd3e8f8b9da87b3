"""The editor's view of the renderer: full-quality and level-of-detail frames.

:class:`Viewport` keeps the renderer(s) in sync with the document lazily (a
renderer is only updated when it draws) and chooses what to draw:

* idle: the full cloud at the window's resolution (full quality);
* interactive (camera or handle moving, brush painting): a level of detail
  from :class:`~splatedit.model.lod.LodPyramid` whose predicted cost fits the
  frame budget, and half resolution when even the coarsest level does not
  fit.  The prediction uses measured frame times (ms per splat, updated
  after every frame).

The LOD level is drawn by a second :class:`~splatedit.render.renderer.Renderer`
sharing the first one's Vulkan device; its deformation-basis rows are the
representatives' rows (:meth:`LodLevel.rows`), so the handle moves at LOD too.
"""

from __future__ import annotations

import time

import numpy as np

from splatedit.app.camera_control import OrbitCamera
from splatedit.render.camera import Camera


def render_camera(cam: OrbitCamera) -> Camera:
    r, u, b = cam.basis()
    return Camera(cam.eye, cam.target, up=u, fov_deg=cam.fov_deg)


class _Slot:
    """One renderer and what it currently holds."""

    def __init__(self, renderer):
        self.r = renderer
        self.cloud = None      # the object uploaded
        self.sel = None        # selection version uploaded
        self.basis = None      # basis object uploaded (or False = cleared)
        self.level = None
        self.dc = None


class Viewport:
    def __init__(self, *, budget_ms: float = 100.0, renderer=None):
        from splatedit.render.renderer import Renderer
        self.full = _Slot(renderer if renderer is not None else Renderer())
        self._Renderer = Renderer
        self.lod_slot: _Slot | None = None
        self.budget_ms = float(budget_ms)
        self.cloud = None
        self.support = None
        self.handle = None
        self.sel_version = 0
        self.basis = None
        self.dc = None
        self.pyramid = None
        self.ms_per_splat = None     # measured on full-quality frames
        self.last_info: dict = {}
        self.full_frames_ms: list[float] = []
        self.interactive_frames_ms: list[float] = []

    # ----------------------------------------------------------- document
    def set_cloud(self, cloud) -> None:
        self.cloud = cloud

    def set_pyramid(self, pyramid) -> None:
        self.pyramid = pyramid

    def set_selection(self, support, handle, version: int) -> None:
        self.support, self.handle, self.sel_version = support, handle, version

    def set_basis(self, basis) -> None:
        self.basis = basis

    def set_dc(self, dc) -> None:
        self.dc = None if dc is None else np.asarray(dc, float)

    # ------------------------------------------------------------- syncing
    def _sync(self, slot: _Slot, level=None) -> None:
        cloud = self.cloud
        if level is not None:
            src = self.pyramid.source
            if slot.cloud is not cloud or slot.level is not level:
                lc = level.cloud if cloud is src else level.deformed(cloud.positions, cloud.u, cloud.v)
                slot.r.set_cloud(lc)
                slot.cloud, slot.level = cloud, level
                slot.sel = slot.basis = slot.dc = None
        elif slot.cloud is not cloud:
            slot.r.set_cloud(cloud)
            slot.cloud = cloud
            slot.sel = slot.basis = slot.dc = None
        if slot.sel != (self.sel_version, id(cloud)):
            s, h = self.support, self.handle
            if s is not None and len(s) == cloud.n:
                if level is not None:
                    s, h = level.masks(s, h)
                slot.r.set_selection(s, h)
            else:
                slot.r.set_selection(None, None)
            slot.sel = (self.sel_version, id(cloud))
        basis = self.basis
        if slot.basis is not basis:
            if basis is None:
                slot.r.clear_basis()
                slot.basis = None
            else:
                rows = basis.rows_for_gpu(0)
                if level is not None:
                    rows = level.rows(*rows)
                slot.r.set_basis(*rows)
                slot.basis = basis
            slot.dc = None
        if basis is not None:
            dc = self.dc if self.dc is not None else np.zeros((basis.n_columns, 3))
            if slot.dc is None or not np.array_equal(slot.dc, dc):
                slot.r.set_displacement(dc)
                slot.dc = dc.copy()

    def _lod_slot(self) -> _Slot:
        if self.lod_slot is None:
            self.lod_slot = _Slot(self._Renderer(device=self.full.r.dev))
        return self.lod_slot

    # ------------------------------------------------------------- drawing
    def choose(self, interactive: bool, w: int, h: int):
        """(level or None, resolution divisor) for the next frame."""
        if not interactive or self.ms_per_splat is None or self.cloud is None:
            return None, 1
        n = self.cloud.n
        px_scale = (w * h) / self._ref_pixels if getattr(self, "_ref_pixels", None) else 1.0
        if self.ms_per_splat * n * px_scale <= self.budget_ms:
            return None, 1
        fit = int(self.budget_ms / max(self.ms_per_splat * px_scale, 1e-9))
        level = self.pyramid.level_for(fit) if self.pyramid is not None else None
        count = n if level is None else level.n
        div = 1
        if self.ms_per_splat * count * px_scale > self.budget_ms:
            div = 2
        return level, div

    def render(self, cam: OrbitCamera, w: int, h: int, interactive: bool = False) -> np.ndarray:
        """An (h, w, 4) uint8 frame."""
        level, div = self.choose(interactive, w, h)
        slot = self.full if level is None else self._lod_slot()
        t0 = time.perf_counter()
        self._sync(slot, level)
        rw, rh = max(1, w // div), max(1, h // div)
        img = slot.r.render(render_camera(cam), rw, rh)
        ms = (time.perf_counter() - t0) * 1e3
        count = self.cloud.n if level is None else level.n
        if div > 1:
            img = np.repeat(np.repeat(img, div, axis=0), div, axis=1)[:h, :w]
            if img.shape[0] < h or img.shape[1] < w:
                pad = np.zeros((h, w, 4), np.uint8)
                pad[:img.shape[0], :img.shape[1]] = img
                img = pad
        # cost model: ms per splat at this resolution (full-resolution frames only)
        if div == 1:
            est = ms / max(count, 1)
            self._ref_pixels = w * h
            self.ms_per_splat = est if self.ms_per_splat is None else 0.5 * (self.ms_per_splat + est)
        (self.interactive_frames_ms if interactive else self.full_frames_ms).append(ms)
        self.last_info = {"ms": ms, "splats": count, "div": div, "lod": level is not None,
                          "interactive": interactive}
        return np.ascontiguousarray(img)

    def pick(self, cam: OrbitCamera, w: int, h: int):
        """(index map (h, w) int64, -1 background; depth (h, w)) of the full cloud."""
        self._sync(self.full)
        return self.full.r.pick(render_camera(cam), w, h)

    def close(self) -> None:
        if self.lod_slot is not None:
            self.lod_slot.r.close()
            self.lod_slot = None
        if self.full is not None:
            self.full.r.close()
            self.full = None
