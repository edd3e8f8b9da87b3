"""Frame scheduling of the editor: when to draw a fast interactive frame,
when the full-quality one, presenting it with the overlay, and the
frame-time bookkeeping that sizes the interactive budget.

Full quality: drawn at once when it is cheap; when it is slow (a large model,
drawn at a level of detail while moving) it is drawn after motion stops by
the background refiner (a whole frame on a second device, with the compute
pre-pass, shown when done) or, with ``SPLATEDIT_REFINE=progressive``, refined
progressively (:mod:`splatedit.app.progressive_refine`: a chunk of splats per
idle frame on the same device, composited over the level-of-detail frame,
dropped on any change: the image sharpens instead of switching, but with a
submit, a shading pass and a readback per step full quality comes 2-3x later
at 1M splats; the detail mode always uses the refiner).

Two presentation paths: the GPU path (the editor has a GUI,
:mod:`splatedit.app.gui_panels`): the scene frame stays on the device and is
blitted into the swapchain image, the GUI and the tools' overlays are drawn
over it by the GUI pass, nothing is read back; and the CPU fallback (no
GUI): the frame is read back, the overlay patches are blended on the CPU
(:mod:`splatedit.app.overlay`) and the pixels copied into the swapchain."""

from __future__ import annotations

import os
import time
from dataclasses import dataclass

import numpy as np

from splatedit.app import overlay as ov
from splatedit.app import revision
from splatedit.app.camera_control import OrbitCamera
from splatedit.app.tools.base import DragMode
from splatedit.app.progressive_refine import ProgressiveRefinement
from splatedit.app.viewport import FrameInfo, ResidentFrame
from splatedit.errors import SplatEditError
from splatedit.tolerances import (EDITOR_ASYNC_REFINE_DELAY_S, EDITOR_ASYNC_REFINE_MS,
                                  EDITOR_PROGRESSIVE_MIN_CHUNK, EDITOR_REFINE_DELAY_S)


@dataclass(frozen=True)
class SceneKey:
    """Everything a drawn scene depends on (equal keys: the frame is current).
    Clouds and bases enter by revision (:mod:`splatedit.app.revision`), never by ``id()``."""
    camera: tuple
    size: tuple[int, int]
    cloud_rev: int
    sel_version: int
    basis_rev: int
    dc: bytes | None
    display: tuple          # heat map, grey shading, splat scale, background


