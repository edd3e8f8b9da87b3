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

The LOD level is drawn by a second :class:`~splatedit.render.splat.renderer.Renderer`
sharing the first one's Vulkan device; its deformation-basis rows are the
representatives' rows (:meth:`LodLevel.rows`), so the handles move at LOD too.

The viewport holds the document state and the measured frame cost; what it
draws comes from its scene adapter (:mod:`splatedit.app.view.scenes`:
:class:`~splatedit.app.view.scenes.SplatScene` or
:class:`~splatedit.app.view.scenes.GaussianScene`, chosen by the document),
which drives :class:`~splatedit.render.scene.SceneRenderer` objects.

The basis is uploaded with all its columns (4 per handle, k + 1 for a
curve; at most 16): the paper uploads only the active handle's rows, but
with several handles holding simultaneous pending transforms every group's
displacement must be drawn, and switching the active handle must not
re-upload anything.
"""

from __future__ import annotations

import numpy as np

from splatedit.app.document import revision
from splatedit.app.view.frame_info import FrameInfo, ResidentFrame, render_camera
from splatedit.app.document.gaussian import gaussians_of
from splatedit.app.view.camera_control import OrbitCamera
from splatedit.app.view.scenes import GaussianScene, SplatScene

__all__ = ["Viewport", "FrameInfo", "ResidentFrame", "render_camera"]


class Viewport:
    """The editor's view: document state, the frame budget policy and the
    measured cost; frames, picks and progressive frames come from
    :attr:`scene` (a scene adapter of :mod:`splatedit.app.view.scenes`).

    Args:
        budget_ms: the interactive frame budget (milliseconds).
        renderer: the splat :class:`~splatedit.render.splat.renderer.Renderer` to
            draw with (the editor's, on the presenter's device); a new one otherwise.
    """

    def __init__(self, *, budget_ms: float = 100.0, renderer=None):
        from splatedit.render.splat.renderer import Renderer
        #: the splat scene (always there: its renderer's device is the view's)
        self.splats = SplatScene(renderer if renderer is not None else Renderer())
        #: the scene adapter drawing the document now (:meth:`set_cloud` chooses it)
        self.scene = self.splats
        self._gaussian_scene: GaussianScene | None = None
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
        #: eye-dome lighting (Renderer.edl: depth edges darkened; raw scans without normals)
        self.edl = False
        #: draw back-facing splats too (Renderer.backface_culling off; splat scenes)
        self.two_sided = False
        #: background colour (linear RGB 0..1, Renderer.background)
        from splatedit.tolerances import RENDER_BACKGROUND
        self.background = tuple(float(x) for x in RENDER_BACKGROUND[:3])
        #: a GaussianCloud drawn and picked instead of the splats (set_gaussians)
        self.gaussians = None
        #: ranking of the Gaussians for the level of detail while moving (set_gaussian_lod)
        self.gs_lod = None
        self.ms_per_splat = None     # measured on full-quality frames
        self._ref_pixels = 1
        self._measured: dict = {}    # (level id, divisor) -> (ms, pixels, splats) of recent frames
        self._last_key = None
        self.last_info: FrameInfo | None = None
        self.full_frames_ms: list[float] = []
        self.interactive_frames_ms: list[float] = []

    @property
    def full(self):
        """The splat scene's full-quality slot (``.r``: the editor's Renderer)."""
        return self.splats.full if self.splats is not None else None

    # ----------------------------------------------------------- document
    def set_cloud(self, cloud) -> None:
        """The document cloud; a Gaussian document (:mod:`splatedit.app.document.gaussian`)
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
        GaussianCloud set, the scene is a
        :class:`~splatedit.app.view.scenes.GaussianScene` on the same Vulkan
        device (still frames: every Gaussian; moving frames: a level of detail
        once its ranking is set, :meth:`set_gaussian_lod`), while the document
        cloud of :meth:`set_cloud` stays the Gaussians' splat proxy
        (:func:`splatedit.render.gaussian.headless.splat_proxy`, same indices) for
        the tools: selection tints, basis rows and dC apply row for row.
        None returns to the splat scene."""
        self.gaussians = gaussians
        if gaussians is None:
            self.scene = self.splats
            return
        if self._gaussian_scene is None:
            self._gaussian_scene = GaussianScene(self.splats.device)
            if self.gs_lod is not None:
                self._gaussian_scene.lod = self.gs_lod
        self._gaussian_scene.gaussians = gaussians
        self.scene = self._gaussian_scene

    def set_gaussian_lod(self, lod) -> None:
        """The :class:`~splatedit.model.gaussian_lod.GaussianLod` of the open
        Gaussian scene (None: every frame draws all Gaussians)."""
        self.gs_lod = lod
        if self._gaussian_scene is not None:
            self._gaussian_scene.set_lod(self, lod)

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

    # ------------------------------------------------------ budget policy
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

    def measured(self, level, div: int, ms: float, pixels: int, count: int, interactive: bool) -> None:
        """Record a frame of configuration (``level``, ``div``) that took
        ``ms`` for ``pixels`` output pixels and ``count`` splats (the scenes
        call it after every frame they draw by :meth:`choose`)."""
        key = (revision.of(level) if level is not None else None, div)
        old = self._measured.get(key)
        if old is not None and old[1] == pixels and ms > old[0]:
            ms_avg = 0.5 * (old[0] + ms)       # slower: average out one-off spikes
        else:
            ms_avg = ms                        # faster (or new size): trust it (warm-up is over)
        self._measured[key] = (ms_avg, pixels, count)
        self._last_key = key
        if level is None and div == 1:
            self._ref_pixels = pixels
            est = ms / max(count, 1)
            self.ms_per_splat = est if self.ms_per_splat is None else 0.5 * (self.ms_per_splat + est)
        (self.interactive_frames_ms if interactive else self.full_frames_ms).append(ms)
        self.last_info = FrameInfo(ms, count, div, level is not None, interactive)

    def measured_full(self, ms: float, pixels: int, count: int, interactive: bool, gaussians: bool = False) -> None:
        """Record a full-quality frame drawn outside :meth:`choose` (a scene
        with its own level-of-detail policy): the scheduler's measure (slow
        full frames are refined in chunks) and the frame lists."""
        self._ref_pixels = pixels
        self.ms_per_splat = ms / count if self.ms_per_splat is None else 0.5 * (self.ms_per_splat + ms / count)
        (self.interactive_frames_ms if interactive else self.full_frames_ms).append(ms)
        self.last_info = FrameInfo(ms, count, 1, False, interactive, gaussians=gaussians)

    # ------------------------------------------------------------- drawing
    def render(self, cam: OrbitCamera, w: int, h: int, interactive: bool = False,
               resident: bool = False):
        """An (h, w, 4) uint8 frame; with ``resident`` (the GPU presentation
        path) a :class:`ResidentFrame` instead when the scene's renderer
        leaves frames on the device (``resident_frames``; else pixels)."""
        return self.scene.render(self, cam, w, h, interactive, resident)

    def gaussian_plan(self, w: int, h: int):
        """The Gaussian scene's level-of-detail plan for a moving w x h frame
        (:meth:`GaussianScene.plan`); None without a Gaussian scene."""
        return self._gaussian_scene.plan(self, w, h) if self._gaussian_scene is not None else None

    def progressive(self, cam: OrbitCamera, w: int, h: int, chunk: int):
        """A progressive frame of the full document (``chunk`` elements per
        step) from the scene (splats:
        :class:`~splatedit.render.splat.progressive.ProgressiveFrame`, the detail
        mode included; Gaussians:
        :class:`~splatedit.render.gaussian.progressive.GaussianProgressiveFrame`,
        after one sorting step); None without a document."""
        if self.cloud is None:
            return None
        return self.scene.progressive(self, cam, w, h, chunk)

    def owns_full_image(self, image) -> bool:
        """``image`` is a scene's full renderer's output image (re-created
        when that renderer draws another size)."""
        return any(s is not None and s.owns_image(image) for s in (self.splats, self._gaussian_scene))

    def pick(self, cam: OrbitCamera, w: int, h: int):
        """(index map (h, w) int64, -1 background; depth (h, w)) of the full cloud."""
        return self.scene.pick(self, cam, w, h)

    def close(self) -> None:
        if self._gaussian_scene is not None:
            self._gaussian_scene.close()
            self._gaussian_scene = None
        if self.splats is not None:
            self.splats.close()
            self.splats = None
