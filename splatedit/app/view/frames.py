"""Frame scheduling of the editor: when to draw a fast interactive frame,
when the full-quality one, presenting it with the overlay, and the
frame-time bookkeeping that sizes the interactive budget.

Full quality: drawn at once when it is cheap; when it is slow (a large model,
drawn at a level of detail while moving) it is refined progressively after
motion stops (:mod:`splatedit.app.view.progressive_refine`: a few chunks of splats
per presented frame on the editor's one Vulkan device, composed over the
level-of-detail frame on the device, dropped on any change: the image
sharpens instead of switching).

Two presentation paths: the GPU path (the editor has a GUI,
:mod:`splatedit.app.ui.gui_panels`): the scene frame stays on the device and is
blitted into the swapchain image, the GUI and the tools' overlays are drawn
over it by the GUI pass, nothing is read back; and the CPU fallback (no
GUI): the frame is read back, the overlay patches are blended on the CPU
(:mod:`splatedit.app.ui.overlay`) and the pixels copied into the swapchain."""

from __future__ import annotations

import os
import time
from dataclasses import dataclass

import numpy as np

from splatedit.app.ui import overlay as ov
from splatedit.app.document import revision
from splatedit.app.tools.base import DragMode
from splatedit.app.view.progressive_refine import ProgressiveRefinement
from splatedit.app.view.viewport import FrameInfo, ResidentFrame
from splatedit.errors import ParameterError, SplatEditError
from splatedit.tolerances import (EDITOR_ASYNC_REFINE_MS, EDITOR_MOVING_BUDGET_MS,
                                  EDITOR_PROGRESSIVE_MIN_CHUNK, EDITOR_PROGRESSIVE_STEPS_PER_FRAME,
                                  EDITOR_REFINE_DELAY_S)


def refine_above_ms() -> float:
    """Full-quality frames predicted slower than this (ms) are refined
    progressively after motion stops: ``SPLATEDIT_REFINE_ABOVE_MS``, default
    ``EDITOR_ASYNC_REFINE_MS``.  ParameterError names a bad value."""
    text = os.environ.get("SPLATEDIT_REFINE_ABOVE_MS", "")
    if not text:
        return EDITOR_ASYNC_REFINE_MS
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0 < value < float("inf"):
        raise ParameterError("SPLATEDIT_REFINE_ABOVE_MS", f"must be a number of milliseconds > 0, got {text!r}")
    return value


def moving_budget(budget_ms: float) -> float:
    """The moving frame's budget (ms, the whole presented frame) for an
    editor whose frame budget is ``budget_ms``: ``EDITOR_MOVING_BUDGET_MS``
    (30 frames/s) or ``budget_ms`` when smaller."""
    return min(float(budget_ms), EDITOR_MOVING_BUDGET_MS)


@dataclass(frozen=True)
class SceneKey:
    """Everything a drawn scene depends on (equal keys: the frame is current).
    Clouds and bases enter by revision (:mod:`splatedit.app.document.revision`), never by ``id()``."""
    camera: tuple
    size: tuple[int, int]
    cloud_rev: int
    sel_version: int
    basis_rev: int
    dc: bytes | None
    display: tuple          # heat map, grey shading, splat scale, background, eye-dome lighting, two-sided


