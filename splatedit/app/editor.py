"""The interactive editor: ``splatedit edit [FILE]``.

A glfw window presenting through a Vulkan swapchain
(:mod:`splatedit.render.vk.swapchain`); frames come from the EWA splat
renderer (:mod:`splatedit.app.view.viewport`) scheduled by
:class:`~splatedit.app.view.frames.FrameScheduler`; with the Dear ImGui interface
(:mod:`splatedit.app.ui.gui_panels`: menu bar, panels, help) they stay on the
presenter's device and the GUI and the tools' overlays are drawn over them on
the GPU; without it (``SPLATEDIT_GUI=0`` or a surface that cannot be a blit
target) the overlay is composited on the CPU (:mod:`splatedit.app.ui.overlay`).  Loading, fitting and saving run in
worker threads; the loop polls them and stays responsive.

The :class:`Editor` is a thin loop: window events go to the tools
(:mod:`splatedit.app.tools`: camera, brush, gizmo, curve) through the event
routing (:mod:`splatedit.app.ui.routing`), keys are looked
up in the one keymap (:mod:`splatedit.app.ui.keymap`, which also generates the
help and the manual's controls list) and run the bound action; each tool draws
its overlay.  Files (:mod:`splatedit.app.document.files`): Ctrl+O shows the file
browser (:class:`~splatedit.app.tools.browser.FileBrowserTool`), a file
dropped on the window opens the same way, and (:mod:`splatedit.app.file_actions`) ``open_dialog``,
``open_path`` and ``recent_files`` are the API a GUI
File menu calls (on :attr:`Editor.file_actions`); load / save errors stay in an error box until dismissed.
Entry point: :func:`run_editor`.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
import time
from pathlib import Path

from splatedit.app.tools.pick_brush import ViewPicking
from splatedit.app.crash_guard import CrashGuard
from splatedit.app.document.files import check_model_file, save_refusal, script_path_for  # noqa: F401 (API)
from splatedit.app.document.files import default_save_path as _default_save_path  # noqa: F401 (API)
from splatedit.app.file_actions import FileActions
from splatedit.app.view.frames import FrameScheduler
from splatedit.app.view.camera_control import OrbitCamera
from splatedit.app.document.jobs import Job
from splatedit.app.ui.keymap import Action
from splatedit.app.ui.options import CONTROLS, add_arguments, options_from_args  # noqa: F401 (re-exported)
from splatedit.app.ui.panel import PANEL_MARGIN, HelpView, compose_overlay
from splatedit.app.document.selection import SelectionTools
from splatedit.app.document.session import Session
from splatedit.app.ui.status import StatusWriter
from splatedit.app.ui.recent import RecentFiles
from splatedit.app.ui.routing import HELP_WHEEL_LINES, EventRouter  # noqa: F401 (API)
from splatedit.app.tools.base import DragMode, free_area
from splatedit.app.tools.browser import FileBrowserTool
from splatedit.app.tools.brush import BrushTool
from splatedit.app.tools.camera import CameraTool
from splatedit.app.tools.curve import CurveTool
from splatedit.app.tools.gizmo import GizmoTool
from splatedit.app.tools import protocol_tools
from splatedit.errors import ParameterError, SplatEditError
from splatedit.tolerances import (EDITOR_GUI_PANEL_WIDTH, EDITOR_SPLAT_SCALE_MAX, EDITOR_SPLAT_SCALE_MIN,
                                  EDITOR_SPLAT_SCALE_STEP,
                                  IQR_DEFAULT_TOL)


class Editor:
    """The editor window's loop and the state its parts share.

    It owns its parts and delegates to them: :attr:`routing` (window events
    to the GUI, the questions and the tools; keys through the keymap,
    :class:`~splatedit.app.ui.routing.EventRouter`), :attr:`file_actions`
    (load / open / save / export / quit,
    :class:`~splatedit.app.file_actions.FileActions`), the tools
    (:mod:`splatedit.app.tools`), the frame scheduler and the crash guard.
    """

    def __init__(self, path=None, *, size=(1280, 720), save_as=None, method="auto",
                 tol=IQR_DEFAULT_TOL, max_centers=None, vsync=True, status_file=None,
                 budget_ms=100.0, lod=True, bundled=False, max_seconds=None, offer_recent=False,
                 out_of_core=None):
        import glfw
        from splatedit.render.vk.swapchain import SwapchainPresenter
        from splatedit.render.vk.window import Window
        self.g = glfw
        self.path = Path(path) if path is not None else None
        self.bundled = bundled
        self.save_as = Path(save_as) if save_as else None
        self.method, self.tol, self.max_centers = method, tol, max_centers
        self.status = StatusWriter(Path(status_file) if status_file else None)
        self.use_lod = lod
        #: open scans out of core: True / False, None: by size (:func:`splatedit.app.document.outofcore.is_out_of_core`)
        self.out_of_core = out_of_core
        self.max_seconds = max_seconds
        self.offer_recent = offer_recent
        self.window = self.presenter = self.viewport = None
        self.frames = FrameScheduler(self, budget_ms)
        self._init_state(OrbitCamera(), glfw)
        self.window = Window("splatedit", *size)
        try:
            self.presenter = SwapchainPresenter(self.window.handle, vsync=vsync)
            from splatedit.app.view.viewport import Viewport
            pres = self.presenter
            if pres.gpu_targets and pres.can_blit and os.environ.get("SPLATEDIT_GUI", "1") != "0":
                # GPU path: one device renders, draws the GUI and presents (no readback)
                from splatedit.app.ui.gui_panels import EditorGui
                from splatedit.render.splat.renderer import Renderer
                self.viewport = Viewport(budget_ms=self.frames.moving_budget_ms, renderer=Renderer(device=pres.dev))
                self.gui = EditorGui(self, pres.dev)
            else:       # CPU fallback: frames read back, overlay blended on the CPU
                self.viewport = Viewport(budget_ms=self.frames.moving_budget_ms)
        except BaseException:
            self.close()
            raise

    def _init_state(self, cam: OrbitCamera, g) -> None:
        """Everything but the window and the GPU (tests build editors on this)."""
        self.cam = cam
        self.g = g
        #: the Dear ImGui interface (None: the CPU overlay fallback, or no window)
        self.gui = None
        self.session: Session | None = None
        #: the out-of-core scan behind the session (:mod:`splatedit.app.document.outofcore`), or None
        self.ooc = None
        #: the central exception guard, recovery copies and the restore question
        #: (:class:`~splatedit.app.crash_guard.CrashGuard`)
        self.crash_guard = CrashGuard(self)
        #: window events and key actions (:class:`~splatedit.app.ui.routing.EventRouter`)
        self.routing = EventRouter(self)
        #: the File menu API (:class:`~splatedit.app.file_actions.FileActions`)
        self.file_actions = FileActions(self)
        self.cloud_name = self.path.name if self.path else "model"
        self.jobs: dict[str, Job] = {}
        self.running = True
        self.exit_code = 0
        self.load_error: SplatEditError | None = None
        self.error_box: str | None = None    # a load / save error shown until dismissed
        self.error_rect: tuple | None = None  # its x, y, w, h on screen (clicks dismiss it)
        if not hasattr(self, "recent"):
            self.recent = RecentFiles()
        # modal questions
        self.confirm_quit = False
        self.confirm_open: Path | None = None   # open this model without saving?
        self.prompt: str | None = None      # save-as path being typed
        self.prompt_selected = False         # Ctrl+A selected the whole path (typing replaces it)
        # pointer
        self.drag = DragMode.NONE
        self.drag_tool = None
        self.drag_last = (0.0, 0.0)
        self.mouse = (0.0, 0.0)
        self.cursor_inside = True
        # overlays
        self.message = ""
        self.message_time = 0.0
        self.help = HelpView()
        self.panel_visible = True
        self.panel_box: tuple | None = (0, 0, 0, 0)
        self.saved_path: Path | None = None
        self.saved_script: Path | None = None
        self.validation_count = 0
        self.start_time = time.perf_counter()
        if not hasattr(self, "frames"):
            self.frames = FrameScheduler(self, 100.0)
        self.debug_enabled = os.environ.get("SPLATEDIT_EDITOR_DEBUG", "") not in ("", "0")
        #: the neighbour graphs of the document's clouds (built in the background) and
        #: the closure of selection edits (:class:`~splatedit.app.document.selection.SelectionTools`)
        self.selection_tools = SelectionTools(self.start_graph_job)
        #: the pick map of the current view (:class:`~splatedit.app.tools.pick_brush.ViewPicking`)
        self.picking = ViewPicking(self)
        # tools: press order (after every tool's press_modal)
        self.camera = CameraTool(self)
        self.brush = BrushTool(self)
        self.gizmo = GizmoTool(self)
        self.curve = CurveTool(self)
        # the tools on the protocol register themselves (app/tools/*.py with TOOL = ...):
        # self.region, self.mirror, self.delete, self.pivot, ...
        found = [cls(self) for cls in protocol_tools()]
        for tool in found:
            setattr(self, tool.name, tool)
        self.tools = (self.camera, self.curve, self.gizmo, self.brush, *found)
        self.browser = FileBrowserTool(self)
        self.actions = self._action_table()
        self.manip_actions = self.gizmo.manip_actions()

    # ------------------------------------------------------------- document
    @property
    def session(self):
        """The open document (:class:`~splatedit.app.document.session.Session`), or None."""
        return self.__dict__.get("_session")

    @session.setter
    def session(self, s) -> None:
        # the document's selection edits close through the editor's neighbour graphs
        edit = getattr(s, "selection_edit", None)
        if edit is not None and edit.graphs is None:
            edit.graphs = self.selection_tools
        self.__dict__["_session"] = s

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

    def show_error(self, text: str) -> None:
        """An error box in the window (until Esc / Enter / a click on it) and on stderr."""
        self.error_box = text
        self.message = ""
        print(f"splatedit: error: {text}", file=sys.stderr, flush=True)
        self.wake()

    def dismiss_error(self) -> None:
        self.error_box = self.error_rect = None

    def debug(self, text: str) -> None:
        if self.debug_enabled:
            print(f"splatedit: debug: {text}", file=sys.stderr, flush=True)

    @property
    def size(self) -> tuple[int, int]:
        return self.window.framebuffer_size()

    def view_area(self) -> tuple[float, float, float, float]:
        """The part of the window framing fills, (x0, y0, x1, y1) fractions
        (:func:`~splatedit.app.tools.base.free_area`): beside the side panel
        when it is shown, below the GUI's menu bar."""
        w, h = self.size
        box = self.panel_box if self.panel_visible else None
        if box is not None and tuple(box) == (0, 0, 0, 0):
            # no frame laid out yet (a model opened before the first GUI frame): the GUI
            # panel's first place, at the left; the CPU text panel's size is not known
            box = (PANEL_MARGIN, 0, EDITOR_GUI_PANEL_WIDTH, 0) if self.gui is not None else None
        top = self.gui.menu_height if self.gui is not None else 0.0
        return free_area(w, h, box, top)

    def motion(self) -> None:
        self.frames.motion()

    def modal(self) -> bool:
        """A question is open (save-as path, quit / open with unsaved changes, restore a
        recovery copy, the file browser)."""
        return (self.prompt is not None or self.confirm_quit or self.confirm_open is not None
                or self.crash_guard.confirm_restore is not None or self.browser.shown)

    @property
    def frame_ms(self) -> float:
        return self.frames.frame_ms

    @property
    def moving_frame_ms(self) -> list:
        return self.frames.moving_frame_ms

    def start_graph_job(self, name: str, fn) -> Job:
        job = Job(name, fn, self.wake)
        self.jobs["graph"] = job
        return job

    def idle(self) -> bool:
        """Nothing left to do until the next input (tests wait for this)."""
        s, fr = self.session, self.frames
        return (s is not None and not self.jobs and s.fit_job is None and not s.committing
                and self.drag is DragMode.NONE
                and s.manip is None and not fr.scene_interactive and fr.scene_key == fr.state())

    # -------------------------------------------------------------- actions
    def _action_table(self) -> dict:
        t = {}
        for tool in self.tools:
            t.update(tool.actions())
        s = lambda: self.session  # noqa: E731
        t.update(self.browser.actions())
        fa = self.file_actions
        t.update({
            Action.OPEN: fa.open_dialog, Action.DISMISS_ERROR: self.dismiss_error,
            Action.DISTORTION_MAP: self.toggle_distortion_map, Action.COLOUR_MODE: self.toggle_colours,
            Action.EDL: self.toggle_edl, Action.TWO_SIDED: self.toggle_two_sided,
            Action.DEFORMATION_MODE: self.cycle_deformation,
            Action.SPLATS_SMALLER: lambda: self.scale_splats(1.0 / EDITOR_SPLAT_SCALE_STEP),
            Action.SPLATS_LARGER: lambda: self.scale_splats(EDITOR_SPLAT_SCALE_STEP),
            Action.PANEL: self.toggle_panel, Action.HELP: self.help.toggle,
            Action.HELP_DOWN: lambda: self.help.page(1), Action.HELP_UP: lambda: self.help.page(-1),
            Action.HELP_CLOSE: self.help.toggle,
            Action.UNDO: lambda: self.say("undo" if s().undo() else "undo: nothing to do"),
            Action.REDO: lambda: self.say("redo" if s().redo() else "redo: nothing to do"),
            Action.SAVE: fa.save_edits, Action.SAVE_AS: fa.ask_save_as,
            Action.EXPORT_SCRIPT: fa.export_script, Action.QUIT: fa.request_quit})
        return t

    def cycle_deformation(self) -> None:
        """B: the next deformation mode of new edits (a Gaussian scene has no detail mode: B says so)."""
        s = self.session
        mode = s.cycle_deformation()
        self.say(f"deformation: {mode.value}" + ("" if s.detail_available else f"; {s.DETAIL_UNAVAILABLE}"))

    def toggle_distortion_map(self) -> None:
        """D: colour the support by stretch (renderer heat map) / back to shading."""
        vp = self.viewport
        vp.distortion_map = not vp.distortion_map
        self.say("distortion heat map " + ("on: 1x grey, 1.5x yellow, 2x orange, 3x red, 4x+ dark red"
                                           if vp.distortion_map else "off"))

    def toggle_colours(self) -> None:
        """M: the file's colours / uniform grey shading."""
        vp = self.viewport
        vp.grey = not vp.grey
        grey = "uniform grey shading" if getattr(vp, "gaussians", None) is None else "grey (luminance)"
        self.say(f"colours: {grey}" if vp.grey else "colours: the file's colours")

    def toggle_edl(self) -> None:
        """Shift+E: eye-dome lighting on / off (splat models; a Gaussian scene says it has none)."""
        vp = self.viewport
        if getattr(vp, "gaussians", None) is not None:
            vp.edl = False
            self.say("eye-dome lighting is for point-splat models, not Gaussian splat scenes")
            return
        vp.edl = not vp.edl
        self.say("eye-dome lighting " + ("on: depth edges and creases darkened (Shift+E: off)"
                                         if vp.edl else "off"))

    def toggle_two_sided(self) -> None:
        """T: draw the splats seen from behind too (back-face culling off) / not."""
        vp = self.viewport
        if getattr(vp, "gaussians", None) is not None:
            vp.two_sided = False
            self.say("a Gaussian scene draws every Gaussian from both sides already")
            return
        vp.two_sided = not vp.two_sided
        self.say("two-sided splats: " + ("on, splats seen from behind are drawn too (T: off)" if vp.two_sided
                                         else "off, splats facing away are not drawn"))

    def scale_splats(self, factor: float) -> None:
        """Shift+[ / Shift+]: draw every splat's axes this much larger (display only)."""
        vp = self.viewport
        vp.splat_scale = min(max(vp.splat_scale * factor, EDITOR_SPLAT_SCALE_MIN), EDITOR_SPLAT_SCALE_MAX)
        self.say(f"splat size {vp.splat_scale:.2f}x (display only; saves are unchanged)")

    def toggle_panel(self) -> None:
        self.panel_visible = not self.panel_visible

    def run_action(self, action: Action) -> None:
        """Run the handler bound to ``action`` (keys and GUI buttons share it;
        :meth:`~splatedit.app.ui.routing.EventRouter.run_action`)."""
        self.routing.run_action(action)

    def finish_manip(self) -> None:
        self.gizmo.finish_manip()

    def commit(self) -> None:
        self.gizmo.commit_pose()

    # -------------------------------------------------------------- overlay
    def overlay_shapes(self, w: int, h: int) -> list:
        """Every tool's overlay shapes of a ``w`` x ``h`` frame
        (:mod:`splatedit.app.tools.shapes`), in tool order (none without a model);
        the GPU path and the CPU fallback paint this one list."""
        if self.session is None:
            return []
        return [shape for tool in self.tools for shape in tool.shapes(w, h)]

    def overlay_patches(self, w: int, h: int) -> list:
        return compose_overlay(self, w, h)

    # --------------------------------------------------------------- status
    def write_status(self) -> None:
        self.status.write(self)

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
        """The event loop until quit.  Every place it dispatches work (events,
        finished jobs, the session's fits and commits, frames, the status file)
        runs under :meth:`~splatedit.app.crash_guard.CrashGuard.guarded`: a bug
        there is shown in the error box and the document is kept (with a
        recovery copy of unsaved edits); SIGTERM ends it like Ctrl+C
        (KeyboardInterrupt), after writing a recovery copy of unsaved edits."""
        if self.path is None:
            raise SplatEditError("no model to open")
        fa = self.file_actions
        fa.start_load()
        guard = self.crash_guard
        if not guard.offer_recovery() and self.offer_recent and fa.recent_files():
            fa.open_dialog(Path.cwd())
        restore_sigterm = _sigterm_as_interrupt()
        try:
            self._loop()
        except KeyboardInterrupt:
            guard.recover_on_exit("the editor was ended (SIGTERM or Ctrl+C)")
            raise
        except BaseException as exc:
            guard.recover_on_exit(f"internal error: {exc!r}")
            raise
        finally:
            restore_sigterm()
        if self.load_error is not None:
            raise self.load_error
        return self.exit_code

    def _loop(self) -> None:
        fr, guarded = self.frames, self.crash_guard.guarded
        try:
            while self.running:
                s = self.session
                busy = bool(self.jobs) or (s is not None and (s.fit_job is not None or s.manip is not None
                                                              or s.committing)) or self.ooc is not None
                pending = fr.pending() or (self.gui is not None and self.gui.needs_frames())
                busy = busy or fr.busy()
                w, h = self.size
                if w == 0 or h == 0 or self.window.iconified():
                    pending = False          # minimized: nothing to draw, do not spin
                events = self.window.poll(0.0 if pending else (0.05 if busy else 0.5))
                self.routing.handle_events(events)          # each event guarded on its own
                with guarded("collecting a finished job"):
                    self.file_actions.poll_jobs()
                if self.ooc is not None:
                    with guarded("refining the out-of-core view"):
                        self.ooc.poll(self)
                if self.session is not None:
                    with guarded("landing a fit or an edit"):
                        self.session.poll()
                        self.gizmo.report_commit()
                if not self.running:
                    break
                self._draw_guarded()
                self.collect_validation()
                with guarded("writing the status file"):
                    self.write_status()
                if self.max_seconds is not None and time.perf_counter() - self.start_time > self.max_seconds:
                    self.say("time limit reached")
                    break
        finally:
            self.running = False
            with contextlib.suppress(Exception):
                self.write_status()

    def _draw_guarded(self) -> None:
        """One frame; a failure (a Vulkan error, or a bug) is reported and the
        same scene is not retried at once (no error loop at the frame rate)."""
        fr, guard = self.frames, self.crash_guard
        errors, failed = guard.internal_errors, False
        with guard.guarded("drawing a frame"):
            try:
                fr.draw()
            except SplatEditError as exc:       # e.g. a Vulkan error: report, keep the document
                self.say(f"drawing failed: {exc}")
                failed = True
        if not failed and guard.internal_errors == errors:
            return
        if self.gui is not None:        # a frame left half laid out is closed (no-op after a whole one)
            with guard.guarded("closing the interrupted frame"):
                self.gui.recover()
        fr.scene_key = fr.state() if self.session is not None else None
        time.sleep(0.2)

    def close(self) -> None:
        if self.session is not None:
            self.session.close()
        for j in list(self.jobs.values()):
            if j.name == "saving":
                j.wait()     # never leave a half-written file behind
        self.selection_tools.cancel()   # a graph build stops at its next tile (its pool would hold up the exit)
        self.frames.close()
        if self.gui is not None:
            if self.presenter is not None:
                self.presenter.dev.wait_idle()
            self.gui.close()
            self.gui = None
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


