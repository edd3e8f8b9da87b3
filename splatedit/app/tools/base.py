"""What every editor tool is: :class:`Tool`, and the :class:`DragMode` of a
mouse drag in progress."""

from __future__ import annotations

import enum
from typing import Callable

import numpy as np

from splatedit.app.ui.keymap import KEYMAP, Action, Binding, Section


class DragMode(enum.Enum):
    """What a held mouse button is doing."""
    NONE = "none"
    ORBIT = "orbit"
    PAN = "pan"
    DOLLY = "dolly"
    PAINT = "paint"
    MANIP = "manip"     # a handle or curve point follows the mouse
    REGION = "region"   # a box or lasso is being drawn

    @property
    def camera(self) -> bool:
        return self in (DragMode.ORBIT, DragMode.PAN, DragMode.DOLLY)


class Tool:
    """An editor tool.  ``ed`` is the :class:`~splatedit.app.editor.Editor`
    (its session, camera, viewport, ``say`` and ``motion``).

    Mouse: the editor offers a button press to every tool's
    :meth:`press_modal` first, then to :meth:`press` in its tool order; the
    first to return a :class:`DragMode` owns the drag (:meth:`drag` on each
    move, :meth:`release` at the end).  Keys: :meth:`actions` maps keymap
    :class:`~splatedit.app.ui.keymap.Action` values to handlers.  Drawing:
    :meth:`underlay` and :meth:`overlay` return overlay patches (CPU
    path only); :meth:`shapes` returns backend-neutral shapes
    (:mod:`splatedit.app.tools.shapes`) drawn by both the GPU and the CPU path:
    tools on the protocol use only :meth:`shapes` and :attr:`ctx`.
    """
    #: the help section of this tool's keymap rows
    section: Section | None = None

    def __init__(self, ed):
        self.ed = ed

    @property
    def session(self):
        return self.ed.session

    def actions(self) -> dict[Action, Callable[[], None]]:
        return {}

    def press_modal(self, e) -> DragMode | None:
        return None

    def press(self, e) -> DragMode | None:
        return None

    def drag(self, mode: DragMode, x: float, y: float, dx: float, dy: float, last: tuple) -> None:
        pass

    def release(self, mode: DragMode) -> None:
        pass

    @property
    def ctx(self) -> "ToolContext":
        """The narrow editor view of the tool protocol (:class:`ToolContext`)."""
        c = getattr(self, "_ctx", None)
        if c is None:
            c = self._ctx = ToolContext(self.ed)
        return c

    def intercept(self, action: Action) -> bool:
        """Offered every action before its handler runs (e.g. Esc while a
        box is armed cancels the box, not the pending moves); True: handled
        here, the bound handler does not run."""
        return False

    def status(self) -> str | None:
        """A short state line for the panel (an armed box, symmetric painting,
        a chosen pivot), or None when there is nothing to say."""
        return None

    def shapes(self, w: int, h: int) -> list:
        """Overlay shapes (:mod:`splatedit.app.tools.shapes`) drawn this frame."""
        return []

    def underlay(self, w: int, h: int) -> list:
        return []

    def overlay(self, w: int, h: int) -> list:
        return []

    def help_entries(self) -> list[Binding]:
        """The keymap rows documenting this tool (its help section)."""
        return [b for b in KEYMAP if b.section is self.section and b.help]


class ToolContext:
    """What a tool on the protocol may use of the editor: the document and
    its selection edit API, the view, the brush's settings, the status line.

    A tool keeps to these members (no ``ed.*`` reach-ins), so it is one file
    plus its keymap rows (and one line in the editor's tool list).
    """

    def __init__(self, ed):
        self._ed = ed

    # ---- document and selection
    @property
    def document(self):
        """The :class:`~splatedit.app.document.session.Session` (None: no model open)."""
        return self._ed.session

    @property
    def target(self) -> str:
        """The brush target: ``"support"`` or ``"handle"`` (the active one)."""
        return self._ed.session.brush_target

    def target_mask(self) -> np.ndarray:
        """(n,) bool: the brush target's current mask (not a copy)."""
        from splatedit.app.document.selection import target_mask
        s = self._ed.session
        return target_mask(s.selection, s.brush_target)

    def select(self, mask: np.ndarray, label: str) -> bool:
        """Make the brush target's mask ``mask`` with the brush rules, close
        the selection (:mod:`splatedit.select.closure`) and record it as one
        undo step; False when nothing changed."""
        s = self._ed.session
        return self._ed.brush.tools.apply(s, s.brush_target, mask, label)

    def neighbour_graph(self):
        """The document cloud's neighbour graph, or None while it is built."""
        return self._ed.brush.tools.graph(self._ed.session.cloud)

    def background_select(self):
        """A :class:`~splatedit.app.document.selection.BackgroundApply` of the
        brush target (the selection copied now, closed by its worker), or
        None while the neighbour graph is built."""
        return self._ed.brush.tools.background_apply(self._ed.session)

    def install(self, job, label: str) -> bool:
        """Make a finished BackgroundApply's selection the document's (one
        undo step); False when the selection changed since it started, or
        another model was opened meanwhile."""
        if job.session is not self._ed.session:
            return False
        return self._ed.brush.tools.install(job, label)

    # ---- background work
    def start_job(self, key: str, name: str, fn, land) -> None:
        """Run ``fn(progress)`` as an editor job (:mod:`splatedit.app.document.jobs`:
        a worker thread, a progress bar named ``name``, the window keeps
        drawing); when it is done, ``land(job)`` runs on the main thread
        (its ``result`` or ``error``)."""
        from splatedit.app.document.jobs import Job
        job = Job(name, fn, self._ed.wake)
        job.land = land        # set before the editor can collect it (it polls on this thread)
        self._ed.jobs[key] = job

    def job_running(self, key: str) -> bool:
        """A job started under ``key`` has not landed yet."""
        return key in self._ed.jobs

    # ---- view
    @property
    def camera(self):
        return self._ed.cam

    @property
    def size(self) -> tuple[int, int]:
        """(w, h) of the framebuffer, pixels."""
        return self._ed.size

    def visible(self):
        """The :class:`~splatedit.app.tools.pick_brush.BrushPicker` of the current view
        (which splat is visible at each pixel)."""
        return self._ed.brush.get_picker()

    @property
    def through(self) -> bool:
        """The brush mode (V): True for 3D / through, False for visible only."""
        from splatedit.app.document.selection import BRUSH_3D
        return self._ed.brush.mode == BRUSH_3D

    def erasing(self, mods: int | None = None) -> bool:
        """Ctrl held (in ``mods``, an input event's modifier bits; None: the
        keyboard now) or the erase toggle (E) on: a stroke erases."""
        if mods is None:
            return self._ed.brush.erasing()
        return self._ed.brush.erase_toggle or bool(mods & self._ed.g.MOD_CONTROL)

    def busy(self) -> bool:
        """A move is running or an edit is being applied (selections wait)."""
        s = self._ed.session
        return s is None or s.manip is not None or s.committing

    # ---- input
    @property
    def keys(self):
        """The input constants (glfw's ``MOUSE_BUTTON_*``, ``MOD_*``)."""
        return self._ed.g

    # ---- feedback
    def say(self, text: str) -> None:
        self._ed.say(text)

    def redraw(self) -> None:
        self._ed.motion()
