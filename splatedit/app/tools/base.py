"""What every editor tool is: :class:`Tool`, and the :class:`DragMode` of a
mouse drag in progress."""

from __future__ import annotations

import enum
from typing import Callable

import numpy as np

from splatedit.app.ui.keymap import KEYMAP, Action, Binding, Section
from splatedit.tolerances import EDITOR_FRAME_MIN_FREE_FRACTION


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


def free_area(w: int, h: int, panel_box, top: float = 0.0) -> tuple[float, float, float, float]:
    """(x0, y0, x1, y1) fractions of a ``w`` x ``h`` pixel window (y down)
    that no GUI covers: below a menu bar ``top`` pixels high and beside the
    side panel's column (``panel_box`` (x, y, w, h) pixels or None): the
    panel grows downwards as its sections open, so its whole column counts,
    like Blender's side regions.  The whole window when what is left would be
    narrower than ``EDITOR_FRAME_MIN_FREE_FRACTION`` of it."""
    w, h = max(int(w), 1), max(int(h), 1)
    x0, x1, y0 = 0.0, float(w), min(max(float(top), 0.0), float(h))
    if panel_box is not None:
        px, _, pw, _ = panel_box
        if w - (px + pw) >= px:         # more room right of the panel
            x0 = float(px + pw)
        else:
            x1 = float(px)
    if x1 - x0 < EDITOR_FRAME_MIN_FREE_FRACTION * w:
        x0, x1 = 0.0, float(w)
    if h - y0 < EDITOR_FRAME_MIN_FREE_FRACTION * h:
        y0 = 0.0
    return x0 / w, y0 / h, x1 / w, 1.0


class Tool:
    """An editor tool, on the tool protocol: it sees the editor only through
    its :attr:`ctx` (:class:`ToolContext`: the document and its selection
    edit API, the view, the pointer, the status line).

    Mouse: the editor offers a button press to every tool's
    :meth:`press_modal` first, then to :meth:`press` in its tool order; the
    first to return a :class:`DragMode` owns the drag (:meth:`drag` on each
    move, :meth:`release` at the end).  Keys: :meth:`actions` maps keymap
    :class:`~splatedit.app.ui.keymap.Action` values to handlers.  Drawing:
    :meth:`shapes` returns backend-neutral shapes
    (:mod:`splatedit.app.tools.shapes`) that one painter draws on the GPU path and
    on the CPU fallback alike.
    """
    #: the help section of this tool's keymap rows
    section: Section | None = None

    def __init__(self, ed):
        #: the narrow editor view of the tool protocol (:class:`ToolContext`)
        self.ctx = ToolContext(ed)

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
        """Overlay shapes (:mod:`splatedit.app.tools.shapes`) drawn this frame in a
        ``w`` x ``h`` pixel window."""
        return []

    def help_entries(self) -> list[Binding]:
        """The keymap rows documenting this tool (its help section)."""
        return [b for b in KEYMAP if b.section is self.section and b.help]


