"""What the viewport draws, per kind of document: scene adapters over
:class:`~splatedit.render.scene.SceneRenderer` objects (issue 18, item 1).

:class:`Viewport <splatedit.app.view.viewport.Viewport>` holds the document
state (cloud, selection, basis, dC, display options, the measured frame
cost) and hands every frame, pick and progressive frame to its current
scene adapter; it has no branch on the kind of scene.  An adapter owns its
renderers and its level-of-detail policy:

* :class:`SplatScene`: the splat :class:`~splatedit.render.splat.renderer.Renderer`
  and a second one for a level of the LOD pyramid (the viewport's budget
  policy, :meth:`Viewport.choose`), frames left resident on the device;
* :class:`GaussianScene`: a :class:`~splatedit.render.gaussian.renderer.GaussianRenderer`
  for still frames and a second one holding the Gaussians ranked by
  :class:`~splatedit.model.gaussian_lod.GaussianLod`, drawing a budgeted
  prefix of them while moving (:meth:`GaussianScene.plan`).

Both keep their renderers in step with the document through
:func:`sync_slot` (only SceneRenderer members).
"""

from __future__ import annotations

import time

import numpy as np

from splatedit.app.document import revision
from splatedit.app.view.frame_info import FrameInfo, ResidentFrame, render_camera
from splatedit.tolerances import GS_LOD_GUESS_MS_PER_GAUSSIAN, GS_LOD_MIN_COUNT, GS_LOD_PREFER_COUNT


class Slot:
    """One renderer (a SceneRenderer) and what it currently holds."""

    def __init__(self, renderer):
        self.r = renderer
        self.cloud = None      # the object uploaded (the source the upload came from)
        self.sel = None        # selection version uploaded
        self.basis = None      # basis object uploaded (or False = cleared)
        self.level = None
        self.dc = None


def sync_slot(vp, slot: Slot, source, upload, level=None) -> bool:
    """Bring ``slot``'s renderer in step with the viewport ``vp``'s document:
    display options; the scene (``upload()``, the cloud to send, when
    ``source`` or ``level`` changed); the selection tints, basis rows and
    dC, mapped through ``level`` (``masks``, ``rows``) when given.  True when
    the scene was uploaded."""
    cloud = vp.cloud
    r = slot.r
    r.distortion_map = vp.distortion_map
    r.grey_shading = vp.grey
    r.splat_scale = vp.splat_scale
    r.edl = bool(vp.edl) and r.supports_edl
    if getattr(r, "backface_culling", None) is not None:     # splat renderers (Gaussians are never culled)
        r.backface_culling = not vp.two_sided
    bg = tuple(float(x) for x in vp.background[:3])
    if tuple(r.background[:3]) != bg:       # only a change (GUI colour picker)
        r.background = (*bg, *tuple(r.background)[3:])
    uploaded = False
    if slot.cloud is not source or slot.level is not level:
        r.set_cloud(upload())
        slot.cloud, slot.level = source, level
        slot.sel = slot.basis = slot.dc = None
        uploaded = True
    if slot.sel != (vp.sel_version, revision.of(cloud)):
        s, h, i = vp.support, vp.handle, vp.inactive
        if s is not None and len(s) == cloud.n:
            if i is None:
                i = np.zeros(cloud.n, bool)
            if level is not None:
                s, h, i = level.masks(s, h, i)
            r.set_selection(s, h, i)
        else:
            r.set_selection(None, None)
        slot.sel = (vp.sel_version, revision.of(cloud))
    basis = vp.basis
    if slot.basis is not basis:
        if basis is None:
            r.clear_basis()
            slot.basis = None
        else:
            # every column of every group (handles and curve), uploaded once per
            # fit: each frame only dC (K x 3) changes, so all pending transforms
            # are drawn together and switching the active handle costs nothing
            rows = basis.rows_for_gpu()
            detail = getattr(basis, "detail_for_gpu", None)   # a DetailBasis (the detail mode)
            if detail is not None and r.supports_detail:
                rows = rows + (detail(),)   # (n_b, lambda) rows: a level's splat keeps its
            if level is not None:           # representative's position, so b = p - lambda n_b holds
                rows = level.rows(*rows)
            r.set_basis(*rows[:5])
            if len(rows) > 5:
                r.set_detail(rows[0], rows[5])
            slot.basis = basis
        slot.dc = None
    if basis is not None:
        dc = vp.dc if vp.dc is not None else np.zeros((basis.n_columns, 3))
        if not isinstance(dc, np.ndarray):      # a RotationDisplacement (immutable)
            if slot.dc is not dc:
                r.set_displacement(dc)
                slot.dc = dc
        elif not isinstance(slot.dc, np.ndarray) or not np.array_equal(slot.dc, dc):
            r.set_displacement(dc)
            slot.dc = dc.copy()
    return uploaded


