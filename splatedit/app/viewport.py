"""The editor's view of the renderer: full-quality and level-of-detail frames.

:class:`Viewport` keeps the renderer(s) in sync with the document lazily (a
renderer is only updated when it draws) and chooses what to draw:

* idle: the full cloud at the window's resolution (full quality);
* interactive (camera or handle moving, brush painting): a level of detail
  from :class:`~splatedit.model.lod.LodPyramid` whose predicted cost fits the
  frame budget, and half resolution when even the coarsest level does not
  fit.  The prediction uses measured frame times (ms per splat, updated
  after every frame).

A Gaussian Splatting scene moves as its most important Gaussians (a
budgeted prefix of :class:`~splatedit.model.gaussian_lod.GaussianLod`'s
ranking, :meth:`Viewport.gaussian_plan`), all of them when still.

The LOD level is drawn by a second :class:`~splatedit.render.renderer.Renderer`
sharing the first one's Vulkan device; its deformation-basis rows are the
representatives' rows (:meth:`LodLevel.rows`), so the handles move at LOD too.

The basis is uploaded with all its columns (4 per handle, k + 1 for a
curve; at most 16): the paper uploads only the active handle's rows, but
with several handles holding simultaneous pending transforms every group's
displacement must be drawn, and switching the active handle must not
re-upload anything.
"""

from __future__ import annotations

import time

from dataclasses import dataclass

import numpy as np

