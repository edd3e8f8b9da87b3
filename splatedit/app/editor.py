"""The interactive editor: ``splatedit edit [FILE]``.

A glfw window presenting through a Vulkan swapchain
(:mod:`splatedit.render.vk.swapchain`); frames come from the EWA splat
renderer (:mod:`splatedit.app.viewport`), the overlay is composited on the
CPU (:mod:`splatedit.app.overlay`).  Loading, fitting and saving run in
worker threads; the loop polls them and stays responsive.

Entry point: :func:`run_editor`.  The controls are in :data:`CONTROLS`.
"""

from __future__ import annotations

import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

from splatedit.app import overlay as ov
from splatedit.app.brush import HANDLE, SUPPORT, BrushPicker, picker_for_view, stroke_points
from splatedit.app.camera_control import OrbitCamera
from splatedit.app.jobs import Job
from splatedit.app.options import CONTROLS, add_arguments, options_from_args  # noqa: F401 (re-exported)
from splatedit.app import selection_tools as seltools
from splatedit.app.session import GRAB, ROTATE, SCALE, Session, ViewInfo
from splatedit.errors import InputError, ParameterError, SplatEditError
from splatedit.tolerances import (EDITOR_ASYNC_REFINE_DELAY_S, EDITOR_ASYNC_REFINE_MS, EDITOR_BRUSH_KEY_STEP,
                                  EDITOR_BRUSH_MAX_PX, EDITOR_BRUSH_MIN_PX, EDITOR_BRUSH_WHEEL_STEP,
                                  EDITOR_CURVE_DOT_PICK_PX, EDITOR_GIZMO_HIT_PX,
                                  EDITOR_GIZMO_MIN_PX, EDITOR_GIZMO_PX, EDITOR_GIZMO_RING_MIN_COS,
                                  EDITOR_GIZMO_RING_PX, EDITOR_GIZMO_RING_SEGMENTS, EDITOR_GIZMO_SCALE_PX,
                                  EDITOR_GUESS_MS_PER_SPLAT,
                                  EDITOR_LOD_MIN_SPLATS, EDITOR_PICK_TOL_PX, EDITOR_REFINE_DELAY_S,
                                  IQR_DEFAULT_TOL)


#: colour of the control curve and its dots
CURVE_RGB = (255, 150, 30)


def _default_save_path(src: Path | None, name: str, bundled: bool) -> Path:
    stem = Path(name).stem if name else (src.stem if src else "model")
    folder = Path.cwd()
    if src is not None and not bundled and os.access(src.parent, os.W_OK):
        folder = src.parent
    p = folder / f"{stem}-edited.ply"
    k = 2
    while p.exists():
        p = folder / f"{stem}-edited-{k}.ply"
        k += 1
    return p


def script_path_for(ply: Path) -> Path:
    return ply.with_suffix("").with_name(ply.with_suffix("").name + ".edits.json")


def _same_file(a, b) -> bool:
    try:
        return Path(a).expanduser().resolve() == Path(b).expanduser().resolve()
    except (OSError, RuntimeError):     # e.g. a symlink loop: compare the spellings
        return Path(a) == Path(b)


def save_refusal(target, model) -> str | None:
    """Why the editor refuses to save to ``target`` (None when it may): saves
    never replace the opened model (a user's file or the bundled one), nor
    does the edit script written beside the save."""
    if model is None:
        return None
    for path in (target, script_path_for(Path(target))):
        if _same_file(path, model):
            return (f"not saved: {path} is the opened model, which saves never replace "
                    "(Ctrl+Shift+S: save under another name)")
    return None


def check_model_file(path) -> None:
    """Refuse a model the editor could not open, before any window exists:
    missing, a directory, an extension :func:`splatedit.io.read` does not
    know, or unreadable.  Raises :class:`InputError` (one line, exit 2)."""
    from splatedit.io import READ_EXTENSIONS, split_scan_index
    p = Path(split_scan_index(path)[0])
    if not p.exists():
        raise InputError("no such file", path=str(path))
    if p.is_dir():
        raise InputError("is a directory, not a file", path=str(path))
    ext = p.suffix.lower()
    if ext not in READ_EXTENSIONS:
        raise InputError(f"unsupported file extension {ext or '(none)'!r} for reading; "
                         f"supported: {', '.join(READ_EXTENSIONS)}", path=str(path))
    try:
        with open(p, "rb") as f:
            f.read(1)
    except OSError as exc:
        raise InputError(f"cannot read the file ({exc.strerror or exc})", path=str(path)) from None


