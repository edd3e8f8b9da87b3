"""The editor's menu bar (Dear ImGui): File (:attr:`MenuBar.file_menu`,
rows of :class:`MenuEntry`, with Open... and the Open recent submenu), Edit
(undo / redo), Select (all / none / invert, box / lasso, grow / shrink /
connected, mirror and the selection toggles), Pivot (the centre and axes of
R / S and the gizmo) and View (panels, help, frame all, the six views about the up axis).

An owned part of :class:`~splatedit.app.ui.gui_panels.EditorGui`
(``gui.menus``, a :class:`MenuBar`): it is given the editor and the GUI's
function that records a widget's rectangle, and reports its height and
whether a menu is open.  Esc closes an open menu
(:meth:`~splatedit.app.ui.gui_panels.EditorGui.feed`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from imgui_bundle import imgui

from splatedit.app.ui.keymap import Action
from splatedit.app.ui.panel import Box

#: View menu: the six views about the up axis (label, shortcut shown, action);
#: the shortcuts without a numpad are the keymap's Shift + 1 / 3 / 7 rows
_VIEW_ENTRIES = (
    ("Front", "Numpad 1 / Shift+1", Action.VIEW_FRONT),
    ("Right", "Numpad 3 / Shift+3", Action.VIEW_RIGHT),
    ("Top", "Numpad 7 / Shift+7", Action.VIEW_TOP),
    ("Back", "Ctrl+Numpad 1 / Ctrl+Shift+1", Action.VIEW_BACK),
    ("Left", "Ctrl+Numpad 3 / Ctrl+Shift+3", Action.VIEW_LEFT),
    ("Bottom", "Ctrl+Numpad 7 / Ctrl+Shift+7", Action.VIEW_BOTTOM),
)


#: Select menu: (label, shortcut shown, action); None: a separator.  The
#: shortcuts are the keymap's rows (a test checks they agree)
_SELECT_ENTRIES = (
    ("All", "A", Action.SELECT_ALL),
    ("None", "C", Action.CLEAR_SELECTION),
    ("Invert", "Ctrl+I", Action.INVERT),
    None,
    ("Box select", "Ctrl+B", Action.BOX_SELECT),
    ("Lasso select", "Ctrl+Shift+B", Action.LASSO_SELECT),
    None,
    ("Grow", "Ctrl+=", Action.GROW),
    ("Shrink", "Ctrl+-", Action.SHRINK),
    ("Connected (under the cursor)", "L", Action.CONNECTED),
    ("Connected, all of it", "Shift+L", Action.CONNECTED_ALL),
    None,
    ("Mirror", "Ctrl+M", Action.MIRROR_SELECTION),
    None,
    ("Delete selected splats", "Delete", Action.DELETE_SPLATS),
    ("Crop to the selection", "Shift+Delete", Action.CROP_SPLATS),
)


@dataclass
class MenuEntry:
    """One File-menu item: ``label``, the callback, a shortcut text shown at the
    right, and an optional predicate that enables it (default: always).  With
    ``submenu`` (a function giving its entries when it opens) the item is a
    submenu and ``action`` is unused; ``name`` records the item's rectangle
    (``gui_rects`` in the status file)."""
    label: str
    action: Callable[[], None] | None
    shortcut: str = ""
    enabled: Callable[[], bool] | None = None
    submenu: Callable[[], list] | None = None
    name: str = ""


class MenuBar:
    """The menu bar of the EditorGui: ``ed`` the editor, ``record(name)``
    records the last widget's rectangle under ``name`` (the GUI's
    ``gui_rects``)."""

    def __init__(self, ed, record: Callable[[str], None]):
        self.ed = ed
        self._rect = record
        #: the File menu, top to bottom (append / insert MenuEntry rows to extend it)
        has = lambda: ed.session is not None  # noqa: E731
        self.file_menu: list[MenuEntry] = [
            MenuEntry("Open...", lambda: ed.run_action(Action.OPEN), "Ctrl+O", name="menu_open"),
            MenuEntry("Open recent", None, submenu=self._recent_menu, name="menu_recent"),
            MenuEntry("Save", lambda: ed.run_action(Action.SAVE), "Ctrl+S", has),
            MenuEntry("Save as...", lambda: ed.run_action(Action.SAVE_AS), "Ctrl+Shift+S", has),
            MenuEntry("Export edit script", lambda: ed.run_action(Action.EXPORT_SCRIPT), "Ctrl+E", has),
            MenuEntry("Quit", lambda: ed.run_action(Action.QUIT), "Q")]
        #: the bar's height in pixels (last frame)
        self.height = 0.0
        #: a menu was open in the frame being laid out / the last frame
        self.open = False

    def draw(self, w: int) -> Box | None:
        """Lay out the bar (a ``w`` pixels wide window); returns its box
        (None when ImGui did not show it).  Resets :attr:`open` first."""
        ed = self.ed
        self.open = False
        if not imgui.begin_main_menu_bar():
            return None
        self.height = imgui.get_window_size().y
        box = Box(0, 0, w, int(self.height))
        if imgui.begin_menu("File"):
            self.open = True
            self._menu_entries(self.file_menu)
            imgui.end_menu()
        self._rect("menu_file")
        s = ed.session
        if imgui.begin_menu("Edit", s is not None):
            self.open = True
            if imgui.menu_item("Undo", "Ctrl+Z", False, s.history.can_undo or s.manip is not None)[0]:
                ed.run_action(Action.UNDO)
            if imgui.menu_item("Redo", "Ctrl+Shift+Z", False, s.history.can_redo)[0]:
                ed.run_action(Action.REDO)
            imgui.end_menu()
        self._rect("menu_edit")
        if imgui.begin_menu("Select", s is not None):
            self.open = True
            self._select_menu()
            imgui.end_menu()
        self._rect("menu_select")
        if imgui.begin_menu("Pivot", s is not None):
            self.open = True
            self._pivot_menu()
            imgui.end_menu()
        self._rect("menu_pivot")
        if imgui.begin_menu("View"):
            self.open = True
            if imgui.menu_item("Panels", "P", ed.panel_visible)[0]:
                ed.run_action(Action.PANEL)
            if imgui.menu_item("Help", "F1", ed.help.shown)[0]:
                ed.run_action(Action.HELP)
            if imgui.menu_item("Frame all", "Home", False, s is not None)[0]:
                ed.run_action(Action.FRAME_ALL)
            if imgui.menu_item("Eye-dome lighting", "Shift+E", bool(ed.viewport.edl),
                               s is not None and getattr(ed.viewport, "gaussians", None) is None)[0]:
                ed.run_action(Action.EDL)
            self._rect("view_edl")
            if imgui.menu_item("Two-sided splats", "T", bool(ed.viewport.two_sided),
                               s is not None and getattr(ed.viewport, "gaussians", None) is None)[0]:
                ed.run_action(Action.TWO_SIDED)
            self._rect("view_two_sided")
            imgui.separator()
            for label, shortcut, action in _VIEW_ENTRIES:
                if imgui.menu_item(label, shortcut, False, s is not None)[0]:
                    ed.run_action(action)
            imgui.end_menu()
        self._rect("menu_view")
        imgui.end_main_menu_bar()
        return box

    def _select_menu(self) -> None:
        """Select: all / none / invert, box / lasso, grow / shrink / connected,
        mirror, and the toggles (brush target, through / visible, erase,
        symmetric painting, mirror axis)."""
        from splatedit.app.document.selection import BRUSH_3D
        from splatedit.select.mirror import AXES
        from splatedit.select.selection import HANDLE, SUPPORT
        ed = self.ed
        s = ed.session
        for e in _SELECT_ENTRIES:
            if e is None:
                imgui.separator()
            else:
                if imgui.menu_item(e[0], e[1], False)[0]:
                    ed.run_action(e[2])
                self._rect(f"select_{e[2].value}")
        imgui.separator()
        if imgui.menu_item("Symmetric painting", "Shift+M", ed.mirror.painting)[0]:
            ed.run_action(Action.MIRROR_PAINT)
        if imgui.menu_item(f"Mirror plane: {AXES[ed.mirror.axis]}", "Ctrl+Shift+M", False)[0]:
            ed.run_action(Action.MIRROR_AXIS)
        imgui.separator()
        if imgui.menu_item("Target: support", "1", s.brush_target == SUPPORT)[0]:
            ed.run_action(Action.BRUSH_SUPPORT)
        if imgui.menu_item("Target: active handle", "2", s.brush_target == HANDLE)[0]:
            ed.run_action(Action.BRUSH_HANDLE)
        if imgui.menu_item("Through (3D brush, box, lasso)", "V", ed.brush.mode == BRUSH_3D)[0]:
            ed.run_action(Action.BRUSH_MODE)
        if imgui.menu_item("Erase mode", "E", ed.brush.erase_toggle)[0]:
            ed.run_action(Action.ERASE_TOGGLE)

    def _pivot_menu(self) -> None:
        """Pivot: the centre of R / S and the gizmo, and the axes of X / Y / Z."""
        from splatedit.app.tools.pivot import FRAMES, PIVOTS
        ed = self.ed
        pv = ed.pivot
        acts = (Action.PIVOT_HANDLE, Action.PIVOT_RIM, Action.PIVOT_CURSOR, Action.PIVOT_VIEW)
        for label, a in zip(PIVOTS, acts):
            if imgui.menu_item(label.capitalize(), ".", pv.mode == label)[0]:
                ed.run_action(a)
            self._rect(f"pivot_{a.value}")
        if imgui.menu_item("3D cursor to the view centre", "Shift+right click: on the model", False)[0]:
            ed.run_action(Action.CURSOR_TO_VIEW_CENTRE)
        imgui.separator()
        for label, a in zip(FRAMES, (Action.AXES_GLOBAL, Action.AXES_LOCAL, Action.AXES_VIEW)):
            if imgui.menu_item(f"Axes: {label}", ",", pv.orientation == label)[0]:
                ed.run_action(a)
            self._rect(f"pivot_{a.value}")

    def _menu_entries(self, entries: list[MenuEntry]) -> None:
        for e in entries:
            ok = e.enabled() if e.enabled is not None else True
            if e.submenu is not None:
                opened = imgui.begin_menu(e.label, ok)
                if opened:
                    self._menu_entries(e.submenu())
                    imgui.end_menu()
                if e.name:
                    self._rect(e.name)
                continue
            if imgui.menu_item(e.label, e.shortcut, False, ok)[0]:
                e.action()
            if e.name:
                self._rect(e.name)

    def _recent_menu(self) -> list[MenuEntry]:
        """File > Open recent: the recent models (opened like Ctrl+O's pick, the
        unsaved-changes question included), then "Clear recent files"."""
        from splatedit.app.ui.recent import menu_labels
        ed = self.ed
        paths = ed.file_actions.recent_files()
        if not paths:
            return [MenuEntry("(no recent files)", lambda: None, enabled=lambda: False, name="recent_none")]
        rows = [MenuEntry(label, lambda p=p: ed.file_actions.open_path(p), name=f"recent_{i}")
                for i, (label, p) in enumerate(zip(menu_labels(paths), paths))]
        return rows + [MenuEntry("Clear recent files", ed.file_actions.clear_recent, name="recent_clear")]