from splatedit.app import revision
from splatedit.app.gaussian_doc import gaussians_of
from splatedit.app.camera_control import OrbitCamera
from splatedit.render.camera import Camera
from splatedit.tolerances import GS_LOD_GUESS_MS_PER_GAUSSIAN, GS_LOD_MIN_COUNT, GS_LOD_PREFER_COUNT


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
        self.inactive = None
        self.sel_version = 0
        self.basis = None
        self.dc = None
        self.pyramid = None
        #: draw the distortion heat map instead of the shaded colours (Renderer.distortion_map)
        self.distortion_map = False
        #: display options (Renderer.grey_shading, Renderer.splat_scale)
        self.grey = False
        self.splat_scale = 1.0
        #: background colour (linear RGB 0..1, Renderer.background)
        from splatedit.tolerances import RENDER_BACKGROUND
        self.background = tuple(float(x) for x in RENDER_BACKGROUND[:3])
        #: a GaussianCloud drawn and picked instead of the splats (set_gaussians)
        self.gaussians = None
        self.gs_slot: _Slot | None = None
        #: ranking of the Gaussians for the level of detail while moving (built in
        #: the background on open, set_gaussian_lod), its renderer, and the cost
        #: measured per drawn Gaussian: full frames, LOD frames per resolution divisor
        self.gs_lod = None
        self.gs_lod_slot: _Slot | None = None
        self._gs_full = None         # (ms, pixels, n) of the last full Gaussian frame
        self._gs_ms_per: dict = {}   # "last": (ms per Gaussian, pixels, divisor) of the last LOD frame
        self._gs_lod_warm = False    # the LOD renderer drew since its last upload (its frames are measured)
        self.ms_per_splat = None     # measured on full-quality frames
        self._ref_pixels = 1
        self._measured: dict = {}    # (level id, divisor) -> (ms, pixels, splats) of recent frames
        self._last_key = None
        self.last_info: FrameInfo | None = None
        self.full_frames_ms: list[float] = []
        self.interactive_frames_ms: list[float] = []

    # ----------------------------------------------------------- document
    def set_cloud(self, cloud) -> None:
        """The document cloud; a Gaussian document (:mod:`splatedit.app.gaussian_doc`)
        also sets its Gaussians (:meth:`set_gaussians`), a plain one clears them."""
        if self.cloud is not None and cloud is not None and cloud.n != self.cloud.n:
            self._measured = {}
            self._last_key = None
            self.ms_per_splat = None
        self.cloud = cloud
        scene = gaussians_of(cloud)
        if scene is not None or self.gaussians is not None:
            self.set_gaussians(scene)

    def set_gaussians(self, gaussians) -> None:
        """The seam for Gaussian Splatting documents (issue 13).  With a
        GaussianCloud set, frames and picks come from a
        :class:`~splatedit.render.gaussians.GaussianRenderer` on the same
        Vulkan device (still frames: every Gaussian), while the document cloud of
        :meth:`set_cloud` stays the Gaussians' splat proxy
        (:func:`splatedit.render.gs_headless.splat_proxy`, same indices) for
        the tools: selection tints, basis rows and dC apply row for row.
        Moving frames draw a level of detail once its ranking is set
        (:meth:`set_gaussian_lod`, :meth:`gaussian_plan`): a second
        GaussianRenderer holding the ranked Gaussians, the rows and tints
        mapped by :class:`~splatedit.model.gaussian_lod.GaussianLod`.
        None returns to the splat renderer."""
        self.gaussians = gaussians
        if gaussians is not None and self.gs_slot is None:
            from splatedit.render.gaussians import GaussianRenderer
            self.gs_slot = _Slot(GaussianRenderer(device=self.full.r.dev))

    def set_gaussian_lod(self, lod) -> None:
        """The :class:`~splatedit.model.gaussian_lod.GaussianLod` of the open
        Gaussian scene (None: every frame draws all Gaussians)."""
        self.gs_lod = lod
        self._gs_ms_per = {}
        if self.gs_lod_slot is not None:
            self.gs_lod_slot.cloud = self.gs_lod_slot.level = None
        if lod is not None and self.full is not None and lod.fits(self.gaussians):
            # upload the level now (1M Gaussians: 0.4 s), not in the first moving frame
            self._sync(self._gs_lod_slot(), lod)

    def set_pyramid(self, pyramid) -> None:
        self.pyramid = pyramid
        self._measured = {k: v for k, v in self._measured.items() if k[0] is None}
        self._last_key = None

    def set_selection(self, support, handle, version: int, inactive=None) -> None:
        """Masks to tint: support, active handle, inactive handles (darker)."""
        self.support, self.handle, self.sel_version = support, handle, version
        self.inactive = inactive

    def set_basis(self, basis) -> None:
        self.basis = basis

    def set_dc(self, dc) -> None:
        from splatedit.deform.rotation import RotationDisplacement
        self.dc = dc if dc is None or isinstance(dc, RotationDisplacement) else np.asarray(dc, float)

    # ------------------------------------------------------------- syncing
    def _sync(self, slot: _Slot, level=None) -> None:
        cloud = self.cloud
        slot.r.distortion_map = self.distortion_map
        slot.r.grey_shading = self.grey
        slot.r.splat_scale = self.splat_scale
        bg = tuple(float(x) for x in self.background[:3])
        if tuple(slot.r.background[:3]) != bg:       # only a change (GUI colour picker)
            slot.r.background = (*bg, *tuple(slot.r.background)[3:])
        if level is not None and slot is self.gs_lod_slot:
            if slot.cloud is not self.gaussians or slot.level is not level:
                slot.r.set_cloud(level.cloud(self.gaussians))   # the ranked Gaussians, most important first
                slot.cloud, slot.level = self.gaussians, level
                self._gs_lod_warm = False
                slot.sel = slot.basis = slot.dc = None
        elif level is not None:
            src = self.pyramid.source
            if slot.cloud is not cloud or slot.level is not level:
                lc = level.cloud if cloud is src else level.deformed(cloud.positions, cloud.u, cloud.v)
                slot.r.set_cloud(lc)
                slot.cloud, slot.level = cloud, level
                slot.sel = slot.basis = slot.dc = None
        elif slot is self.gs_slot:
            if slot.cloud is not self.gaussians:
                slot.r.set_cloud(self.gaussians)
                slot.cloud = self.gaussians
                slot.sel = slot.basis = slot.dc = None
        elif slot.cloud is not cloud:
            slot.r.set_cloud(cloud)
            slot.cloud = cloud
            slot.sel = slot.basis = slot.dc = None
        if slot.sel != (self.sel_version, revision.of(cloud)):
            s, h, i = self.support, self.handle, self.inactive
            if s is not None and len(s) == cloud.n:
                if i is None:
                    i = np.zeros(cloud.n, bool)
                if level is not None:
                    s, h, i = level.masks(s, h, i)
                slot.r.set_selection(s, h, i)
            else:
                slot.r.set_selection(None, None)
            slot.sel = (self.sel_version, revision.of(cloud))
        basis = self.basis
        if slot.basis is not basis:
            if basis is None:
                slot.r.clear_basis()
                slot.basis = None
            else:
                # every column of every group (handles and curve), uploaded once per
                # fit: each frame only dC (K x 3) changes, so all pending transforms
                # are drawn together and switching the active handle costs nothing
                rows = basis.rows_for_gpu()
                detail = getattr(basis, "detail_for_gpu", None)   # a DetailBasis (the detail mode)
                if detail is not None and slot is not self.gs_slot and slot is not self.gs_lod_slot:
                    rows = rows + (detail(),)   # (n_b, lambda) rows: a level's splat keeps its
                if level is not None:           # representative's position, so b = p - lambda n_b holds
                    rows = level.rows(*rows)
                slot.r.set_basis(*rows[:5])
                if len(rows) > 5:
                    slot.r.set_detail(rows[0], rows[5])
                slot.basis = basis
            slot.dc = None
        if basis is not None:
            dc = self.dc if self.dc is not None else np.zeros((basis.n_columns, 3))
            if not isinstance(dc, np.ndarray):      # a RotationDisplacement (immutable)
                if slot.dc is not dc:
                    slot.r.set_displacement(dc)
                    slot.dc = dc
            elif not isinstance(slot.dc, np.ndarray) or not np.array_equal(slot.dc, dc):
                slot.r.set_displacement(dc)
                slot.dc = dc.copy()

    def _lod_slot(self) -> _Slot:
        if self.lod_slot is None:
            self.lod_slot = _Slot(self._Renderer(device=self.full.r.dev))
        return self.lod_slot

    # ------------------------------------------------------------- drawing
    def assume_cost(self, ms_per_splat: float | None, pixels: int) -> None:
        """Forget the measured frame times and assume this full-quality cost
        (tests and benchmarks: simulate a slower or faster device)."""
        self._measured = {}
        self._last_key = None
        self.ms_per_splat = ms_per_splat
        self._ref_pixels = pixels

    def _configs(self):
        """Interactive configurations, finest first: (level or None, divisor)."""
        levels = self.pyramid.levels if self.pyramid is not None else []
        out = [(None, 1)] + [(lvl, 1) for lvl in levels]
        last = levels[-1] if levels else None
        out += [(last, 2), (last, 3)]
        return out

    #: scaling law of lavapipe frame times between configurations (measured on
    #: bunny resamplings: time ~ splats^0.7 (bigger LOD splats cost more fill)
    #: and ~ divisor^-1.2 (fewer pixels, same splat setup))
    COUNT_EXP, DIV_EXP = 0.7, 1.2

    def _predict(self, cfg, pixels: int) -> float:
        level, div = cfg
        n = self.cloud.n
        count = n if level is None else level.n
        key = (revision.of(level) if level is not None else None, div)
        if key in self._measured:
            ms, px, _ = self._measured[key]
            return ms * pixels / max(px, 1)
        if self._last_key is not None and self._last_key in self._measured:
            # from the configuration measured last, with the scaling law
            ms, px, c0 = self._measured[self._last_key]
            d0 = self._last_key[1]
            return (ms * pixels / max(px, 1) * (count / max(c0, 1)) ** self.COUNT_EXP
                    * (d0 / div) ** self.DIV_EXP)
        full = self.ms_per_splat * n * pixels / max(self._ref_pixels, 1)
        return full * (count / n) ** self.COUNT_EXP * (1.0 / div) ** self.DIV_EXP

    def choose(self, interactive: bool, w: int, h: int):
        """(level or None, resolution divisor) for the next frame: the finest
        configuration whose measured (or predicted) time fits the budget."""
        if not interactive or self.ms_per_splat is None or self.cloud is None:
            return None, 1
        configs = self._configs()
        for cfg in configs:
            if self._predict(cfg, w * h) <= self.budget_ms:
                return cfg
        return configs[-1]

    def render(self, cam: OrbitCamera, w: int, h: int, interactive: bool = False,
               resident: bool = False):
        """An (h, w, 4) uint8 frame; with ``resident`` (the GPU presentation
        path) a :class:`ResidentFrame` instead when the splat renderer drew it
        (no readback; the Gaussian renderer still returns pixels)."""
        if self.gaussians is not None:
            plan = self.gaussian_plan(w, h) if interactive else None
            if plan is not None:
                return self._render_gaussian_lod(cam, w, h, *plan)
            self._sync(self.gs_slot)
            t0 = time.perf_counter()
            img = self.gs_slot.r.render(render_camera(cam), w, h)
            ms = (time.perf_counter() - t0) * 1e3
            n = len(self.gaussians)
            self._gs_full = (ms, w * h, n)
            self._ref_pixels = w * h          # the scheduler's measure: slow full frames are refined in chunks
            self.ms_per_splat = ms / n if self.ms_per_splat is None else 0.5 * (self.ms_per_splat + ms / n)
            (self.interactive_frames_ms if interactive else self.full_frames_ms).append(ms)
            self.last_info = FrameInfo(ms, n, 1, False, interactive, gaussians=True)
            return img
        level, div = self.choose(interactive, w, h)
        slot = self.full if level is None else self._lod_slot()
        self._sync(slot, level)          # uploads (new cloud, selection...) are not frame cost
        t0 = time.perf_counter()
        rw, rh = max(1, w // div), max(1, h // div)
        if resident:
            img = ResidentFrame(slot.r.render_resident(render_camera(cam), rw, rh), rw, rh)
        else:
            img = slot.r.render(render_camera(cam), rw, rh)
        if div > 1 and not resident:
            img = np.repeat(np.repeat(img, div, axis=0), div, axis=1)[:h, :w]
            if img.shape[0] < h or img.shape[1] < w:
                pad = np.zeros((h, w, 4), np.uint8)
                pad[:img.shape[0], :img.shape[1]] = img
                img = pad
        ms = (time.perf_counter() - t0) * 1e3
        count = self.cloud.n if level is None else level.n
        key = (revision.of(level) if level is not None else None, div)
        old = self._measured.get(key)
        if old is not None and old[1] == w * h and ms > old[0]:
            ms_avg = 0.5 * (old[0] + ms)       # slower: average out one-off spikes
        else:
            ms_avg = ms                        # faster (or new size): trust it (warm-up is over)
        self._measured[key] = (ms_avg, w * h, count)
        self._last_key = key
        if level is None and div == 1:
            self._ref_pixels = w * h
            est = ms / max(count, 1)
            self.ms_per_splat = est if self.ms_per_splat is None else 0.5 * (self.ms_per_splat + est)
        (self.interactive_frames_ms if interactive else self.full_frames_ms).append(ms)
        self.last_info = FrameInfo(ms, count, div, level is not None, interactive)
        return img if resident else np.ascontiguousarray(img)

    # ------------------------------------------------ Gaussian level of detail
    def gaussian_plan(self, w: int, h: int):
        """(Gaussians drawn, resolution divisor) of the level of detail for a
        moving frame of w x h pixels, or None for all of them at full
        resolution (no ranking yet, or the full frame fits the budget).

        The count is the budget over the measured milliseconds per drawn
        Gaussian (the last LOD frame's, scaled to the divisor by DIV_EXP;
        before one the full frame's, or GS_LOD_GUESS_MS_PER_GAUSSIAN), clamped to
        GS_LOD_MIN_COUNT..the largest level; half resolution when full
        resolution fits fewer than GS_LOD_PREFER_COUNT of them."""
        lod, scene = self.gs_lod, self.gaussians
        if lod is None or not lod.fits(scene) or lod.n <= GS_LOD_MIN_COUNT:
            return None
        px = max(w * h, 1)
        n = len(scene)
        if self._gs_full is not None:
            ms, fpx, fn = self._gs_full
            per_full = ms * px / max(fpx, 1) / max(fn, 1)
        else:
            per_full = GS_LOD_GUESS_MS_PER_GAUSSIAN
        if per_full * n <= self.budget_ms:
            return None
        lo = min(GS_LOD_MIN_COUNT, lod.m)
        count = lo
        last = self._gs_ms_per.get("last")        # (ms per Gaussian, pixels, divisor) of the last LOD frame
        for div in (1, 2):
            if last is not None:
                per = last[0] * px / max(last[1], 1) * (last[2] / div) ** self.DIV_EXP
            else:
                per = per_full / div ** self.DIV_EXP
            fits = self.budget_ms / max(per, 1e-12)
            count = int(min(max(fits, lo), lod.m))
            if fits >= min(GS_LOD_PREFER_COUNT, lod.m):
                return count, div
        return count, 2

    def _gs_lod_slot(self) -> _Slot:
        if self.gs_lod_slot is None:
            from splatedit.render.gaussians import GaussianRenderer
            self.gs_lod_slot = _Slot(GaussianRenderer(device=self.full.r.dev))
        return self.gs_lod_slot

    def _render_gaussian_lod(self, cam: OrbitCamera, w: int, h: int, count: int, div: int) -> np.ndarray:
        """The first ``count`` ranked Gaussians (deformed, tinted as the full
        set) with their coverage compensation, at 1/``div`` resolution."""
        lod = self.gs_lod
        slot = self._gs_lod_slot()
        self._sync(slot, lod)
        warm = self._gs_lod_warm
        slot.r.set_draw_count(count)
        slot.r.splat_scale = self.splat_scale * lod.compensation(count)
        rw, rh = max(1, w // div), max(1, h // div)
        t0 = time.perf_counter()
        img = slot.r.render(render_camera(cam), rw, rh)
        if div > 1:
            img = np.repeat(np.repeat(img, div, axis=0), div, axis=1)[:h, :w]
            if img.shape[0] < h or img.shape[1] < w:
                img = np.pad(img, ((0, h - img.shape[0]), (0, w - img.shape[1]), (0, 0)), mode="edge")
        ms = (time.perf_counter() - t0) * 1e3
        if warm:          # not the first frame after an upload (pipeline compiles, first touch of the buffers)
            per = ms / count
            old = self._gs_ms_per.get("last")
            if old is not None and old[1] == w * h and old[2] == div:
                per = 0.5 * (old[0] + per)
            self._gs_ms_per["last"] = (per, w * h, div)
        self._gs_lod_warm = True
        self.interactive_frames_ms.append(ms)
        self.last_info = FrameInfo(ms, count, div, True, True, gaussians=True)
        return np.ascontiguousarray(img)

    def progressive(self, cam: OrbitCamera, w: int, h: int, chunk: int):
        """A :class:`~splatedit.render.progressive.ProgressiveFrame` of the full
        cloud (``chunk`` splats per step) on the full renderer, synced with the
        document (the detail mode included: its chunks go through its pre-pass);
        for a Gaussian document a
        :class:`~splatedit.render.gs_progressive.GaussianProgressiveFrame` of
        all its Gaussians (``chunk`` per step, after one sorting step); None
        without a document."""
        if self.cloud is None:
            return None
        if self.gaussians is not None:
            from splatedit.render.gs_progressive import GaussianProgressiveFrame
            self._sync(self.gs_slot)
            return GaussianProgressiveFrame(self.gs_slot.r, render_camera(cam), w, h, chunk)
        from splatedit.render.progressive import ProgressiveFrame
        self._sync(self.full)
        return ProgressiveFrame(self.full.r, render_camera(cam), w, h, chunk)

    def owns_full_image(self, image) -> bool:
        """``image`` is the full renderer's output image (re-created when that
        renderer draws another size)."""
        t = self.full.r._targets if self.full is not None else None
        return t is not None and image is t.out

    def pick(self, cam: OrbitCamera, w: int, h: int):
        """(index map (h, w) int64, -1 background; depth (h, w)) of the full cloud."""
        if self.gaussians is not None:
            self._sync(self.gs_slot)
            return self.gs_slot.r.pick(render_camera(cam), w, h)
        self._sync(self.full)
        return self.full.r.pick(render_camera(cam), w, h)

    def close(self) -> None:
        if self.gs_lod_slot is not None:
            self.gs_lod_slot.r.close()
            self.gs_lod_slot = None
        if self.gs_slot is not None:
            self.gs_slot.r.close()
            self.gs_slot = None
        if self.lod_slot is not None:
            self.lod_slot.r.close()
            self.lod_slot = None
        if self.full is not None:
            self.full.r.close()
            self.full = None