# ------------------------------------------------------------------ editor
class Editor:
    def __init__(self, path=None, *, size=(1280, 720), save_as=None, method="auto",
                 tol=IQR_DEFAULT_TOL, max_centers=None, vsync=True, status_file=None,
                 budget_ms=100.0, lod=True, bundled=False, max_seconds=None):
        import glfw
        from splatedit.render.vk.swapchain import SwapchainPresenter
        from splatedit.render.vk.window import Window
        self.g = glfw
        self.path = Path(path) if path is not None else None
        self.bundled = bundled
        self.save_as = Path(save_as) if save_as else None
        self.method, self.tol, self.max_centers = method, tol, max_centers
        self.status_file = Path(status_file) if status_file else None
        self.use_lod = lod
        self.max_seconds = max_seconds
        self.window = Window("splatedit", *size)
        self.presenter = None
        self.viewport = None
        try:
            self.presenter = SwapchainPresenter(self.window.handle, vsync=vsync)
            from splatedit.app.viewport import Viewport
            self.viewport = Viewport(budget_ms=budget_ms)
        except BaseException:
            self.close()
            raise
        self.cam = OrbitCamera()
        self.session: Session | None = None
        self.cloud_name = self.path.name if self.path else "model"
        self.jobs: dict[str, Job] = {}
        self.running = True
        self.exit_code = 0
        # view / interaction state
        self.brush_radius = 24.0
        self.erase_toggle = False
        self.show_help = False
        self.confirm_quit = False
        self.prompt: str | None = None      # save-as path being typed
        self.prompt_fresh = False            # the first key replaces the proposed path
        self.drag = None                     # orbit/pan/dolly/paint/manip
        self.drag_last = (0.0, 0.0)
        self.stroke_changed = False
        self.manip_by_drag = False
        self.mouse = (0.0, 0.0)
        self.cursor_inside = True
        self.zoom_anchor = None
        self._centre = None
        self._centre_key = None
        self.picker = None
        self.picker_key = None
        self.message = ""
        self.message_time = 0.0
        # frames
        self.scene = None
        self.scene_key = None
        self.scene_interactive = False
        self.refiner = None
        self._refine_failed_key = None   # view whose background frame failed (not retried)
        self.last_motion = 0.0
        self.frame_ms = 0.0
        self.moving_frame_ms: list[float] = []     # whole frames (render + overlay + present) while moving
        self._rendered_interactive = False
        self.budget_ms = float(budget_ms)
        self.frame_overhead_ms = 10.0
        self.frames = 0
        self.saved_path: Path | None = None
        self.saved_script: Path | None = None
        self.validation_count = 0
        self.load_error: SplatEditError | None = None
        self._status_last = None
        self.panel_box = (0, 0, 0, 0)
        self.sel_version_seen = -1
        self.start_time = time.perf_counter()
        self.debug_enabled = os.environ.get("SPLATEDIT_EDITOR_DEBUG", "") not in ("", "0")
        self.tools = seltools.SelectionTools(self._start_graph_job)
        self._warned_no_graph = False

    # ---------------------------------------------------------------- utils
    def wake(self) -> None:
        try:
            self.window.post_empty_event()
        except Exception:  # noqa: BLE001 - window closing
            pass

    def say(self, text: str) -> None:
        self.message = text
        self.message_time = time.perf_counter()
        print(f"splatedit: {text}", file=sys.stderr)

    def debug(self, text: str) -> None:
        if self.debug_enabled:
            print(f"splatedit: debug: {text}", file=sys.stderr, flush=True)

    @property
    def size(self) -> tuple[int, int]:
        return self.window.framebuffer_size()

    def motion(self) -> None:
        self.last_motion = time.perf_counter()

    def _start_graph_job(self, name: str, fn) -> Job:
        job = Job(name, fn, self.wake)
        self.jobs["graph"] = job
        return job

    # -------------------------------------------------------------- loading
    def start_load(self) -> None:
        path = self.path

        def work(progress):
            from splatedit.io import read
            cloud = read(str(path), progress=progress)
            if not cloud.name:
                cloud.name = path.name
            return cloud

        self.jobs["load"] = Job("loading", work, self.wake)

    def on_loaded(self, cloud) -> None:
        self.cloud_name = cloud.name or self.cloud_name
        self.session = Session(cloud, method=self.method, tol=self.tol, max_centers=self.max_centers,
                               on_change=self.wake)
        self.viewport.set_cloud(cloud)
        if cloud.n >= EDITOR_LOD_MIN_SPLATS and self.viewport.ms_per_splat is None:
            # a first guess of the device's cost (lavapipe: ~0.5-1 us per splat at 720p) so
            # that a huge model's first full-quality frame is already drawn in the background
            w, h = self.size
            self.viewport.assume_cost(EDITOR_GUESS_MS_PER_SPLAT, max(w * h, 1))
        r = float(np.linalg.norm(cloud.positions.max(0) - cloud.positions.min(0))) / 2
        self.cam.scene_radius = max(r, 1e-9)
        self.frame_all()
        self.window.set_title(f"splatedit - {self.cloud_name}")
        if self.use_lod and cloud.n >= EDITOR_LOD_MIN_SPLATS:
            def work(progress):
                from splatedit.model.lod import LodPyramid
                return LodPyramid(cloud, progress=progress)
            self.jobs["lod"] = Job("levels of detail", work, self.wake)
        self.tools.prepare(cloud)
        self.say(f"loaded {self.cloud_name}: {cloud.n:,} splats")

    def poll_jobs(self) -> None:
        for name, job in list(self.jobs.items()):
            if not job.done:
                continue
            del self.jobs[name]
            if job.error is not None:
                if name == "load":
                    # reported by run_editor's caller as any bad input: "splatedit: error: ..."
                    err = job.error
                    self.load_error = err if isinstance(err, SplatEditError) else SplatEditError(
                        f"{self.path}: cannot read the model: {err}")
                    self.exit_code = 2
                    self.running = False
                else:
                    self.say(f"{job.name} failed: {job.error}")
                    if name == "graph":
                        self.tools.poll()
                continue
            if name == "load":
                self.on_loaded(job.result)
            elif name == "lod":
                self.viewport.set_pyramid(job.result)
                counts = ", ".join(f"{lvl.n:,}" for lvl in job.result.levels)
                self.say(f"levels of detail ready ({counts} splats)")
            elif name == "save":
                ply, script, pos = job.result
                self.session.history.mark_saved(pos)
                self.saved_path, self.saved_script = ply, script
                self.say(f"saved {ply} and {script.name}")
            elif name == "export":
                self.saved_script = job.result
                self.say(f"edit script written to {job.result}")
            elif name == "graph":
                if self.tools.poll() and self.tools.closure_pending and self.session is not None:
                    self.close_pending_selection()

    # --------------------------------------------------------------- camera
    def frame_all(self) -> None:
        if self.session is None:
            return
        w, h = self.size
        lo, hi = self.session.cloud.bounds()
        c = (lo + hi) / 2
        self.cam.frame(c, float(np.linalg.norm(hi - lo)) / 2, w / max(h, 1))
        self.motion()

    def frame_selection(self) -> None:
        s = self.session
        if s is None:
            return
        m = s.selection.handle if s.selection.handle.any() else s.selection.support
        if not m.any():
            self.frame_all()
            return
        w, h = self.size
        self.cam.frame_points(s.cloud.positions[m], w / max(h, 1))
        self.motion()

    def view_preset(self, yaw: float, pitch: float) -> None:
        self.cam.yaw, self.cam.pitch = yaw, pitch
        self.motion()

    def handle_centre(self) -> np.ndarray:
        """Posed centroid of the active handle (cached per document version and pose)."""
        s = self.session
        k = s.selection.active
        key = (s.version, id(s.cloud), k, s.pose[k].tobytes() if k < len(s.pose) else b"")
        if self._centre_key != key:
            self._centre = s.handle_centroid() if s.selection.handle.any() else None
            self._centre_key = key
        return self._centre

    def curve_dots(self, w: int, h: int) -> np.ndarray:
        """(k + 1, 2) pixel positions of the (moved) picked curve points (NaN behind the eye)."""
        s = self.session
        pts = s.curve_point_positions()
        if not len(pts):
            return np.zeros((0, 2))
        px, d = self.cam.project(pts, w, h)
        px = np.array(px, float)
        px[np.asarray(d) <= 0] = np.nan
        return px

    def curve_dot_hit(self, x: float, y: float) -> int | None:
        w, h = self.size
        px = self.curve_dots(w, h)
        if not len(px):
            return None
        with np.errstate(invalid="ignore"):
            d = np.hypot(px[:, 0] - x, px[:, 1] - y)
        d = np.where(np.isfinite(d), d, np.inf)
        j = int(np.argmin(d))
        return j if d[j] <= EDITOR_CURVE_DOT_PICK_PX else None

    def _gizmo_base(self, w: int, h: int):
        """``(pivot, pivot_px, world_per_px)`` of the gizmo, or None when it is
        hidden (no fitted active handle, a manipulation running, the curve
        tool on, or the handle behind the eye)."""
        s = self.session
        if not s.active_fitted() or s.manip is not None or s.curve_mode:
            return None
        piv = self.handle_centre()
        if piv is None:
            return None
        px, d = self.cam.project(piv, w, h)
        if d[0] <= 0:
            return None
        margin = EDITOR_GIZMO_SCALE_PX
        x, y = float(px[0][0]), float(px[0][1])
        if not (-margin <= x <= w + margin and -margin <= y <= h + margin):
            return None   # far off-screen: its rings would be huge patches for nothing
        return piv, px[0], self.cam.world_per_pixel(float(d[0]), h)

    def gizmo_axes(self, w: int, h: int) -> list:
        """Screen segments ``(axis, p0, p1)`` of the translate gizmo's arrows
        (shown when the basis is ready and nothing is being manipulated)."""
        base = self._gizmo_base(w, h)
        if base is None:
            return []
        piv, p0, wpp = base
        ends, de = self.cam.project(piv + np.eye(3) * (wpp * EDITOR_GIZMO_PX), w, h)
        out = []
        for k in range(3):
            if de[k] > 0 and float(np.hypot(*(ends[k] - p0))) > EDITOR_GIZMO_MIN_PX:
                out.append((k, p0, ends[k]))
        return out

    def gizmo_rings(self, w: int, h: int) -> list:
        """Screen polylines ``(axis, pixels (m, 2))`` of the rotate rings: a
        circle around the handle centroid in the plane normal to each world
        axis (closed: the last point repeats the first; NaN behind the eye);
        rings seen almost edge-on are left out."""
        base = self._gizmo_base(w, h)
        if base is None:
            return []
        piv, _, wpp = base
        back = self.cam.basis()[2]
        t = np.linspace(0.0, 2.0 * math.pi, EDITOR_GIZMO_RING_SEGMENTS + 1)
        t[-1] = 0.0
        out = []
        for k in range(3):
            if abs(float(back[k])) < EDITOR_GIZMO_RING_MIN_COS:
                continue
            e = np.eye(3)
            u, v = e[(k + 1) % 3], e[(k + 2) % 3]
            pts = piv + wpp * EDITOR_GIZMO_RING_PX * (np.cos(t)[:, None] * u + np.sin(t)[:, None] * v)
            px, d = self.cam.project(pts, w, h)
            px = np.array(px, float)
            px[np.asarray(d) <= 0] = np.nan
            out.append((k, px))
        return out

    def gizmo_scale_circle(self, w: int, h: int):
        """``(centre_px, radius_px)`` of the uniform scale grip, or None."""
        base = self._gizmo_base(w, h)
        return None if base is None else (base[1], float(EDITOR_GIZMO_SCALE_PX))

    def gizmo_hit(self, x: float, y: float) -> int | None:
        """The gizmo arrow under pixel (x, y) (outer three quarters, 7 px wide)."""
        w, h = self.size
        best, axis = EDITOR_GIZMO_HIT_PX, None
        q = np.array([x, y])
        for k, p0, p1 in self.gizmo_axes(w, h):
            d = p1 - p0
            t = float(np.clip((q - p0) @ d / (d @ d), 0.0, 1.0))
            dist = float(np.linalg.norm(q - (p0 + t * d)))
            if t >= 0.25 and dist <= best:
                best, axis = dist, k
        return axis

    def ring_hit(self, x: float, y: float) -> int | None:
        """The rotate ring under pixel (x, y) (within EDITOR_GIZMO_HIT_PX), the nearest one."""
        w, h = self.size
        best, axis = EDITOR_GIZMO_HIT_PX, None
        q = np.array([x, y], float)
        for k, px in self.gizmo_rings(w, h):
            a, b = px[:-1], px[1:]
            ok = np.isfinite(a).all(axis=1) & np.isfinite(b).all(axis=1)
            if not ok.any():
                continue
            a, b = a[ok], b[ok]
            d = b - a
            dd = np.maximum((d * d).sum(axis=1), 1e-12)
            t = np.clip(((q - a) * d).sum(axis=1) / dd, 0.0, 1.0)
            dist = float(np.hypot(*(q - (a + t[:, None] * d)).T).min())
            if dist <= best:
                best, axis = dist, k
        return axis

    def scale_hit(self, x: float, y: float) -> bool:
        """Pixel (x, y) is on the scale grip (within EDITOR_GIZMO_HIT_PX of its circle)."""
        w, h = self.size
        c = self.gizmo_scale_circle(w, h)
        if c is None:
            return False
        return abs(math.hypot(x - c[0][0], y - c[0][1]) - c[1]) <= EDITOR_GIZMO_HIT_PX

    def gizmo_pick(self, x: float, y: float) -> tuple | None:
        """What a left press at (x, y) grabs on the gizmo: ``(GRAB, axis)`` on an
        arrow, else ``(ROTATE, axis)`` on a ring, else ``(SCALE, None)`` on the
        scale grip, else None (priority in that order)."""
        k = self.gizmo_hit(x, y)
        if k is not None:
            return GRAB, k
        k = self.ring_hit(x, y)
        if k is not None:
            return ROTATE, k
        if self.scale_hit(x, y):
            return SCALE, None
        return None

    def ring_grab_point(self, k: int, w: int, h: int):
        """A pixel on ring ``k`` that :meth:`gizmo_pick` maps to that ring: the
        ring point farthest from the arrows and the other rings (for the status
        file), or None when every point of it is covered by them."""
        rings = dict(self.gizmo_rings(w, h))
        if k not in rings:
            return None
        q = rings[k][:-1]
        q = q[np.isfinite(q).all(axis=1)]
        if not len(q):
            return None
        ring_d = np.full(len(q), np.inf)         # to the other rings (the nearest ring is picked)
        for j, p in rings.items():
            p = p[np.isfinite(p).all(axis=1)]
            if j != k and len(p):
                ring_d = np.minimum(ring_d, np.hypot(q[:, None, 0] - p[None, :, 0],
                                                     q[:, None, 1] - p[None, :, 1]).min(axis=1))
        arrow_d = np.full(len(q), np.inf)        # to the arrows (picked first)
        for _, p0, p1 in self.gizmo_axes(w, h):
            d = p1 - p0
            t = np.clip((q - p0) @ d / max(float(d @ d), 1e-12), 0.0, 1.0)
            arrow_d = np.minimum(arrow_d, np.hypot(*(q - (p0 + t[:, None] * d)).T))
        score = np.where(arrow_d > EDITOR_GIZMO_HIT_PX + 2, np.minimum(ring_d, arrow_d), -1.0)
        i = int(np.argmax(score))
        return q[i] if score[i] > 4.0 else None

    def view_info(self, pivot=None) -> ViewInfo:
        w, h = self.size
        r, u, b = self.cam.basis()
        piv = self.session.handle_centroid() if pivot is None else np.asarray(pivot, float)
        px, depth = self.cam.project(piv, w, h)
        return ViewInfo(r, u, b, (float(px[0, 0]), float(px[0, 1])),
                        self.cam.world_per_pixel(max(float(depth[0]), 1e-9), h))

    # -------------------------------------------------------------- picking
    def pick_key(self) -> tuple:
        w, h = self.size
        dc = self.viewport.dc
        return (self.cam.state(), w, h, id(self.session.cloud), id(self.session.basis),
                None if dc is None or not dc.any() else dc.tobytes())

    def get_picker(self) -> BrushPicker:
        w, h = self.size
        s = self.session
        key = self.pick_key()
        if self.picker is None or self.picker_key != key:
            ready = self.refiner.take_pick(key) if self.refiner is not None else None
            idx, front = ready if ready is not None else self.viewport.pick(self.cam, w, h)
            self.picker = picker_for_view(idx, front, self.cam, s.cloud.positions, s.cloud.radii,
                                          EDITOR_PICK_TOL_PX)
            self.picker_key = key
        return self.picker

    def splat_under(self, x: float, y: float) -> int:
        p = self.get_picker().pick
        ix, iy = int(x), int(y)
        if 0 <= iy < p.shape[0] and 0 <= ix < p.shape[1]:
            return int(p[iy, ix])
        return -1

    def paint_at(self, points) -> None:
        s = self.session
        erase = self.erase_toggle or bool(self.window.mods() & self.g.MOD_CONTROL)
        picker = self.get_picker()
        graph = self.tools.graph(s.cloud) if self.tools.mode == seltools.BRUSH_3D else None
        if self.tools.mode == seltools.BRUSH_3D and graph is None and not self._warned_no_graph:
            self._warned_no_graph = True
            self.say("3D brush: the neighbour graph is being built, painting visible splats meanwhile")
        displaced = self.viewport.dc is not None and bool(self.viewport.dc.any())
        changed = False
        for x, y in points:
            if graph is not None:
                sph = seltools.brush_sphere(picker, self.cam, s.cloud.positions, x, y, self.brush_radius,
                                       self.size, displaced)
                idx = seltools.splats_in_sphere(graph.tree, sph) if sph is not None else np.zeros(0, np.int64)
            else:
                idx = picker.query(x, y, self.brush_radius)
            changed |= s.paint(idx, erase=erase)
        if changed:
            self.stroke_changed = True
            self.motion()

    # ------------------------------------------------------ selection tools
    def close_pending_selection(self) -> None:
        """The neighbour graph arrived after a selection change: close it now (an undo step)."""
        s = self.session
        if s.manip is not None:
            return
        n = self.tools.close(s)
        if n:
            s.push("fill holes")
            self.say(f"closure added {n:,} splats")

    def selection_tool(self, tool: str, x: float | None = None, y: float | None = None,
                       whole: bool = False) -> None:
        """Run ``tool`` ("grow", "shrink", "connected", "invert") on the brush
        target (support or active handle), close the selection: one undo step."""
        s = self.session
        if s.manip is not None:
            return
        target = s.brush_target
        what = "support" if target == SUPPORT else "handle"
        graph = self.tools.graph(s.cloud)
        if graph is None and tool != "invert":
            self.say("the neighbour graph is still being built: try again in a moment")
            return
        sel = s.selection
        if tool == "grow":
            mask = seltools.grown(sel, graph, target)
        elif tool == "shrink":
            mask = seltools.shrunk(sel, graph, target)
        elif tool == "invert":
            mask = seltools.inverted(sel, target)
        elif tool == "connected":
            picker = self.get_picker()
            sph = seltools.brush_sphere(picker, self.cam, s.cloud.positions, x, y, self.brush_radius, self.size,
                                   self.viewport.dc is not None and bool(self.viewport.dc.any()))
            if sph is None:
                self.say("select connected: put the cursor on the model")
                return
            reach = None
            if not whole:
                reach = np.zeros(s.cloud.n, bool)
                reach[seltools.splats_in_sphere(graph.tree, sph)] = True
            mask = seltools.target_mask(sel, target) | seltools.connected_region(graph, sph.seed, reach)
        else:
            raise ValueError(tool)
        before = s.selection.counts
        if not self.tools.apply(s, target, mask, f"{tool} {what}"):
            self.say(f"{tool}: the {what} did not change")
            return
        n = s.selection.counts[0 if target == SUPPORT else 1] - before[0 if target == SUPPORT else 1]
        added = self.tools.last_added
        self.say(f"{tool} {what}: {n:+,} splats" + (f", closure added {added:,}" if added else ""))

    # ---------------------------------------------------------------- input
    def handle_events(self, events) -> None:
        for e in events:
            try:
                getattr(self, f"on_{e.kind}")(e)
            except SplatEditError as exc:
                self.say(str(exc))

    def on_resize(self, e) -> None:
        self.scene_key = None
        self.motion()

    def on_enter(self, e) -> None:
        self.cursor_inside = bool(e.action)

    def on_iconify(self, e) -> None:
        self.scene_key = None

    def on_close(self, e) -> None:
        self.request_quit()

    def on_char(self, e) -> None:
        if self.prompt is not None and e.char.isprintable():
            self.prompt = e.char if self.prompt_fresh else self.prompt + e.char
            self.prompt_fresh = False

    def on_scroll(self, e) -> None:
        if self.session is None:
            return
        if e.mods & self.g.MOD_CONTROL:
            self.brush_radius = float(np.clip(self.brush_radius * (EDITOR_BRUSH_WHEEL_STEP ** e.dy),
                                              EDITOR_BRUSH_MIN_PX, EDITOR_BRUSH_MAX_PX))
            return
        w, h = self.size
        # zoom to the surface point under the cursor: picked once (when the pick map of
        # this view is at hand), then kept as an anchor while the cursor stays put
        anchor = self.zoom_anchor
        if anchor is None or abs(anchor[0] - e.x) > 2 or abs(anchor[1] - e.y) > 2:
            point = None
            if self.picker is not None and self.picker_key == self.pick_key() and self.drag is None:
                i = self.splat_under(e.x, e.y)
                if i >= 0:
                    point = self.session.cloud.positions[i].copy()
            if point is None:
                point = self.cam.point_at_depth(e.x, e.y, w, h, self.cam.distance)
            anchor = self.zoom_anchor = (e.x, e.y, point)
        _, d = self.cam.project(anchor[2], w, h)
        depth = float(d[0]) if d[0] > 0 else None
        self.cam.dolly(e.dy, e.x, e.y, w, h, depth)
        self.motion()

    def on_move(self, e) -> None:
        x, y = e.x, e.y
        lx, ly = self.drag_last
        dx, dy = x - lx, y - ly
        self.mouse = (x, y)
        self.cursor_inside = True
        w, h = self.size
        s = self.session
        if self.drag == "orbit":
            self.cam.orbit(dx, dy)
            self.motion()
        elif self.drag == "pan":
            self.cam.pan(dx, dy, h)
            self.motion()
        elif self.drag == "dolly":
            self.cam.dolly(-dy / 20.0)
            self.motion()
        elif self.drag == "paint" and s is not None:
            self.paint_at(stroke_points(lx, ly, x, y, self.brush_radius))
        if s is not None and s.manip is not None:
            s.manip.mouse = (x, y)
            self.motion()
        self.drag_last = (x, y)

    def on_button(self, e) -> None:
        g = self.g
        s = self.session
        x, y = e.x, e.y
        self.mouse = (x, y)
        if e.action == g.RELEASE:
            if self.drag == "paint" and s is not None:
                if self.stroke_changed:
                    added = self.tools.close(s)
                    if added:
                        self.say(f"closure added {added:,} splats")
                s.end_stroke(self.stroke_changed)
                self.stroke_changed = False
            if self.drag == "manip" and s is not None and s.manip is not None:
                self.finish_manip()
            self.drag = None
            return
        if e.action != g.PRESS or s is None or self.prompt is not None or self.confirm_quit:
            return
        self.drag_last = (x, y)
        alt = bool(e.mods & g.MOD_ALT)
        shift = bool(e.mods & g.MOD_SHIFT)
        ctrl = bool(e.mods & g.MOD_CONTROL)
        if s.manip is not None:
            if e.button == g.MOUSE_BUTTON_LEFT:
                self.finish_manip()
            elif e.button == g.MOUSE_BUTTON_RIGHT:
                s.cancel()
                self.motion()
            return
        if e.button == g.MOUSE_BUTTON_MIDDLE or (e.button == g.MOUSE_BUTTON_LEFT and alt):
            self.drag = "pan" if shift else ("dolly" if ctrl and not alt else "orbit")
            return
        if e.button == g.MOUSE_BUTTON_LEFT and s.curve_mode:
            self.curve_click(x, y)
            return
        if e.button == g.MOUSE_BUTTON_LEFT:
            hit = self.gizmo_pick(x, y) if s.basis is not None and not ctrl else None
            if hit is not None and s.begin(hit[0], self.view_info(), (x, y)):
                if hit[1] is not None:
                    s.manip.set_axis(hit[1])
                self.drag = "manip"
                self.motion()
                return
            if s.basis is not None and not ctrl and not self.erase_toggle:
                i = self.splat_under(x, y)
                k = s.selection.handle_of(i) if i >= 0 else -1
                self.debug(f"left press at {x:.0f},{y:.0f}: splat {i}, handle {k}")
                if k >= 0:
                    s.select_handle(k)
                    if s.begin(GRAB, self.view_info(), (x, y)):
                        self.drag = "manip"
                        self.motion()
                        return
            self.drag = "paint"
            self.stroke_changed = False
            self.paint_at([(x, y)])

    def on_key(self, e) -> None:
        g = self.g
        if e.action not in (g.PRESS, g.REPEAT):
            return
        k, mods = e.key, e.mods
        ctrl, shift = bool(mods & g.MOD_CONTROL), bool(mods & g.MOD_SHIFT)
        s = self.session
        if self.prompt is not None:
            if k in (g.KEY_ENTER, g.KEY_KP_ENTER):
                path, self.prompt = self.prompt.strip(), None
                if path:
                    self.save(Path(path).expanduser())
            elif k == g.KEY_ESCAPE:
                self.prompt = None
            elif k == g.KEY_BACKSPACE:
                self.prompt = "" if self.prompt_fresh else self.prompt[:-1]
                self.prompt_fresh = False
            return
        if self.confirm_quit:
            if k in (g.KEY_Y, g.KEY_Q):
                self.running = False
            else:                      # N, Esc or anything else: stay
                self.confirm_quit = False
                self.say("quit cancelled")
            return
        if k in (g.KEY_F1, g.KEY_H) and not ctrl:
            self.show_help = not self.show_help
            return
        if s is None:
            if k == g.KEY_Q:           # Esc cancels and never quits
                self.running = False
            return
        # ---- manipulation in progress
        if s.manip is not None:
            m = s.manip
            if k in (g.KEY_X, g.KEY_Y, g.KEY_Z):
                m.set_axis({g.KEY_X: 0, g.KEY_Y: 1, g.KEY_Z: 2}[k])
            elif k in (g.KEY_ENTER, g.KEY_KP_ENTER):
                self.finish_manip()
            elif k == g.KEY_ESCAPE:
                s.cancel()
                self.drag = None
            elif k == g.KEY_BACKSPACE:
                m.backspace()
            elif k == g.KEY_D:
                self.toggle_distortion_map()
            elif k in (g.KEY_G, g.KEY_R, g.KEY_S):
                m.mode = {g.KEY_G: GRAB, g.KEY_R: ROTATE, g.KEY_S: SCALE}[k]
                m.typed = ""
            else:
                ch = _typed_char(g, k)
                if ch is not None:
                    m.type_char(ch)
            self.motion()
            return
        # ---- idle
        if ctrl:
            if k == g.KEY_Z:
                ok = s.redo() if shift else s.undo()
                self.say(("redo" if shift else "undo") + ("" if ok else ": nothing to do"))
            elif k == g.KEY_Y:
                self.say("redo" if s.redo() else "redo: nothing to do")
            elif k == g.KEY_S:
                if shift:
                    self.prompt = str(self.save_target())
                    self.prompt_fresh = True
                else:
                    self.save(self.save_target())
            elif k == g.KEY_E:
                self.export_script()
            elif k in (g.KEY_EQUAL, g.KEY_KP_ADD):
                self.selection_tool("grow")
            elif k in (g.KEY_MINUS, g.KEY_KP_SUBTRACT):
                self.selection_tool("shrink")
            elif k == g.KEY_I:
                self.selection_tool("invert")
            elif k in (g.KEY_KP_1, g.KEY_KP_3, g.KEY_KP_7):   # Blender's habit: the opposite views
                self.view_preset(*{g.KEY_KP_1: (math.pi, 0.0), g.KEY_KP_3: (-math.pi / 2, 0.0),
                                   g.KEY_KP_7: (0.0, math.radians(-89.0))}[k])
            self.motion()
            return
        if k in (g.KEY_G, g.KEY_R, g.KEY_S):
            if not s.active_fitted():
                self.say("paint a support region and a handle first" if not s.selection.handle.any()
                         else "the deformation is still being fitted" if s.fitting
                         else f"cannot move the handle: {s.fit_error}" if s.fit_error
                         else "the active handle is not fitted yet")
            else:
                s.begin({g.KEY_G: GRAB, g.KEY_R: ROTATE, g.KEY_S: SCALE}[k], self.view_info(), self.mouse)
                self.motion()
        elif k in (g.KEY_ENTER, g.KEY_KP_ENTER):
            if s.pose_pending:
                self.commit()
        elif k == g.KEY_ESCAPE and s.pose_pending:
            s.reset_pose()
            self.say("pending moves discarded")
        elif k == g.KEY_ESCAPE and s.curve_mode:
            s.curve_mode = False
        elif k == g.KEY_K:
            if shift:
                s.clear_curve()
            else:
                s.curve_mode = not s.curve_mode
                self.say("curve tool: click on the support to add points, drag a dot to bend"
                         if s.curve_mode else "curve tool off")
        elif k == g.KEY_BACKSPACE and s.curve_points:
            s.remove_curve_point()
        elif k == g.KEY_N:
            if s.add_handle():
                self.say(f"handle {len(s.selection.handles)}: paint it with the handle brush")
            else:
                self.say("the active handle is empty: paint it with the handle brush")
        elif k == g.KEY_DELETE:
            if s.remove_handle():
                self.say(f"handle removed ({len(s.selection.handles)} left)")
        elif k == g.KEY_TAB:
            if len(s.selection.handles) > 1:
                s.cycle_handle(-1 if shift else 1)
                s.brush_target = HANDLE
            else:
                s.brush_target = HANDLE if s.brush_target == SUPPORT else SUPPORT
        elif k in (g.KEY_1, g.KEY_2):
            s.brush_target = SUPPORT if k == g.KEY_1 else HANDLE
        elif k == g.KEY_E:
            self.erase_toggle = not self.erase_toggle
        elif k == g.KEY_V:
            mode = self.tools.toggle_mode()
            self.say("brush: 3D (everything inside the sphere, front and back)" if mode == seltools.BRUSH_3D
                     else "brush: visible splats only")
        elif k == g.KEY_L:
            self.selection_tool("connected", *self.mouse, whole=shift)
        elif k == g.KEY_D and not shift:
            self.toggle_distortion_map()
        elif k == g.KEY_C:
            s.clear(HANDLE if shift else None)
        elif k == g.KEY_LEFT_BRACKET:
            self.brush_radius = max(EDITOR_BRUSH_MIN_PX, self.brush_radius / EDITOR_BRUSH_KEY_STEP)
        elif k == g.KEY_RIGHT_BRACKET:
            self.brush_radius = min(EDITOR_BRUSH_MAX_PX, self.brush_radius * EDITOR_BRUSH_KEY_STEP)
        elif k == g.KEY_HOME:
            self.frame_all()
        elif k in (g.KEY_F, g.KEY_KP_DECIMAL):
            self.frame_selection()
        elif k == g.KEY_KP_1:                       # (Ctrl: the opposite views, above)
            self.view_preset(0.0, 0.0)
        elif k == g.KEY_KP_3:
            self.view_preset(math.pi / 2, 0.0)
        elif k == g.KEY_KP_7:
            self.view_preset(0.0, math.radians(89.0))
        elif k == g.KEY_Q:                          # Esc cancels and never quits
            self.request_quit()
        self.motion()

    # -------------------------------------------------------------- actions
    def toggle_distortion_map(self) -> None:
        """D: colour the support by stretch (renderer heat map) / back to shading."""
        vp = self.viewport
        vp.distortion_map = not vp.distortion_map
        self.say("distortion heat map " + ("on: 1x grey, 1.5x yellow, 2x orange, 3x red, 4x+ dark red"
                                           if vp.distortion_map else "off"))

    def curve_click(self, x: float, y: float) -> None:
        """Curve tool: drag the dot under the cursor, else add a curve point."""
        s = self.session
        j = self.curve_dot_hit(x, y)
        if j is not None:
            if s.begin_curve_point(j, self.view_info(s.curve_point_positions()[j]), (x, y)):
                self.drag = "manip"
                self.motion()
            else:
                self.say("the curve is still being fitted" if s.fitting else
                         f"cannot bend: {s.fit_error}" if s.fit_error else "add a second curve point")
            return
        i = self.splat_under(x, y)
        if i < 0 or not s.selection.support[i]:
            self.say("curve points go on the support (blue): paint it first (1)")
            return
        if s.add_curve_point(s.cloud.positions[i]):
            self.motion()

    def finish_manip(self) -> None:
        """End the running move: applied at once for a single handle, else kept.
        A typed value that cannot be applied (a scale factor <= 0) is refused:
        the manipulation goes on."""
        self._apply(lambda s: s.finish() == "commit")

    def commit(self) -> None:
        """Enter: apply the running move and every pending one as one edit."""
        self._apply(lambda s: s.commit())

    def _apply(self, action) -> None:
        """Run ``action(session)`` (True when an edit was applied) unless the
        running manipulation has a value that cannot be applied."""
        s = self.session
        self.drag = None
        bad = s.manip.problem() if s.manip is not None else None
        if bad:
            self.say(f"{bad}: type another value (Backspace), or Esc to cancel")
            self.motion()
            return
        try:
            if action(s):
                self.say(f"edit {len(s.edits)} applied in {s.last_commit_seconds * 1e3:.0f} ms")
        except SplatEditError as exc:
            s.cancel()
            self.say(f"edit not applied: {exc}")
        self.motion()

    def save_target(self) -> Path:
        if self.save_as is not None:
            return self.save_as
        if self.saved_path is not None:
            return self.saved_path
        self.save_as = _default_save_path(self.path, self.cloud_name, self.bundled)
        return self.save_as

    def save(self, path: Path) -> None:
        s = self.session
        if "save" in self.jobs:
            self.say("a save is already running")
            return
        refusal = save_refusal(path, self.path)
        if refusal:
            self.say(refusal)
            return
        cloud, script, pos = s.cloud, s.edit_script(), s.history.position
        self.save_as = path
        spath = script_path_for(path)

        def work(progress):
            from splatedit.io import write
            progress("saving", 0.0)
            write(str(path), cloud, overwrite=True)
            script.save(spath)
            return path, spath, pos

        self.jobs["save"] = Job("saving", work, self.wake)
        self.say(f"saving {path} ...")

    def export_script(self) -> None:
        s = self.session
        script = s.edit_script()
        spath = script_path_for(self.save_target())

        def work(progress):
            script.save(spath)
            return spath

        self.jobs["export"] = Job("exporting", work, self.wake)

    def request_quit(self) -> None:
        s = self.session
        if s is not None and s.dirty and not self.confirm_quit:
            self.confirm_quit = True
            self.say("unsaved changes: press Y (or Q) to quit without saving, N or Esc to stay")
        else:
            self.running = False

    # ---------------------------------------------------------------- frame
    def sync_document(self) -> None:
        s = self.session
        vp = self.viewport
        if vp.cloud is not s.cloud:
            vp.set_cloud(s.cloud)
            self.picker = None
        self.tools.prepare(s.cloud)
        if self.sel_version_seen != s.version:
            vp.set_selection(s.selection.support, s.selection.handle, s.version, s.selection.others())
            self.sel_version_seen = s.version
        if vp.basis is not s.basis:
            vp.set_basis(s.basis)
        vp.set_dc(s.current_dc() if s.basis is not None else None)

    def scene_state(self) -> tuple:
        s = self.session
        dc = None if self.viewport.dc is None else self.viewport.dc.tobytes()
        return (self.cam.state(), self.size, id(s.cloud), s.version, id(s.basis), dc,
                self.viewport.distortion_map)

    def draw(self) -> None:
        w, h = self.size
        if w == 0 or h == 0 or self.window.iconified():
            return
        t0 = time.perf_counter()
        if self.session is None:
            frame = np.full((h, w, 4), 255, np.uint8)
        else:
            self.sync_document()
            key = self.scene_state()
            moving = time.perf_counter() - self.last_motion < EDITOR_REFINE_DELAY_S or self.drag is not None
            stale = self.scene is None or key != self.scene_key
            if stale or (self.scene_interactive and not moving):
                if not moving and self.async_refine():
                    # a slow full-quality frame: drawn by the background refiner, once the
                    # view has been still for a while (a started frame cannot be aborted)
                    if stale:
                        self.render_scene(key, interactive=True)
                    if (self.scene_interactive and key != self._refine_failed_key
                            and time.perf_counter() - self.last_motion >= EDITOR_ASYNC_REFINE_DELAY_S):
                        self.request_refine(key)
                else:
                    self.render_scene(key, interactive=moving)
            if self.refiner is not None and self.refiner.error is not None:
                # a failed full-quality frame is reported once and not retried for this view
                failed_key, exc = self.refiner.error
                self.say(f"full-quality frame failed: {exc}")
                self.refiner.error = None
                self._refine_failed_key = failed_key
            if self.refiner is not None and self.scene_interactive:
                img = self.refiner.take(key)
                if img is not None and img.shape[:2] == (h, w):
                    self.scene, self.scene_interactive = img, False
                    self.viewport.last_info = {"ms": self.refiner.last_ms, "splats": self.session.cloud.n,
                                               "div": 1, "lod": False, "interactive": False}
            frame = self.scene.copy()
            if frame.shape[:2] != (h, w):
                fr = np.full((h, w, 4), 255, np.uint8)
                hh, ww = min(h, frame.shape[0]), min(w, frame.shape[1])
                fr[:hh, :ww] = frame[:hh, :ww]
                frame = fr
        for p in self.overlay_patches(w, h):
            ov.blend(frame, p)
        self.presenter.present(frame)
        self.frames += 1
        self.frame_ms = (time.perf_counter() - t0) * 1e3
        if self._rendered_interactive:
            self.moving_frame_ms = (self.moving_frame_ms + [self.frame_ms])[-30:]
            # the frame budget is for the whole frame: leave room for overlay + present
            extra = max(self.frame_ms - self.viewport.last_info.get("ms", 0.0), 0.0)
            self.frame_overhead_ms = 0.8 * self.frame_overhead_ms + 0.2 * extra
            self.viewport.budget_ms = max(self.budget_ms - self.frame_overhead_ms, 0.3 * self.budget_ms)
        self._rendered_interactive = False

    def async_refine(self) -> bool:
        """True when full-quality frames are slow enough to be drawn in the background."""
        vp = self.viewport
        return vp.ms_per_splat is not None and vp.ms_per_splat * self.session.cloud.n > EDITOR_ASYNC_REFINE_MS

    def render_scene(self, key, interactive: bool) -> None:
        w, h = self.size
        self.scene = self.viewport.render(self.cam, w, h, interactive=interactive)
        self._rendered_interactive = interactive
        self.scene_key = key
        info = self.viewport.last_info
        self.scene_interactive = bool(interactive and (info.get("lod") or info.get("div", 1) > 1))

    def request_refine(self, key) -> None:
        from splatedit.app.viewport import BackgroundRefiner
        if self.refiner is None:
            self.refiner = BackgroundRefiner(self.wake, self.viewport.budget_ms)
        s = self.session
        w, h = self.size
        cam = OrbitCamera(np.array(self.cam.target, float), self.cam.distance, self.cam.yaw,
                          self.cam.pitch, self.cam.fov_deg, np.array(self.cam.up_axis, float),
                          self.cam.scene_radius)
        self.refiner.request(key, dict(cloud=s.cloud, support=s.selection.support.copy(),
                                       handle=s.selection.handle.copy(), sel_version=s.version,
                                       inactive=s.selection.others(),
                                       basis=s.basis, dc=self.viewport.dc, camera=cam, w=w, h=h,
                                       distortion_map=self.viewport.distortion_map,
                                       pick_key=self.pick_key()))

    # -------------------------------------------------------------- overlay
    def overlay_patches(self, w: int, h: int) -> list:
        patches = []
        s = self.session
        if s is not None:
            patches.extend(self.curve_patches(w, h))
            patches.extend(self.gizmo_patches(w, h))
            if (self.drag not in ("orbit", "pan", "dolly") and s.manip is None and self.prompt is None
                    and not self.confirm_quit and self.cursor_inside):
                col = (230, 60, 60) if (self.erase_toggle or self.window.mods() & self.g.MOD_CONTROL) else \
                    (ov.SUPPORT_RGB if s.brush_target == SUPPORT else ov.HANDLE_RGB)
                img = ov.ring(int(round(self.brush_radius)), col)
                patches.append(ov.Patch(int(self.mouse[0]) - img.shape[1] // 2,
                                        int(self.mouse[1]) - img.shape[0] // 2, img))
                tag = ov.text_panel(("3D" if self.tools.mode == seltools.BRUSH_3D else "VIS",), size=11,
                                    fg=tuple(col) + (255,), pad=2, bg=(20, 22, 28, 150))
                r = int(round(self.brush_radius * 0.7071))
                patches.append(ov.Patch(int(self.mouse[0]) + r + 2, int(self.mouse[1]) + r + 2, tag))
            hl = self.tools.highlighted(s.cloud)
            if hl is not None:
                px, d = self.cam.project(s.cloud.positions[hl], w, h)
                p = seltools.points_patch(np.where((d > 0)[:, None], px, np.nan), (w, h))
                if p is not None:
                    patches.insert(0, p)
        panel = ov.text_panel(tuple(self.panel_lines()))
        self.panel_box = (8, 8, panel.shape[1], panel.shape[0])
        patches.append(ov.Patch(8, 8, panel))
        y = 8 + panel.shape[0] + 6
        for job in self.jobs.values():
            bar = ov.progress_bar(360, job.fraction, f"{job.stage} {job.fraction * 100:3.0f}%")
            patches.append(ov.Patch(8, y, bar))
            y += bar.shape[0] + 4
        if s is not None and s.fit_job is not None:
            j = s.fit_job
            bar = ov.progress_bar(360, j.fraction, f"{j.stage} {j.fraction * 100:3.0f}%")
            patches.append(ov.Patch(8, y, bar))
        if self.show_help:
            img = ov.text_panel(tuple(CONTROLS.rstrip().splitlines()), size=13, bg=(10, 12, 18, 225))
            patches.append(ov.Patch(max((w - img.shape[1]) // 2, 0), max((h - img.shape[0]) // 2, 0), img))
        center_msg = None
        if self.confirm_quit:
            center_msg = ("Unsaved changes.", "Y / Q / Esc: quit without saving     N: keep editing",
                          "(Ctrl+S saves)")
        elif self.prompt is not None:
            center_msg = ("Save as (type a path; Enter: save, Esc: cancel):",
                          self.prompt + ("" if self.prompt_fresh else "_"))
        if center_msg:
            img = ov.text_panel(center_msg, size=16, bg=(40, 20, 20, 235), min_width=420)
            patches.append(ov.Patch((w - img.shape[1]) // 2, (h - img.shape[0]) // 2, img))
        return patches

    def curve_patches(self, w: int, h: int) -> list:
        """The control curve c'(t) as a line strip and its picked points as dots."""
        s = self.session
        out = []
        poly = s.curve_polyline()
        if poly is not None:
            px, d = self.cam.project(poly, w, h)
            px = np.array(px, float)
            px[np.asarray(d) <= 0] = np.nan
            p = ov.polyline_patch(px, CURVE_RGB, 3)
            if p:
                out.append(p)
        dots = self.curve_dots(w, h)
        active = s.manip_target[1] if (s.manip_target and s.manip_target[0] == "curve") else None
        for j, q in enumerate(dots):
            if np.isfinite(q).all():
                out.append(ov.dot_patch(q, (255, 255, 255) if j == active else CURVE_RGB,
                                        7 if j == active else 5))
        return out

    def gizmo_patches(self, w: int, h: int) -> list:
        s = self.session
        out = []
        if len(s.selection.handles) > 1:        # inactive handles: a dark green cross at their centre
            for k, hm in enumerate(s.selection.handles):
                if k != s.selection.active and hm.any():
                    px, d = self.cam.project(s.handle_centroid(k), w, h)
                    if d[0] > 0:
                        out.append(ov.cross_patch(px[0], (20, 90, 25), 6))
        if not s.selection.handle.any() or (s.manip_target and s.manip_target[0] == "curve"):
            return out
        piv = self.handle_centre()
        m = s.current_matrix()
        cur = m[:3, :3] @ piv + m[:3, 3]
        grip = self.gizmo_scale_circle(w, h)
        if grip is not None and np.isfinite(grip[0]).all() and np.abs(grip[0]).max() < 1e5:
            img = ov.ring(int(round(grip[1])), (225, 225, 225), 1)
            out.append(ov.Patch(int(round(grip[0][0])) - img.shape[1] // 2,
                                int(round(grip[0][1])) - img.shape[0] // 2, img))
        for k, px in self.gizmo_rings(w, h):
            p = ov.polyline_patch(px, ov.AXIS_RGB[k], 2)
            if p:
                out.append(p)
        for k, p0, p1 in self.gizmo_axes(w, h):
            p = ov.line_patch(p0, p1, ov.AXIS_RGB[k], 3, dot=True)
            if p:
                out.append(p)
        px, depth = self.cam.project(np.vstack([piv, cur]), w, h)
        if depth.min() <= 0:
            return out
        if s.manip is not None and s.manip.axis is not None:
            a = np.zeros(3)
            a[s.manip.axis] = self.cam.scene_radius
            ends, d2 = self.cam.project(np.vstack([cur - a, cur + a]), w, h)
            if d2.min() > 0:
                p = ov.line_patch(ends[0], ends[1], ov.AXIS_RGB[s.manip.axis], 1)
                if p:
                    out.append(p)
        if s.manip is not None:
            p = ov.line_patch(px[0], px[1], (255, 255, 255), 1)
            if p:
                out.append(p)
        out.append(ov.cross_patch(px[1], ov.HANDLE_RGB if s.active_fitted() else (200, 200, 200)))
        return out

    def panel_lines(self) -> list:
        s = self.session
        if s is None:
            return [f"splatedit - opening {self.path}", "F1: help"]
        st = s.stats()
        lines = [f"{self.cloud_name}   {s.cloud.n:,} splats"]
        tgt = "SUPPORT" if s.brush_target == SUPPORT else "HANDLE"
        erase = "  ERASE" if self.erase_toggle else ""
        mode = "3D" if self.tools.mode == seltools.BRUSH_3D else "VISIBLE"
        lines.append((f"brush: {tgt} {mode}{erase}  radius {self.brush_radius:.0f} px   (Tab, V, E, [ ])",
                      ov.SUPPORT_RGB if s.brush_target == SUPPORT else ov.HANDLE_RGB))
        lines.append(f"support {st['support']:,}   handle {st['handle']:,}")
        hs = s.selection.handles
        if len(hs) > 1 or s.curve_points or s.curve_mode:
            sizes = " ".join(f"[{n:,}]" if k == s.selection.active else f"{n:,}"
                             for k, n in enumerate(st["handle_sizes"]))
            tool = " K:ON" if s.curve_mode else ""
            lines.append((f"handles {len(hs)}: {sizes}   curve {st['curve_points']} pts{tool}   "
                          f"columns {st['columns']}/16", CURVE_RGB if s.curve_mode else (235, 235, 235)))
        if s.pose_pending and s.manip is None:
            lines.append(("pending moves: Enter applies them as one edit, Esc discards", (255, 230, 120)))
        state = st["state"]
        if state == "fitting":
            lines.append(f"solver: {st.get('stage', 'fitting')} {st.get('fraction', 0) * 100:.0f}% "
                         f"({st.get('elapsed', 0):.1f} s)")
        elif "centers" in st:
            lines.append(f"solver: {st['method']}, {st['centers']} centers / {st['constraints']} "
                         f"constraints, residual {st['residual']:.1e}")
            lines.append(f"        precompute {st['fit_seconds']:.2f} s fit + {st['basis_seconds']:.2f} s basis")
        elif state == "error":
            lines.append((f"solver: {st['error'][:90]}", (255, 120, 120)))
        else:
            lines.append("solver: paint a support (1) then a handle (2)")
        if s.manip is not None:
            lines.append((s.manip.describe(), (255, 230, 120)))
        lines += ov.distortion_lines(s.distortion(), self.viewport.distortion_map)
        info = self.viewport.last_info
        if info:
            what = f"{info['splats']:,} splats" + (" LOD" if info.get("lod") else "") + \
                (f" 1/{info['div']} res" if info.get("div", 1) > 1 else "")
            lines.append(f"frame: render {info['ms']:.0f} ms ({what}), total {self.frame_ms:.0f} ms")
        lines.append(f"edits {len(s.edits)}{'  unsaved' if s.dirty else ''}   undo {s.history.position}"
                     f"/{len(s.history) - 1}")
        if self.message and time.perf_counter() - self.message_time < 8:
            lines.append((self.message[:100], (255, 220, 140)))
        lines.append("F1: help")
        return lines

    # --------------------------------------------------------------- status
    def write_status(self) -> None:
        if self.status_file is None:
            return
        s = self.session
        msgs = self.validation_count
        st = {"loaded": s is not None, "frames_presented": self.presenter.frames_presented,
              "running": self.running, "jobs": sorted(self.jobs), "validation_messages": msgs,
              "confirm_quit": self.confirm_quit, "prompt": self.prompt, "help": self.show_help,
              "window": list(self.size), "panel_box": list(self.panel_box),
              "camera": {"distance": round(self.cam.distance, 6), "yaw": round(self.cam.yaw, 6),
                         "pitch": round(self.cam.pitch, 6),
                         "target": [round(float(x), 6) for x in self.cam.target]},
              "moving_frame_ms_median": (round(float(np.median(self.moving_frame_ms)), 1)
                                         if self.moving_frame_ms else None),
              "interactive_frames": len(self.viewport.interactive_frames_ms),
              "interactive_ms_median": (round(float(np.median(self.viewport.interactive_frames_ms[-30:])), 1)
                                        if self.viewport.interactive_frames_ms else None),
              "last_render": {k: (round(v, 1) if isinstance(v, float) else v)
                              for k, v in self.viewport.last_info.items()},
              "saved": str(self.saved_path) if self.saved_path else None,
              "script": str(self.saved_script) if self.saved_script else None}
        if s is not None:
            ss = s.stats()
            st.update(n=s.cloud.n, state=ss["state"], support=ss["support"], handle=ss["handle"],
                      edits=len(s.edits), dirty=s.dirty, undo_position=s.history.position,
                      history=len(s.history), manip=None if s.manip is None else s.manip.mode,
                      brush=s.brush_target, fit_error=ss.get("error"), handles=ss["handles"],
                      active_handle=ss["active_handle"], handle_sizes=ss["handle_sizes"],
                      curve_points=ss["curve_points"], curve_mode=s.curve_mode,
                      pose_pending=ss["pose_pending"], columns=ss["columns"],
                      basis_columns=None if s.basis is None else s.basis.n_columns,
                      brush_mode=self.tools.mode, closure_added=self.tools.last_added,
                      closure_highlight=self.tools.highlighted(s.cloud) is not None)
            idle = (not self.jobs and s.fit_job is None and self.drag is None and s.manip is None
                    and not self.scene_interactive and self.scene_key == self.scene_state()
                    and not (self.refiner is not None and self.refiner.busy))
            st["idle"] = bool(idle)
            w, h = self.size
            st["gizmo"] = [[k, *(round(float(v), 1) for v in (*p0, *p1))]
                           for k, p0, p1 in self.gizmo_axes(w, h)] if w and h else []
            back = self.cam.basis()[2]
            st["gizmo_rings"] = [[k, *(round(float(v), 1) for v in q), round(abs(float(back[k])), 3)]
                                 for k, _ in self.gizmo_rings(w, h)
                                 for q in [self.ring_grab_point(k, w, h)] if q is not None] \
                if w and h else []
            grip = self.gizmo_scale_circle(w, h) if w and h else None
            st["gizmo_scale"] = None if grip is None else [round(float(grip[0][0]), 1),
                                                           round(float(grip[0][1]), 1), grip[1]]
            st["curve_dots"] = [[round(float(v), 1) for v in q] for q in self.curve_dots(w, h)] \
                if w and h else []
            hc = []
            for k, hm in enumerate(s.selection.handles):
                if hm.any() and w and h:
                    px, d = self.cam.project(s.handle_centroid(k), w, h)
                    hc.append([round(float(px[0, 0]), 1), round(float(px[0, 1]), 1)])
                else:
                    hc.append(None)
            st["handle_px"] = hc
        text = json.dumps(st, sort_keys=True)
        if text != self._status_last:
            tmp = self.status_file.with_suffix(".tmp")
            tmp.write_text(text)
            os.replace(tmp, self.status_file)
            self._status_last = text

    def collect_validation(self) -> None:
        try:
            from splatedit.render.vk import drain_validation_messages
            msgs = drain_validation_messages()
        except Exception:  # noqa: BLE001
            msgs = []
        for m in msgs:
            print(f"splatedit: vulkan validation: {m}", file=sys.stderr)
        self.validation_count += len(msgs)

    # ----------------------------------------------------------------- loop
    def run(self) -> int:
        if self.path is None:
            raise SplatEditError("no model to open")
        self.start_load()
        try:
            while self.running:
                s = self.session
                busy = bool(self.jobs) or (s is not None and (s.fit_job is not None or s.manip is not None))
                refining = self.refiner is not None and self.refiner.busy
                async_refine = s is not None and self.async_refine()
                pending = (self.scene_key is None or self.drag is not None
                           or (self.scene_interactive and not async_refine)
                           or (s is not None and self.scene_key != self.scene_state()))
                # waiting for a background refinement (or its start): poll at 20 Hz
                busy = busy or refining or (self.scene_interactive and async_refine)
                w, h = self.size
                if w == 0 or h == 0 or self.window.iconified():
                    pending = False          # minimized: nothing to draw, do not spin
                timeout = 0.0 if pending else (0.05 if busy else 0.5)
                events = self.window.poll(timeout)
                self.handle_events(events)
                self.poll_jobs()
                if self.session is not None:
                    self.session.poll()
                if not self.running:
                    break
                try:
                    self.draw()
                except SplatEditError as exc:       # e.g. a Vulkan error: report, keep the document
                    self.say(f"drawing failed: {exc}")
                    self.scene_key = self.scene_state() if self.session is not None else None
                    time.sleep(0.2)
                self.collect_validation()
                self.write_status()
                if self.max_seconds is not None and time.perf_counter() - self.start_time > self.max_seconds:
                    self.say("time limit reached")
                    break
        finally:
            self.running = False
            self.write_status()
        if self.load_error is not None:
            raise self.load_error
        return self.exit_code

    def close(self) -> None:
        if self.session is not None:
            self.session.close()
        for j in list(self.jobs.values()):
            if j.name == "saving":
                j.wait()     # never leave a half-written file behind
        if self.refiner is not None:
            self.refiner.close()
            self.refiner = None
        if self.viewport is not None:
            self.viewport.close()
            self.viewport = None
        if self.presenter is not None:
            self.presenter.close()
            self.presenter = None
        if self.window is not None:
            self.window.close()
            self.window = None
        self.collect_validation()


def _typed_char(g, k) -> str | None:
    if g.KEY_0 <= k <= g.KEY_9:
        return str(k - g.KEY_0)
    if g.KEY_KP_0 <= k <= g.KEY_KP_9:
        return str(k - g.KEY_KP_0)
    if k in (g.KEY_PERIOD, g.KEY_KP_DECIMAL, g.KEY_COMMA):
        return "."
    if k in (g.KEY_MINUS, g.KEY_KP_SUBTRACT):
        return "-"
    return None


def run_editor(path=None, **options) -> int:
    """Open the interactive editor on ``path`` (None: the bundled model).

    Options: ``size`` (w, h), ``save_as`` (default save path), ``method``,
    ``tol``, ``max_centers`` (solver settings, also written to the exported
    edit script), ``vsync`` (default True), ``status_file`` (test hook: a JSON
    file rewritten whenever the editor's state changes; also read from the
    environment variable ``SPLATEDIT_EDITOR_STATUS``), ``budget_ms`` (frame
    budget while moving, default 100 ms = 10 fps), ``lod`` (default True),
    ``max_seconds`` (quit after this long; tests).
    Returns the process exit code.
    """
    bundled = False
    if path is None:
        from splatedit.data import default_model_path
        path = default_model_path()
        bundled = True
    if options.get("status_file") is None and os.environ.get("SPLATEDIT_EDITOR_STATUS"):
        options["status_file"] = os.environ["SPLATEDIT_EDITOR_STATUS"]
    check_model_file(path)      # before any window: a bad path is one error line, exit 2
    if options.get("save_as") and save_refusal(options["save_as"], path):
        raise ParameterError("--save-as", f"{options['save_as']} is the model being edited; "
                             "saves never replace it: choose another path")
    editor = Editor(path, bundled=bundled, **options)
    try:
        return editor.run()
    finally:
        editor.close()


def main(argv=None) -> int:
    """``python -m splatedit.app.editor [FILE] [options]`` (same as ``splatedit edit``)."""
    import argparse
    p = argparse.ArgumentParser(prog="splatedit edit", description="interactive editor",
                                epilog=CONTROLS, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_arguments(p)
    a = p.parse_args(argv)
    try:
        return run_editor(a.file, **options_from_args(a))
    except SplatEditError as exc:
        print(f"splatedit: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