def _raise_interrupt(signum, frame):
    raise KeyboardInterrupt


def _sigterm_as_interrupt():
    """SIGTERM ends the editor like Ctrl+C (KeyboardInterrupt: a recovery
    copy of unsaved edits is written, the window closed, exit code 130).
    Returns a function that puts the previous handler back (a no-op off the
    main thread, where handlers cannot be set)."""
    if threading.current_thread() is not threading.main_thread():
        return lambda: None
    previous = signal.signal(signal.SIGTERM, _raise_interrupt)
    return lambda: signal.signal(signal.SIGTERM, previous if previous is not None else signal.SIG_DFL)


def run_editor(path=None, **options) -> int:
    """Open the interactive editor on ``path`` (None: the bundled model).

    Options: ``size`` (w, h), ``save_as`` (default save path), ``method``,
    ``tol``, ``max_centers`` (solver settings, also written to the exported
    edit script), ``vsync`` (default True), ``status_file`` (test hook: a JSON
    file rewritten whenever the editor's state changes; also read from the
    environment variable ``SPLATEDIT_EDITOR_STATUS``), ``budget_ms`` (frame
    budget while moving, default 100 ms = 10 fps), ``lod`` (default True),
    ``max_seconds`` (quit after this long; tests), ``out_of_core`` (True /
    False; None: by the file's size, see :mod:`splatedit.app.document.outofcore`).
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
    from splatedit.app.view.frames import refine_above_ms
    refine_above_ms()           # so is a bad SPLATEDIT_REFINE_ABOVE_MS
    from splatedit.app.document.outofcore import point_budgets
    point_budgets()             # and a bad SPLATEDIT_OOC_BUDGET
    if options.get("save_as") and save_refusal(options["save_as"], path):
        raise ParameterError("--save-as", f"{options['save_as']} is the model being edited; "
                             "saves never replace it: choose another path")
    editor = Editor(path, bundled=bundled, offer_recent=bundled, **options)
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
    except KeyboardInterrupt:
        print("splatedit: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
