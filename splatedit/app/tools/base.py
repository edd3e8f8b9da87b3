"""What every editor tool is: :class:`Tool`, and the :class:`DragMode` of a
mouse drag in progress."""

from __future__ import annotations

import enum
from typing import Callable

from splatedit.app.keymap import KEYMAP, Action, Binding, Section


class DragMode(enum.Enum):
    """What a held mouse button is doing."""
    NONE = "none"
    ORBIT = "orbit"
    PAN = "pan"
    DOLLY = "dolly"
    PAINT = "paint"
    MANIP = "manip"     # a handle or curve point follows the mouse

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
    :class:`~splatedit.app.keymap.Action` values to handlers.  Drawing:
    :meth:`underlay` and :meth:`overlay` return overlay patches.
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

    def underlay(self, w: int, h: int) -> list:
        return []

    def overlay(self, w: int, h: int) -> list:
        return []

    def help_entries(self) -> list[Binding]:
        """The keymap rows documenting this tool (its help section)."""
        return [b for b in KEYMAP if b.section is self.section and b.help]