def upscale(img: np.ndarray, div: int, w: int, h: int, pad: str = "constant") -> np.ndarray:
    """A 1/``div`` resolution frame repeated to (h, w, 4); missing border
    pixels ``pad``-ed (numpy.pad mode: zeros or the edge)."""
    img = np.repeat(np.repeat(img, div, axis=0), div, axis=1)[:h, :w]
    if img.shape[0] < h or img.shape[1] < w:
        img = np.pad(img, ((0, h - img.shape[0]), (0, w - img.shape[1]), (0, 0)), mode=pad)
    return img


class SplatScene:
    """The splat document's renderers: ``full`` (the editor's renderer) and
    ``lod_slot`` (a level of the pyramid, created on first use on the same
    device).  Frames follow the viewport's budget policy
    (:meth:`Viewport.choose`) and measure it (:meth:`Viewport.measured`)."""

    def __init__(self, renderer):
        self.full = Slot(renderer)
        self.lod_slot: Slot | None = None

    @property
    def device(self):
        return self.full.r.dev

    def _sync(self, vp, slot: Slot, level=None) -> None:
        cloud = vp.cloud
        if level is None:
            sync_slot(vp, slot, cloud, lambda: cloud)
            return
        src = vp.pyramid.source
        sync_slot(vp, slot, cloud,
                  lambda: level.cloud if cloud is src else level.deformed(cloud.positions, cloud.u, cloud.v), level)

    def _lod(self) -> Slot:
        if self.lod_slot is None:
            self.lod_slot = Slot(type(self.full.r)(device=self.full.r.dev))
        return self.lod_slot

    def render(self, vp, cam, w: int, h: int, interactive: bool, resident: bool):
        level, div = vp.choose(interactive, w, h)
        slot = self.full if level is None else self._lod()
        self._sync(vp, slot, level)          # uploads (new cloud, selection...) are not frame cost
        t0 = time.perf_counter()
        rw, rh = max(1, w // div), max(1, h // div)
        if resident and slot.r.resident_frames:
            img = ResidentFrame(slot.r.render_resident(render_camera(cam), rw, rh), rw, rh)
        else:
            resident = False
            img = slot.r.render(render_camera(cam), rw, rh)
        if div > 1 and not resident:
            img = upscale(img, div, w, h)
        ms = (time.perf_counter() - t0) * 1e3
        count = vp.cloud.n if level is None else level.n
        vp.measured(level, div, ms, w * h, count, interactive)
        return img if resident else np.ascontiguousarray(img)

    def pick(self, vp, cam, w: int, h: int):
        self._sync(vp, self.full)
        return self.full.r.pick(render_camera(cam), w, h)

    def progressive(self, vp, cam, w: int, h: int, chunk: int):
        from splatedit.render.splat.progressive import ProgressiveFrame
        self._sync(vp, self.full)
        return ProgressiveFrame(self.full.r, render_camera(cam), w, h, chunk)

    def owns_image(self, image) -> bool:
        """``image`` is the full renderer's output image."""
        t = self.full.r.targets
        return t is not None and image is t.out

    def close(self) -> None:
        if self.lod_slot is not None:
            self.lod_slot.r.close()
            self.lod_slot = None
        self.full.r.close()


class GaussianScene:
    """A Gaussian Splatting document's renderers on ``device``: ``slot``
    (every Gaussian, still frames) and ``lod_slot`` (the Gaussians ranked by
    :attr:`lod`, most important first, drawing a budgeted prefix while
    moving).  The document cloud stays the Gaussians' splat proxy (same
    indices) for the tools: tints, basis rows and dC apply row for row."""

    def __init__(self, device):
        from splatedit.render.gaussian.renderer import GaussianRenderer
        self._make = lambda: GaussianRenderer(device=device)
        self.gaussians = None
        self.slot = Slot(self._make())
        self.lod = None
        self.lod_slot: Slot | None = None
        self.full_cost = None          # (ms, pixels, n) of the last full Gaussian frame
        self.lod_cost = None           # (ms per Gaussian, pixels, divisor) of the last LOD frame
        self._lod_warm = False         # the LOD renderer drew since its last upload (its frames are measured)

    def _sync(self, vp) -> None:
        g = self.gaussians
        sync_slot(vp, self.slot, g, lambda: g)

    def _sync_lod(self, vp) -> Slot:
        if self.lod_slot is None:
            self.lod_slot = Slot(self._make())
        g, lod = self.gaussians, self.lod
        if sync_slot(vp, self.lod_slot, g, lambda: lod.cloud(g), lod):   # the ranked Gaussians
            self._lod_warm = False
        return self.lod_slot

    def set_lod(self, vp, lod) -> None:
        """The ranking of the open scene (None: every frame draws all Gaussians);
        its level is uploaded now (1M Gaussians: 0.4 s), not in the first moving frame."""
        self.lod = lod
        self.lod_cost = None
        if self.lod_slot is not None:
            self.lod_slot.cloud = self.lod_slot.level = None
        if lod is not None and lod.fits(self.gaussians):
            self._sync_lod(vp)

    def plan(self, vp, w: int, h: int):
        """(Gaussians drawn, resolution divisor) of the level of detail for a
        moving frame of w x h pixels, or None for all of them at full
        resolution (no ranking yet, or the full frame fits the budget).

        The count is the budget over the measured milliseconds per drawn
        Gaussian (the last LOD frame's, scaled to the divisor by DIV_EXP;
        before one the full frame's, or GS_LOD_GUESS_MS_PER_GAUSSIAN), clamped to
        GS_LOD_MIN_COUNT..the largest level; half resolution when full
        resolution fits fewer than GS_LOD_PREFER_COUNT of them."""
        lod, scene = self.lod, self.gaussians
        if lod is None or not lod.fits(scene) or lod.n <= GS_LOD_MIN_COUNT:
            return None
        px = max(w * h, 1)
        n = len(scene)
        if self.full_cost is not None:
            ms, fpx, fn = self.full_cost
            per_full = ms * px / max(fpx, 1) / max(fn, 1)
        else:
            per_full = GS_LOD_GUESS_MS_PER_GAUSSIAN
        if per_full * n <= vp.budget_ms:
            return None
        lo = min(GS_LOD_MIN_COUNT, lod.m)
        count = lo
        last = self.lod_cost
        for div in (1, 2):
            if last is not None:
                per = last[0] * px / max(last[1], 1) * (last[2] / div) ** vp.DIV_EXP
            else:
                per = per_full / div ** vp.DIV_EXP
            fits = vp.budget_ms / max(per, 1e-12)
            count = int(min(max(fits, lo), lod.m))
            if fits >= min(GS_LOD_PREFER_COUNT, lod.m):
                return count, div
        return count, 2

    def render(self, vp, cam, w: int, h: int, interactive: bool, resident: bool):
        """Pixels (the Gaussian renderer's frames are read back)."""
        plan = self.plan(vp, w, h) if interactive else None
        if plan is not None:
            return self._render_lod(vp, cam, w, h, *plan)
        self._sync(vp)
        t0 = time.perf_counter()
        img = self.slot.r.render(render_camera(cam), w, h)
        ms = (time.perf_counter() - t0) * 1e3
        n = len(self.gaussians)
        self.full_cost = (ms, w * h, n)
        vp.measured_full(ms, w * h, n, interactive, gaussians=True)
        return img

    def _render_lod(self, vp, cam, w: int, h: int, count: int, div: int) -> np.ndarray:
        """The first ``count`` ranked Gaussians (deformed, tinted as the full
        set) with their coverage compensation, at 1/``div`` resolution."""
        lod = self.lod
        slot = self._sync_lod(vp)
        warm = self._lod_warm
        slot.r.set_draw_count(count)
        slot.r.splat_scale = vp.splat_scale * lod.compensation(count)
        rw, rh = max(1, w // div), max(1, h // div)
        t0 = time.perf_counter()
        img = slot.r.render(render_camera(cam), rw, rh)
        if div > 1:
            img = upscale(img, div, w, h, pad="edge")
        ms = (time.perf_counter() - t0) * 1e3
        if warm:          # not the first frame after an upload (pipeline compiles, first touch of the buffers)
            per = ms / count
            old = self.lod_cost
            if old is not None and old[1] == w * h and old[2] == div:
                per = 0.5 * (old[0] + per)
            self.lod_cost = (per, w * h, div)
        self._lod_warm = True
        vp.interactive_frames_ms.append(ms)
        vp.last_info = FrameInfo(ms, count, div, True, True, gaussians=True)
        return np.ascontiguousarray(img)

    def pick(self, vp, cam, w: int, h: int):
        self._sync(vp)
        return self.slot.r.pick(render_camera(cam), w, h)

    def progressive(self, vp, cam, w: int, h: int, chunk: int):
        from splatedit.render.gaussian.progressive import GaussianProgressiveFrame
        self._sync(vp)
        return GaussianProgressiveFrame(self.slot.r, render_camera(cam), w, h, chunk)

    def owns_image(self, image) -> bool:
        return False

    def close(self) -> None:
        for slot in (self.lod_slot, self.slot):
            if slot is not None:
                slot.r.close()
        self.lod_slot = self.slot = None