class FrameScheduler:
    def __init__(self, ed, budget_ms: float):
        self.ed = ed
        self.scene = None
        self.scene_key: SceneKey | None = None
        self.scene_interactive = False
        self.refiner = None
        self.progressive = None          # ProgressiveRefinement of the current view
        #: the last finished ProgressiveRefinement (timings, for benchmarks and tests)
        self.last_progressive = None
        self._stepped = None             # the refinement stepped in the frame being drawn
        self._refine_failed_key = None   # view whose background frame failed (not retried)
        self.last_motion = 0.0
        self.frame_ms = 0.0
        self.moving_frame_ms: list[float] = []     # whole frames (render + overlay + present) while moving
        self._rendered_interactive = False
        self.budget_ms = float(budget_ms)
        self.frame_overhead_ms = 10.0
        self.frames = 0
        self._sel_version_seen = -1

    def invalidate(self) -> None:
        self.scene_key = None
        self.drop_progressive()

    def drop_progressive(self) -> None:
        if self.progressive is not None:
            self.progressive.close()
            self.progressive = None

    def motion(self) -> None:
        self.last_motion = time.perf_counter()

    # ------------------------------------------------------------ document
    def sync_document(self) -> None:
        s, vp, ed = self.ed.session, self.ed.viewport, self.ed
        cloud, basis, dc = s.display_state(vp.distortion_map)   # the last edit's, for its heat map
        if vp.cloud is not cloud:
            vp.set_cloud(cloud)
            ed.brush.picker = None
        ed.brush.tools.prepare(s.cloud)
        if self._sel_version_seen != s.version:
            vp.set_selection(s.selection.support, s.selection.handle, s.version, s.selection.others())
            self._sel_version_seen = s.version
        if vp.basis is not basis:
            vp.set_basis(basis)
        vp.set_dc(dc)

    def state(self) -> SceneKey:
        ed, s, vp = self.ed, self.ed.session, self.ed.viewport
        dc = None if vp.dc is None else vp.dc.tobytes()
        return SceneKey(ed.cam.state(), ed.size, revision.of(s.cloud), s.version, revision.of(s.basis), dc,
                        (vp.distortion_map, vp.grey, vp.splat_scale, vp.background))

    def async_refine(self) -> bool:
        """True when full-quality frames are slow enough to be drawn in the background."""
        vp = self.ed.viewport
        return vp.ms_per_splat is not None and vp.ms_per_splat * self.ed.session.cloud.n > EDITOR_ASYNC_REFINE_MS

    def pending(self) -> bool:
        """A frame must be drawn now (the scene is stale or still interactive)."""
        s = self.ed.session
        return (self.scene_key is None or self.ed.drag is not DragMode.NONE or self.progressive is not None
                or (self.scene_interactive and not (s is not None and self.async_refine()))
                or (s is not None and self.scene_key != self.state()))

    def busy(self) -> bool:
        """Waiting for a background refinement (or its start)."""
        s = self.ed.session
        refining = self.refiner is not None and self.refiner.busy
        return refining or (self.scene_interactive and s is not None and self.async_refine())

    # --------------------------------------------------------------- draw
    @property
    def gpu(self) -> bool:
        """The GPU presentation path: the scene stays on the device (blitted into
        the swapchain image), the GUI and the tools' overlays are drawn over it."""
        return getattr(self.ed, "gui", None) is not None

    def draw(self) -> None:
        ed = self.ed
        w, h = ed.size
        if w == 0 or h == 0 or ed.window.iconified():
            return
        t0 = time.perf_counter()
        if self.gpu:
            self._draw_gpu(w, h)
        else:
            if ed.session is None:
                frame = np.full((h, w, 4), 255, np.uint8)
            else:
                frame = self._scene_frame(w, h)
            for p in ed.overlay_patches(w, h):
                ov.blend(frame, p)
            ed.presenter.present(frame)
        self.frames += 1
        self.frame_ms = (time.perf_counter() - t0) * 1e3
        if self._stepped is not None:
            self._stepped.frame_ms.append(self.frame_ms)
            self._stepped = None
        if self._rendered_interactive:
            self.moving_frame_ms = (self.moving_frame_ms + [self.frame_ms])[-30:]
            # the frame budget is for the whole frame: leave room for overlay + present
            vp = ed.viewport
            extra = max(self.frame_ms - (vp.last_info.ms if vp.last_info else 0.0), 0.0)
            self.frame_overhead_ms = 0.8 * self.frame_overhead_ms + 0.2 * extra
            vp.budget_ms = max(self.budget_ms - self.frame_overhead_ms, 0.3 * self.budget_ms)
        self._rendered_interactive = False

    def _draw_gpu(self, w: int, h: int) -> None:
        """One presented frame on the GPU: the scene (a device-resident frame
        blitted, or pixels from the background refiner uploaded), then the GUI
        pass (panels, help, the tools' overlays) into the swapchain image."""
        ed = self.ed
        src = None
        if ed.session is not None:
            self._update_scene(w, h)
            src = self.scene
        ed.gui.build(w, h)
        pres = ed.presenter

        def record(cb, target):
            if isinstance(src, ResidentFrame):
                pres.blit_into(cb, src.image, target, (src.width, src.height))
                ed.gui.render_into(cb, target)
            elif src is not None:
                pres.upload_into(cb, target, src)
                ed.gui.render_into(cb, target)
            else:
                ed.gui.gui.render_into(cb, target, clear=(1.0, 1.0, 1.0, 1.0), final="present")
        if not pres.render_frame(record):
            ed.gui.discard()

    def _scene_frame(self, w: int, h: int) -> np.ndarray:
        self._update_scene(w, h)
        frame = self.scene.copy()
        if frame.shape[:2] != (h, w):
            fr = np.full((h, w, 4), 255, np.uint8)
            hh, ww = min(h, frame.shape[0]), min(w, frame.shape[1])
            fr[:hh, :ww] = frame[:hh, :ww]
            frame = fr
        return frame

    def _update_scene(self, w: int, h: int) -> None:
        """Render (or take from the background refiner) the scene when it is stale."""
        ed = self.ed
        sc = self.scene
        if isinstance(sc, ResidentFrame) and getattr(sc.image, "handle", None) is None:
            self.scene = self.scene_key = None      # its renderer's images were re-created (a resize)
        self.sync_document()
        key = self.state()
        now = time.perf_counter()
        moving = now - self.last_motion < EDITOR_REFINE_DELAY_S or ed.drag is not DragMode.NONE
        stale = self.scene is None or key != self.scene_key
        if self.progressive is not None and (moving or self.progressive.key != key):
            self.drop_progressive()          # any change: camera, selection, pose, display
        if stale or (self.scene_interactive and not moving):
            if not moving and self.async_refine():
                # a slow full-quality frame: refined progressively, a chunk per frame
                if stale:
                    self.render_scene(key, interactive=True)
                if self.scene_interactive and self._progressive_step(key, w, h):
                    pass
                # the detail mode: drawn by the background refiner, once the view
                # has been still for a while (a started frame cannot be aborted)
                elif (self.scene_interactive and key != self._refine_failed_key
                        and time.perf_counter() - self.last_motion >= EDITOR_ASYNC_REFINE_DELAY_S):
                    self.request_refine(key)
            else:
                self.render_scene(key, interactive=moving)
        if self.refiner is not None and self.refiner.error is not None:
            # a failed full-quality frame is reported once and not retried for this view
            failed_key, exc = self.refiner.error
            ed.say(f"full-quality frame failed: {exc}")
            self.refiner.error = None
            self._refine_failed_key = failed_key
        if self.refiner is not None and self.scene_interactive:
            img = self.refiner.take(key)
            if img is not None and img.shape[:2] == (h, w):
                self.scene, self.scene_interactive = img, False
                ed.viewport.last_info = FrameInfo(self.refiner.last_ms, ed.session.cloud.n, 1, False, False)

    def _progressive_step(self, key, w: int, h: int) -> bool:
        """One step of the progressive refinement of ``key`` (started here); False
        where it is not used (the background refiner draws the frame instead):
        unless ``SPLATEDIT_REFINE=progressive`` (the progressive frame's chunks
        go through the pre-pass, but per-step submits, shading passes and
        readbacks make full quality arrive 2-3x later than from the background
        refiner: 3-5 s against about 2 s at 1M splats, see
        docs/PERFORMANCE.md), and always in the detail mode (not tested there)."""
        if os.environ.get("SPLATEDIT_REFINE", "background") != "progressive":
            return False
        ed, vp = self.ed, self.ed.viewport
        p = self.progressive
        if p is None:
            if key == self._refine_failed_key:
                return True
            chunk = max(EDITOR_PROGRESSIVE_MIN_CHUNK, int(vp.budget_ms / max(vp.ms_per_splat, 1e-9)))
            if self.gpu:
                ed.presenter.wait_previous()     # the shown frame may be the full renderer's image
            try:
                frame = vp.progressive(ed.cam, w, h, chunk)
            except SplatEditError as exc:
                ed.say(f"full-quality frame failed: {exc}")
                self._refine_failed_key = key
                return True
            if frame is None:
                return False
            # the level-of-detail frame as pixels, under the chunks
            under = self.scene if isinstance(self.scene, np.ndarray) else None
            if under is None or under.shape[:2] != (h, w):
                under = vp.render(ed.cam, w, h, interactive=True)
            p = self.progressive = ProgressiveRefinement(frame, key, under, vp.budget_ms)
            # shown until the first chunk arrives: pixels, not the renderers' images (a
            # ResidentFrame of the full renderer is destroyed when the steps resize its targets)
            self.scene = under
        self._stepped = p
        try:
            img = p.step()
        except SplatEditError as exc:
            ed.say(f"full-quality frame failed: {exc}")
            self._refine_failed_key = key
            self.drop_progressive()
            return True
        if img is not None:
            self.scene = img
        if p.done:
            self.scene_interactive = False
            n = ed.session.cloud.n
            vp.last_info = FrameInfo(p.total_ms, n, 1, False, False)
            vp.ms_per_splat = p.total_ms / max(n, 1)
            self.last_progressive = p
            self.drop_progressive()
        return True

    def render_scene(self, key, interactive: bool) -> None:
        ed = self.ed
        w, h = ed.size
        if self.gpu:
            ed.presenter.wait_previous()     # the last frame may still read the image redrawn now
        self.scene = ed.viewport.render(ed.cam, w, h, interactive=interactive, resident=self.gpu)
        self._rendered_interactive = interactive
        self.scene_key = key
        info = ed.viewport.last_info
        self.scene_interactive = bool(interactive and info is not None and (info.lod or info.div > 1))

    def request_refine(self, key) -> None:
        from splatedit.app.viewport import BackgroundRefiner
        ed = self.ed
        vp = ed.viewport
        if self.refiner is None:
            self.refiner = BackgroundRefiner(ed.wake, vp.budget_ms)
        s = ed.session
        w, h = ed.size
        c = ed.cam
        cam = OrbitCamera(np.array(c.target, float), c.distance, c.yaw, c.pitch, c.fov_deg,
                          np.array(c.up_axis, float), c.scene_radius)
        self.refiner.request(key, dict(cloud=vp.cloud, support=s.selection.support.copy(),
                                       handle=s.selection.handle.copy(), sel_version=s.version,
                                       inactive=s.selection.others(), basis=vp.basis, dc=vp.dc, camera=cam,
                                       w=w, h=h, distortion_map=vp.distortion_map, grey=vp.grey,
                                       splat_scale=vp.splat_scale, background=vp.background, pick_key=ed.brush.pick_key()))

    def close(self) -> None:
        self.drop_progressive()
        if self.refiner is not None:
            self.refiner.close()
            self.refiner = None