class ToolContext:
    """What a tool may use of the editor: the document and its selection
    edit API, the view (camera, size, what is visible where), the pointer,
    the other tools by name, the status line.

    A tool keeps to these members (no ``ed.*`` reach-ins), so it is one file
    plus its keymap rows.
    """

    def __init__(self, ed):
        self._ed = ed

    # ---- document and selection
    @property
    def document(self):
        """The :class:`~splatedit.app.document.session.Session` (None: no model open)."""
        return self._ed.session

    @property
    def items(self) -> str:
        """What the document's elements are called in messages: ``"Gaussians"``
        for a Gaussian splatting scene, else ``"splats"`` (as the panel says)."""
        from splatedit.app.document.gaussian import gaussians_of
        s = self._ed.session
        return "Gaussians" if s is not None and gaussians_of(s.cloud) is not None else "splats"

    @property
    def selection_edit(self):
        """The document's selection edit API
        (:class:`~splatedit.app.document.selection_edit.SelectionEdit`)."""
        return self._ed.session.selection_edit

    @property
    def target(self) -> str:
        """The brush target: ``"support"`` or ``"handle"`` (the active one)."""
        return self._ed.session.brush_target

    def target_mask(self) -> np.ndarray:
        """(n,) bool: the brush target's current mask (not a copy)."""
        return self._ed.session.selection_edit.target_mask()

    def select(self, mask: np.ndarray, label: str) -> bool:
        """Make the brush target's mask ``mask`` with the brush rules, close
        the selection (:mod:`splatedit.select.closure`) and record it as one
        undo step; False when nothing changed."""
        return self._ed.session.selection_edit.select(mask, label)

    @property
    def graphs(self):
        """The neighbour graphs and closure bookkeeping
        (:class:`~splatedit.app.document.selection.SelectionTools`: the 3D /
        visible brush mode, the last closure's highlight)."""
        return self._ed.selection_tools

    def neighbour_graph(self):
        """The document cloud's neighbour graph, or None while it is built."""
        return self._ed.selection_tools.graph(self._ed.session.cloud)

    def background_select(self):
        """A :class:`~splatedit.app.document.selection.BackgroundApply` of the
        brush target (the selection copied now, closed by its worker), or
        None while the neighbour graph is built."""
        return self._ed.session.selection_edit.background_select()

    def install(self, job, label: str) -> bool:
        """Make a finished BackgroundApply's selection the document's (one
        undo step); False when the selection changed since it started, or
        another model was opened meanwhile."""
        return self._ed.session.selection_edit.install(job, label)

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
        """The :class:`~splatedit.app.view.camera_control.OrbitCamera`."""
        return self._ed.cam

    @property
    def size(self) -> tuple[int, int]:
        """(w, h) of the framebuffer, pixels."""
        return self._ed.size

    def visible(self):
        """The :class:`~splatedit.app.tools.pick_brush.BrushPicker` of the current view
        (which splat is visible at each pixel)."""
        return self._ed.picking.get()

    def splat_under(self, x: float, y: float) -> int:
        """The splat visible at pixel (x, y), or -1."""
        return self._ed.picking.splat_under(x, y)

    def pick_ready(self) -> bool:
        """The current view's pick map is at hand (using it costs nothing)."""
        return self._ed.picking.current()

    def displaced(self) -> bool:
        """The view draws a displacement (a move in progress or pending)."""
        return self._ed.picking.displaced()

    @property
    def viewport(self):
        """The view's display settings and drawn state, read only
        (:class:`~splatedit.app.view.viewport.Viewport`: ``cloud`` drawn,
        ``splat_scale``, ``two_sided``, ``gaussians``)."""
        return self._ed.viewport

    def view_area(self) -> tuple[float, float, float, float]:
        """The part of the window no GUI covers, (x0, y0, x1, y1) fractions
        (y down; :func:`free_area`): beside the side panel when it is shown,
        below the GUI's menu bar (:meth:`Editor.view_area`)."""
        return self._ed.view_area()

    # ---- brush settings
    @property
    def through(self) -> bool:
        """The brush mode (V): True for 3D / through, False for visible only."""
        from splatedit.app.document.selection import BRUSH_3D
        return self._ed.selection_tools.mode == BRUSH_3D

    def erasing(self, mods: int | None = None) -> bool:
        """Ctrl held (in ``mods``, an input event's modifier bits; None: the
        keyboard now) or the erase toggle (E) on: a stroke erases."""
        if mods is None:
            mods = self._ed.window.mods()
        return self._ed.brush.erase_toggle or bool(mods & self._ed.g.MOD_CONTROL)

    def busy(self) -> bool:
        """A move is running or an edit is being applied (selections wait)."""
        s = self._ed.session
        return s is None or s.manip is not None or s.committing

    # ---- pointer and input
    @property
    def keys(self):
        """The input constants (glfw's ``MOUSE_BUTTON_*``, ``MOD_*``, ``KEY_*``)."""
        return self._ed.g

    @property
    def mouse(self) -> tuple[float, float]:
        """The pointer's last position, pixels."""
        return self._ed.mouse

    def pointer_free(self) -> bool:
        """The pointer is over the model and may show a tool cursor: inside
        the window, no camera drag, no question open, not over a GUI window."""
        ed = self._ed
        if ed.drag.camera or ed.modal() or not ed.cursor_inside:
            return False
        return not (ed.gui is not None and ed.gui.wants_mouse)

    def dragging(self) -> bool:
        """A mouse drag is in progress (any tool's)."""
        return self._ed.drag is not DragMode.NONE

    def end_drag(self) -> None:
        """The drag in progress ends here (its release goes nowhere)."""
        self._ed.drag = DragMode.NONE

    def tool(self, name: str) -> "Tool":
        """Another tool by its editor name (``"brush"``, ``"gizmo"``,
        ``"pivot"``, ``"mirror"`` ...)."""
        return getattr(self._ed, name)

    # ---- feedback
    def say(self, text: str) -> None:
        """A message on the status line."""
        self._ed.say(text)

    @property
    def message(self) -> str:
        """The status line's current message."""
        return self._ed.message

    def show_error(self, text: str) -> None:
        """An error box (until dismissed)."""
        self._ed.show_error(text)

    def debug(self, text: str) -> None:
        """A debug line on stderr (SPLATEDIT_EDITOR_DEBUG=1)."""
        self._ed.debug(text)

    def redraw(self) -> None:
        """The view changed: draw the next frame (and keep drawing while it moves)."""
        self._ed.motion()