class FrameScheduler:
    def __init__(self, ed, budget_ms: float):
        self.ed = ed
        self.scene = None
        self.scene_key: SceneKey | None = None
        self.scene_interactive = False
        self.progressive = None          # ProgressiveRefinement of the current view
        #: (ProgressiveRefinement done, brush pick key): its pick map drawn in chunks while still
        self.picking = None
        self._pick_ready = None          # (brush pick key, index map, depth) of the last still view
        #: the last finished ProgressiveRefinement (timings, for benchmarks and tests)
        self.last_progressive = None
        #: progressive refinements finished (status file, tests)
        self.refinements = 0
        self._stepped = None             # the refinement stepped in the frame being drawn
        self._refine_failed_key = None   # view whose refinement failed (not retried)
        self.last_motion = 0.0
        self.frame_ms = 0.0
        self.moving_frame_ms: list[float] = []     # whole frames (render + overlay + present) while moving
        self._rendered_interactive = False
        #: the frame interval while still (the progressive refinement's per-frame budget)
        self.budget_ms = float(budget_ms)
        #: the whole moving frame's budget (30 frames/s unless ``budget_ms`` is smaller)
        self.moving_budget_ms = moving_budget(budget_ms)
        #: full-quality frames predicted slower than this (ms) are refined progressively
        self.refine_above_ms = refine_above_ms()
        self.frame_overhead_ms = 10.0
        self.frames = 0
        self._sel_version_seen = -1

    def invalidate(self) -> None:
        self.scene_key = None
        self.drop_progressive()

    def drop_picking(self) -> None:
        if self.picking is not None:
            self.picking[0].close()
            self.picking = None

    def take_pick(self, key):
        """(index map, depth) of the view with brush pick key ``key``, drawn in
        chunks after its refinement (the brush's pick map), or None."""
        ready = self._pick_ready
        if ready is not None and ready[0] == key:
            return ready[1], ready[2]
        return None

    def drop_progressive(self) -> None:
        self.drop_picking()
        p = self.progressive
        if p is not None:
            if isinstance(self.scene, ResidentFrame) and self.scene.image is p.image:
                self.scene = self.scene_key = None      # its image goes with it: drawn again
            p.close()
            self.progressive = None

    def motion(self) -> None:
        self.last_motion = time.perf_counter()

    # ------------------------------------------------------------ document
    def sync_document(self) -> None:
        s, vp, ed = self.ed.session, self.ed.viewport, self.ed
        cloud, basis, dc = s.display_state(vp.distortion_map)   # the last edit's, for its heat map
        if vp.cloud is not cloud:
            vp.set_cloud(cloud)
            ed.picking.invalidate()
        ed.selection_tools.prepare(s.cloud)
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
                        (vp.distortion_map, vp.grey, vp.splat_scale, vp.background, vp.edl,
                         vp.two_sided))

    def async_refine(self) -> bool:
        """True when full-quality frames are slow enough to be refined progressively."""
        vp = self.ed.viewport
        return vp.ms_per_splat is not None and vp.ms_per_splat * self.ed.session.cloud.n > self.refine_above_ms

    def pending(self) -> bool:
        """A frame must be drawn now (the scene is stale or still interactive)."""
        s = self.ed.session
        return (self.scene_key is None or self.ed.drag is not DragMode.NONE or self.progressive is not None
                or self.picking is not None
                or (self.scene_interactive and not (s is not None and self.async_refine()))
                or (s is not None and self.scene_key != self.state()))

    def busy(self) -> bool:
        """A slow view waits for its refinement to start (motion just stopped)."""
        s = self.ed.session
        return self.scene_interactive and s is not None and self.async_refine()

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
        if (ed.session is not None and ed.drag is DragMode.NONE and not self.scene_interactive
                and self.scene_key is not None and self.scene_key == self.state()):
            ed.camera.view_hint()       # a still view drawn: does it show (almost) nothing?
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
            self._stepped.frame_done(self.frame_ms)
            self._stepped = None
        if self._rendered_interactive:
            self.moving_frame_ms = (self.moving_frame_ms + [self.frame_ms])[-30:]
            # the frame budget is for the whole frame: leave room for overlay + present
            vp = ed.viewport
            extra = max(self.frame_ms - (vp.last_info.ms if vp.last_info else 0.0), 0.0)
            self.frame_overhead_ms = 0.8 * self.frame_overhead_ms + 0.2 * extra
            vp.budget_ms = max(self.moving_budget_ms - self.frame_overhead_ms, 0.3 * self.moving_budget_ms)
        self._rendered_interactive = False

    def _draw_gpu(self, w: int, h: int) -> None:
        """One presented frame on the GPU: the scene (a device-resident frame
        blitted, or pixels uploaded), then the GUI
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
        """Render the scene when it is stale, or advance its progressive refinement."""
        ed = self.ed
        sc = self.scene
        if isinstance(sc, ResidentFrame) and getattr(sc.image, "handle", None) is None:
            self.scene = self.scene_key = None      # its renderer's images were re-created (a resize)
        self.sync_document()
        key = self.state()
        now = time.perf_counter()
        moving = now - self.last_motion < EDITOR_REFINE_DELAY_S or ed.drag is not DragMode.NONE
        if self.progressive is not None and (moving or self.progressive.key != key):
            self.drop_progressive()          # any change: camera, selection, pose, display
        if self.picking is not None:
            self._pick_step(key, moving)
        stale = self.scene is None or key != self.scene_key
        if stale or (self.scene_interactive and not moving):
            if not moving and self.async_refine():
                # a slow full-quality frame: refined progressively, a few chunks per frame
                if stale:
                    self.render_scene(key, interactive=True)
                if self.scene_interactive and not self._progressive_step(key, w, h):
                    self.render_scene(key, interactive=False)    # no progressive frame: drawn at once
            else:
                self.render_scene(key, interactive=moving)

    def _progressive_step(self, key, w: int, h: int) -> bool:
        """Advance the progressive refinement of ``key`` (started here) by one
        presented frame's worth of chunks; False where there is no progressive
        frame (the caller draws the frame at once)."""
        ed, vp = self.ed, self.ed.viewport
        p = self.progressive
        if self.gpu:
            ed.presenter.wait_previous()     # the shown frame may be the image composed now
        if p is None:
            if key == self._refine_failed_key:
                return True
            chunk = max(EDITOR_PROGRESSIVE_MIN_CHUNK,
                        int(self.budget_ms / EDITOR_PROGRESSIVE_STEPS_PER_FRAME / max(vp.ms_per_splat, 1e-9)))
            try:
                frame = vp.progressive(ed.cam, w, h, chunk)
                if frame is None:
                    return False
            except SplatEditError as exc:
                ed.say(f"full-quality frame failed: {exc}")
                self._refine_failed_key = key
                return True
            try:
                under = self._under(w, h)
                p = self.progressive = ProgressiveRefinement(frame, key, under, self.budget_ms, self.gpu)
            except BaseException as exc:
                frame.close()
                if not isinstance(exc, SplatEditError):
                    raise
                ed.say(f"full-quality frame failed: {exc}")
                self._refine_failed_key = key
                return True
        self._stepped = p
        try:
            img = p.advance()
        except SplatEditError as exc:
            ed.say(f"full-quality frame failed: {exc}")
            self._refine_failed_key = key
            self.drop_progressive()
            return True
        # a Gaussian frame's images are pixels on both paths (uploaded on the GPU path)
        self.scene = ResidentFrame(img, w, h) if self.gpu and not isinstance(img, np.ndarray) else img
        if p.done:
            self.scene_interactive = False
            n = ed.session.cloud.n
            vp.last_info = FrameInfo(p.total_ms, n, 1, False, False, gaussians=vp.gaussians is not None)
            vp.ms_per_splat = p.total_ms / max(n, 1)
            self.last_progressive = p
            self.refinements += 1
            self.progressive = None
            pick_key = ed.picking.key()
            if (pick_key is not None and getattr(p.frame, "chunked_pick", True)
                    and (self._pick_ready is None or self._pick_ready[0] != pick_key)):
                self.picking = (p, pick_key)     # the brush's pick map next, while the view is still
            else:
                p.close()
        return True

    def _pick_step(self, key, moving: bool) -> None:
        """One chunk of the still view's pick map (started when its refinement
        ended), dropped on any change; kept for the brush when complete."""
        p, pick_key = self.picking
        if moving or p.key != key or self.ed.picking.key() != pick_key:
            self.drop_picking()
            return
        f = p.frame
        try:
            f.pick_step()
            if f.pick_done:
                idx, depth = f.pick_result()
                self._pick_ready = (pick_key, idx, depth)
                self.drop_picking()
        except SplatEditError as exc:
            self.ed.say(f"pick map failed: {exc}")
            self.drop_picking()

    def _under(self, w: int, h: int):
        """The level-of-detail frame shown under the progressive chunks: on the
        GPU path the LOD renderer's image (not redrawn while the view refines:
        any change drops the refinement), on the CPU path its pixels.  A frame
        the full renderer drew at reduced size (no LOD pyramid yet) is drawn
        again as pixels: the steps re-size that renderer's images."""
        ed, vp = self.ed, self.ed.viewport
        sc = self.scene
        if isinstance(sc, ResidentFrame) and not vp.owns_full_image(sc.image):
            return sc.image, (sc.width, sc.height)
        if isinstance(sc, np.ndarray) and sc.shape[:2] == (h, w):
            return sc
        return vp.render(ed.cam, w, h, interactive=True)

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

    def close(self) -> None:
        self.drop_progressive()
