"""The editor's one declarative keymap.

Every key and mouse binding of ``splatedit edit`` is a :class:`Binding` row of
:data:`KEYMAP`: its chords (keys + modifiers), the :class:`Action` it runs,
the :class:`Context` it applies in, the help :class:`Section` and the help
text.  From this one table come

* the key dispatch (:func:`lookup`: glfw key + modifiers + context -> action),
* the F1 help window and ``splatedit edit --help`` (:func:`help_lines`),
* the editor manual's controls list (docs/editor.md) (:func:`readme_block`; ``python -m
  splatedit.app.ui.keymap --write-readme`` rewrites it, and a test fails when
  the manual is out of sync with the table).

Mouse gestures are rows with ``mouse=True``: the tools handle them (they
depend on what is under the cursor), the table documents them.  This module
imports no glfw at import time (``splatedit edit --help`` stays light);
key names are resolved on first use.
"""

from __future__ import annotations

import enum
import re
import sys
from dataclasses import dataclass
from pathlib import Path


class Section(enum.Enum):
    """Help sections, in the order they are shown."""
    CAMERA = "Camera"
    SELECTION = "Selection (paper Sect. 3: support = blue, handles = green, the active one brighter)"
    DEFORMATION = ("Deformation (the basis of all handles and the curve is fitted in the background;\n"
                   "             at most 16 columns: 4 per handle + 1 per curve point)")
    CURVE = "Control curve (paper Sect. 3 end, Fig. 3 and 7)"
    DISPLAY = "Display"
    FILE = "File and history"
    BROWSER = "File browser (Ctrl+O; recent files first, then the folder's models)"


class Context(enum.Enum):
    """When a binding applies."""
    ANY = "any"          # with or without a model, idle or manipulating
    IDLE = "idle"        # a model is open and nothing is being moved
    MANIP = "manip"      # during a G/R/S move (or a curve point drag)
    HELP = "help"        # while the help window is shown (before the others)
    BROWSER = "browser"  # while the file browser is shown (only these keys)
    ERROR = "error"      # while an error box is shown (before the others)


class Action(enum.Enum):
    NONE = "none"                    # documentation-only row (mouse gestures)
    # camera
    FRAME_ALL = "frame_all"
    FRAME_SELECTION = "frame_selection"
    VIEW_FRONT = "view_front"
    VIEW_RIGHT = "view_right"
    VIEW_TOP = "view_top"
    VIEW_BACK = "view_back"
    VIEW_LEFT = "view_left"
    VIEW_BOTTOM = "view_bottom"
    CYCLE_UP_AXIS = "cycle_up_axis"
    # selection
    BRUSH_MODE = "brush_mode"
    ERASE_TOGGLE = "erase_toggle"
    BRUSH_SUPPORT = "brush_support"
    BRUSH_HANDLE = "brush_handle"
    NEXT_HANDLE = "next_handle"
    PREV_HANDLE = "prev_handle"
    NEW_HANDLE = "new_handle"
    REMOVE_HANDLE = "remove_handle"
    BRUSH_SMALLER = "brush_smaller"
    BRUSH_LARGER = "brush_larger"
    CLEAR_SELECTION = "clear_selection"
    CLEAR_HANDLES = "clear_handles"
    GROW = "grow"
    SHRINK = "shrink"
    CONNECTED = "connected"
    CONNECTED_ALL = "connected_all"
    INVERT = "invert"
    SELECT_ALL = "select_all"
    BOX_SELECT = "box_select"
    LASSO_SELECT = "lasso_select"
    MIRROR_SELECTION = "mirror_selection"
    MIRROR_PAINT = "mirror_paint"
    MIRROR_AXIS = "mirror_axis"
    DELETE_SPLATS = "delete_splats"
    CROP_SPLATS = "crop_splats"
    # deformation
    GRAB = "grab"
    ROTATE = "rotate"
    SCALE = "scale"
    AXIS_X = "axis_x"
    AXIS_Y = "axis_y"
    AXIS_Z = "axis_z"
    TYPE_VALUE = "type_value"
    TYPE_BACKSPACE = "type_backspace"
    MANIP_DONE = "manip_done"
    MANIP_CANCEL = "manip_cancel"
    COMMIT_POSE = "commit_pose"
    CANCEL = "cancel"                # Esc when idle: discard pending moves / curve tool off
    DEFORMATION_MODE = "deformation_mode"
    PIVOT_NEXT = "pivot_next"
    PIVOT_HANDLE = "pivot_handle"
    PIVOT_RIM = "pivot_rim"
    PIVOT_CURSOR = "pivot_cursor"
    PIVOT_VIEW = "pivot_view"
    AXES_NEXT = "axes_next"
    AXES_GLOBAL = "axes_global"
    AXES_LOCAL = "axes_local"
    AXES_VIEW = "axes_view"
    CURSOR_TO_VIEW_CENTRE = "cursor_to_view_centre"
    # curve
    CURVE_TOOL = "curve_tool"
    CLEAR_CURVE = "clear_curve"
    REMOVE_CURVE_POINT = "remove_curve_point"
    # display
    DISTORTION_MAP = "distortion_map"
    COLOUR_MODE = "colour_mode"
    SPLATS_SMALLER = "splats_smaller"
    SPLATS_LARGER = "splats_larger"
    EDL = "edl"
    TWO_SIDED = "two_sided"
    PANEL = "panel"
    HELP = "help"
    HELP_DOWN = "help_down"
    HELP_UP = "help_up"
    HELP_CLOSE = "help_close"
    # file and history
    UNDO = "undo"
    REDO = "redo"
    SAVE = "save"
    SAVE_AS = "save_as"
    EXPORT_SCRIPT = "export_script"
    OPEN = "open"
    DISMISS_ERROR = "dismiss_error"
    QUIT = "quit"
    # file browser
    BROWSE_UP = "browse_up"
    BROWSE_DOWN = "browse_down"
    BROWSE_PAGE_UP = "browse_page_up"
    BROWSE_PAGE_DOWN = "browse_page_down"
    BROWSE_FIRST = "browse_first"
    BROWSE_LAST = "browse_last"
    BROWSE_PICK = "browse_pick"
    BROWSE_PARENT = "browse_parent"
    BROWSE_CANCEL = "browse_cancel"


#: modifier names of a chord ("ctrl+shift+z")
_MODS = ("ctrl", "shift", "alt")


@dataclass(frozen=True)
class Chord:
    """A key with the exact Ctrl/Shift state it needs (Alt is ignored for
    keys).  ``key`` is a glfw key name without ``KEY_`` (``"KP_1"``)."""
    key: str
    ctrl: bool = False
    shift: bool = False

    @classmethod
    def parse(cls, spec: str) -> "Chord":
        parts = spec.lower().split("+")
        mods, key = parts[:-1], parts[-1]
        bad = [m for m in mods if m not in _MODS]
        if bad or not key:
            raise ValueError(f"bad chord {spec!r}")
        return cls(key.upper(), "ctrl" in mods, "shift" in mods)

    def glfw_key(self) -> int:
        import glfw
        return getattr(glfw, "KEY_" + self.key)


@dataclass(frozen=True)
class Binding:
    """One row of the keymap.

    ``label``: the left column of the help (how a user names the input);
    ``keys``: chord specs this row dispatches (empty for mouse rows and
    documentation lines); ``help``: the right column (``\\n`` starts an
    indented continuation line)."""
    section: Section
    label: str
    help: str
    action: Action = Action.NONE
    keys: tuple[str, ...] = ()
    context: Context = Context.IDLE
    mouse: bool = False
    indent: int = 0

    @property
    def chords(self) -> tuple[Chord, ...]:
        return tuple(Chord.parse(k) for k in self.keys)


def _digits(prefix: str = "") -> tuple[str, ...]:
    return tuple(f"{prefix}{d}" for d in range(10))


S, C = Section, Context
KEYMAP: tuple[Binding, ...] = (
    # ---- camera
    Binding(S.CAMERA, "Middle drag", "orbit around the pivot          (laptop: Alt + left drag)", mouse=True,
            context=C.ANY),
    Binding(S.CAMERA, "Shift + middle drag", "pan                             (laptop: Alt + Shift + left drag)",
            mouse=True, context=C.ANY),
    Binding(S.CAMERA, "Ctrl + middle drag", "dolly", mouse=True, context=C.ANY),
    Binding(S.CAMERA, "Wheel", "zoom to the cursor", mouse=True, context=C.ANY),
    Binding(S.CAMERA, "Home", "frame the model, far outliers left out (beside the side panel)", Action.FRAME_ALL, ("home",)),
    Binding(S.CAMERA, "F  or  numpad .", "frame the selection (handle, else support)", Action.FRAME_SELECTION,
            ("f", "kp_decimal")),
    Binding(S.CAMERA, "Numpad 1 / 3 / 7", "front / right / top view (Ctrl: back / left / bottom), about the up axis",
            Action.VIEW_FRONT, ("kp_1",)),
    Binding(S.CAMERA, "", "", Action.VIEW_RIGHT, ("kp_3",)),
    Binding(S.CAMERA, "", "", Action.VIEW_TOP, ("kp_7",)),
    Binding(S.CAMERA, "", "", Action.VIEW_BACK, ("ctrl+kp_1",)),
    Binding(S.CAMERA, "", "", Action.VIEW_LEFT, ("ctrl+kp_3",)),
    Binding(S.CAMERA, "", "", Action.VIEW_BOTTOM, ("ctrl+kp_7",)),
    Binding(S.CAMERA, "Shift + 1 / 3 / 7", "the same views without a numpad (Ctrl+Shift: back / left / bottom;\n"
            "also in the View menu)", Action.VIEW_FRONT, ("shift+1",)),
    Binding(S.CAMERA, "", "", Action.VIEW_RIGHT, ("shift+3",)),
    Binding(S.CAMERA, "", "", Action.VIEW_TOP, ("shift+7",)),
    Binding(S.CAMERA, "", "", Action.VIEW_BACK, ("ctrl+shift+1",)),
    Binding(S.CAMERA, "", "", Action.VIEW_LEFT, ("ctrl+shift+3",)),
    Binding(S.CAMERA, "", "", Action.VIEW_BOTTOM, ("ctrl+shift+7",)),
    Binding(S.CAMERA, "U", "up axis: detected from the model; U cycles +Y, +Z, +X, -Y, -Z, -X (panel shows it)",
            Action.CYCLE_UP_AXIS, ("u",)),
    # ---- selection
    Binding(S.SELECTION, "Left drag", "paint with the brush: 3D, every splat in the sphere under the circle",
            mouse=True),
    Binding(S.SELECTION, "V", "brush mode: 3D (front and back) / visible splats only", Action.BRUSH_MODE, ("v",)),
    Binding(S.SELECTION, "Ctrl + left drag", "erase with the brush            (E toggles erase mode)",
            mouse=True),
    Binding(S.SELECTION, "", "", Action.ERASE_TOGGLE, ("e",)),
    Binding(S.SELECTION, "1 / 2", "brush paints the support / the active handle (inside the support)",
            Action.BRUSH_SUPPORT, ("1",)),
    Binding(S.SELECTION, "", "", Action.BRUSH_HANDLE, ("2",)),
    Binding(S.SELECTION, "Tab", "one handle: toggle support / handle brush; several: next handle (Shift: previous)",
            Action.NEXT_HANDLE, ("tab",)),
    Binding(S.SELECTION, "", "", Action.PREV_HANDLE, ("shift+tab",)),
    Binding(S.SELECTION, "N", "new handle (becomes active; paint it with the handle brush)", Action.NEW_HANDLE,
            ("n",)),
    Binding(S.SELECTION, "Shift+N", "remove the active handle", Action.REMOVE_HANDLE, ("shift+n",)),
    Binding(S.SELECTION, "[ / ]  or  Ctrl+wheel", "brush radius", Action.BRUSH_SMALLER, ("left_bracket",)),
    Binding(S.SELECTION, "", "", Action.BRUSH_LARGER, ("right_bracket",)),
    Binding(S.SELECTION, "C / Shift+C", "clear the selection / clear the handles", Action.CLEAR_SELECTION, ("c",)),
    Binding(S.SELECTION, "", "", Action.CLEAR_HANDLES, ("shift+c",)),
    Binding(S.SELECTION, "Ctrl + =  /  Ctrl + -", "grow / shrink the brush target by one ring (numpad + / - too)",
            Action.GROW, ("ctrl+equal", "ctrl+kp_add")),
    Binding(S.SELECTION, "", "", Action.SHRINK, ("ctrl+minus", "ctrl+kp_subtract")),
    Binding(S.SELECTION, "L / Shift+L", "add the connected part under the cursor within the brush / all of it",
            Action.CONNECTED, ("l",)),
    Binding(S.SELECTION, "", "", Action.CONNECTED_ALL, ("shift+l",)),
    Binding(S.SELECTION, "Ctrl + I", "invert the brush target (support: handles cleared; handle: within the support)",
            Action.INVERT, ("ctrl+i",)),
    Binding(S.SELECTION, "A", "select all: the whole model as support (handle brush: the free support)",
            Action.SELECT_ALL, ("a",)),
    Binding(S.SELECTION, "Ctrl+B / Ctrl+Shift+B", "box / lasso select: the next left drag draws it; the splats inside\n"
            "join the brush target (Ctrl held: erased); V decides: 3D = every centre inside\n"
            "(through), visible = only what is seen; Esc, right click or the key again: cancel",
            Action.BOX_SELECT, ("ctrl+b",)),
    Binding(S.SELECTION, "", "", Action.LASSO_SELECT, ("ctrl+shift+b",)),
    Binding(S.SELECTION, "Ctrl+M", "mirror: add the brush target's mirror image across the model's middle plane",
            Action.MIRROR_SELECTION, ("ctrl+m",)),
    Binding(S.SELECTION, "Shift+M", "symmetric painting on / off (each dab also paints its mirror image)",
            Action.MIRROR_PAINT, ("shift+m",)),
    Binding(S.SELECTION, "Ctrl+Shift+M", "mirror plane: X / Y / Z (through the middle of the bounding box)",
            Action.MIRROR_AXIS, ("ctrl+shift+m",)),
    Binding(S.SELECTION, "Delete / Shift+Delete", "delete the support splats from the model / crop: keep only them\n"
            "(one undo step; the edit script records it, saves replay)", Action.DELETE_SPLATS, ("delete",)),
    Binding(S.SELECTION, "", "", Action.CROP_SPLATS, ("shift+delete",)),
    Binding(S.SELECTION, "", "The Select menu has all of these.\nAfter each stroke or tool the selection is closed (holes, back sides); "
            "additions flash yellow"),
    # ---- deformation
    Binding(S.DEFORMATION, "Left drag on a handle", "make it active and move it in the view plane", mouse=True),
    Binding(S.DEFORMATION, "Left drag on an arrow",
            "move the active handle along that axis (gizmo: X red, Y green, Z blue)", mouse=True),
    Binding(S.DEFORMATION, "Left drag on a ring", "rotate the active handle about that axis, through its centre",
            mouse=True),
    Binding(S.DEFORMATION, "Left drag outer circle", "scale the active handle about its centre (outward: larger)",
            mouse=True),
    Binding(S.DEFORMATION, "B", "deformation of new edits: ROTATION (default: the handles' rotations are blended,\n"
            "bends and twists keep their thickness) / DETAIL (as ROTATION on a smoothed base\n"
            "surface, the relief re-attached along its normals; refits) / LINEAR (the paper's);\n"
            "a Gaussian scene: ROTATION / LINEAR (no DETAIL: B says so)",
            Action.DEFORMATION_MODE, ("b",)),
    Binding(S.DEFORMATION, ".  (period)", "pivot of R / S and the gizmo: handle centre / support rim (where the support\n"
            "meets the fixed part) / 3D cursor / view centre (also the Pivot menu)", Action.PIVOT_NEXT,
            ("period",)),
    Binding(S.DEFORMATION, ",  (comma)", "axes of the gizmo and X / Y / Z: global / local (the handle's principal axes) / view",
            Action.AXES_NEXT, ("comma",)),
    Binding(S.DEFORMATION, "Shift + right click", "place the 3D cursor on the model", mouse=True),
    Binding(S.DEFORMATION, "G / R / S", "grab / rotate / scale the active handle with the mouse\n"
            "(the overlay shows the distance / angle / factor while moving)", Action.GRAB, ("g",)),
    Binding(S.DEFORMATION, "", "", Action.ROTATE, ("r",)),
    Binding(S.DEFORMATION, "", "", Action.SCALE, ("s",)),
    Binding(S.DEFORMATION, "G / R / S", "", Action.GRAB, ("g",), C.MANIP),
    Binding(S.DEFORMATION, "", "", Action.ROTATE, ("r",), C.MANIP),
    Binding(S.DEFORMATION, "", "", Action.SCALE, ("s",), C.MANIP),
    Binding(S.DEFORMATION, "X / Y / Z", "constrain to that axis of the chosen axes (again: free)", Action.AXIS_X,
            ("x",), C.MANIP, indent=2),
    Binding(S.DEFORMATION, "", "", Action.AXIS_Y, ("y",), C.MANIP),
    Binding(S.DEFORMATION, "", "", Action.AXIS_Z, ("z",), C.MANIP),
    Binding(S.DEFORMATION, "0-9 . -", "type a value: distance, degrees or factor (G X 0.1 Enter)",
            Action.TYPE_VALUE, _digits() + _digits("kp_") + ("period", "kp_decimal", "comma", "minus",
                                                               "kp_subtract"), C.MANIP, indent=2),
    Binding(S.DEFORMATION, "Backspace", "delete the last typed character", Action.TYPE_BACKSPACE, ("backspace",),
            C.MANIP, indent=2),
    Binding(S.DEFORMATION, "Enter or left click", "done (one handle, no curve: the edit is applied at once)",
            Action.MANIP_DONE, ("enter", "kp_enter"), C.MANIP, indent=2),
    Binding(S.DEFORMATION, "Esc or right click", "cancel this move", Action.MANIP_CANCEL, ("escape",), C.MANIP,
            indent=2),
    Binding(S.DEFORMATION, "", "With several handles or a curve the moves are kept (the other handles keep theirs):"),
    Binding(S.DEFORMATION, "Enter", "apply all of them as one edit (the result becomes the new base)",
            Action.COMMIT_POSE, ("enter", "kp_enter"), indent=2),
    Binding(S.DEFORMATION, "Esc", "discard the pending moves (else: curve tool off)", Action.CANCEL,
            ("escape",), indent=2),
    # ---- curve
    Binding(S.CURVE, "K", "curve tool on / off (Shift+K: clear the curve)", Action.CURVE_TOOL, ("k",)),
    Binding(S.CURVE, "", "", Action.CLEAR_CURVE, ("shift+k",)),
    Binding(S.CURVE, "Left click on support", "add a curve point (2..16); the curve through them is drawn as it "
            "will act", mouse=True),
    Binding(S.CURVE, "Left drag on a dot", "move that point in the view plane (X / Y / Z: along an axis); in the\n"
            "rotation mode (default) the part bends along the curve, its cross-sections turning with\n"
            "the curve's frame; in the linear mode (B) the paper's curve edit", mouse=True),
    Binding(S.CURVE, "Backspace", "remove the last curve point", Action.REMOVE_CURVE_POINT, ("backspace",)),
    Binding(S.CURVE, "Enter / Esc", "apply the bent curve as an edit (the curve is consumed) / discard moves"),
    # ---- display
    Binding(S.DISPLAY, "D", "distortion heat map on / off: the support coloured by stretch (1x grey .. 3x red)\n"
            "(the panel shows \"stretch max N.Nx, K > 3x\" while a pose is moved, then of the last\n"
            "committed edit until the next change)", Action.DISTORTION_MAP,
            ("d",)),
    Binding(S.DISPLAY, "", "", Action.DISTORTION_MAP, ("d",), C.MANIP),
    Binding(S.DISPLAY, "M", "colours: the file's colours / uniform grey shading (for dark or colourless scans)",
            Action.COLOUR_MODE, ("m",)),
    Binding(S.DISPLAY, "Shift+[ / Shift+]", "splat size: smaller / larger (x0.8 / x1.25, 0.25x .. 4x)",
            Action.SPLATS_SMALLER, ("shift+left_bracket",)),
    Binding(S.DISPLAY, "", "", Action.SPLATS_LARGER, ("shift+right_bracket",)),
    Binding(S.DISPLAY, "Shift+E", "eye-dome lighting on / off: depth edges and creases darkened (reads raw\n"
            "scans without normals; also in the View menu)", Action.EDL, ("shift+e",)),
    Binding(S.DISPLAY, "T", "two-sided splats on / off: draw the splats seen from behind too (a raw scan's\n"
            "estimated normals facing away: a post or a wall from above; also in the View menu)",
            Action.TWO_SIDED, ("t",)),
    Binding(S.DISPLAY, "P", "hide / show the panel", Action.PANEL, ("p",), C.ANY),
    Binding(S.DISPLAY, "F1  or  H", "show / hide this help (PageDown / PageUp, arrows or the wheel scroll it)",
            Action.HELP, ("f1", "h"), C.ANY),
    Binding(S.DISPLAY, "", "", Action.HELP_DOWN, ("page_down", "down", "space"), C.HELP),
    Binding(S.DISPLAY, "", "", Action.HELP_UP, ("page_up", "up"), C.HELP),
    Binding(S.DISPLAY, "", "", Action.HELP_CLOSE, ("escape",), C.HELP),
    # ---- file and history
    Binding(S.FILE, "Ctrl+Z / Ctrl+Shift+Z", "undo / redo (edits and selections; Ctrl+Y also redoes)", Action.UNDO,
            ("ctrl+z",)),
    Binding(S.FILE, "", "", Action.REDO, ("ctrl+shift+z", "ctrl+y")),
    Binding(S.FILE, "Ctrl+S", "save <name>-edited.ply (+ <name>-edited.edits.json edit script); without an edit,\n"
            "or with nothing new since the last save, it says so and writes nothing", Action.SAVE,
            ("ctrl+s",)),
    Binding(S.FILE, "Ctrl+Shift+S", "save as: edit the proposed path (Backspace deletes a character;\n"
            "Ctrl+A selects all, Ctrl+U or Ctrl+Backspace clears), Enter saves, Esc cancels", Action.SAVE_AS, ("ctrl+shift+s",)),
    Binding(S.FILE, "Ctrl+E", "export only the edit script", Action.EXPORT_SCRIPT, ("ctrl+e",)),
    Binding(S.FILE, "Ctrl+O", "open another model in this window: the file browser (below); asks first when\n"
            "there are unsaved changes (Y opens without saving, N or Esc stays)", Action.OPEN, ("ctrl+o",), C.ANY),
    Binding(S.FILE, "Drop a file", "on the window: open it the same way (a dropped folder: browse it)", mouse=True,
            context=C.ANY),
    Binding(S.FILE, "Esc or Enter", "close an error box (load and save errors stay until closed; also on stderr)",
            Action.DISMISS_ERROR, ("escape", "enter", "kp_enter"), C.ERROR),
    Binding(S.FILE, "Q", "quit (asks first when there are unsaved changes: Y or Q again quits, N or Esc stays;\n"
            "Esc never quits)", Action.QUIT, ("q",), C.ANY),
    # ---- file browser
    Binding(S.BROWSER, "Up / Down", "select the previous / next entry (PageUp / PageDown, Home / End, wheel)",
            Action.BROWSE_UP, ("up",), C.BROWSER),
    Binding(S.BROWSER, "", "", Action.BROWSE_DOWN, ("down",), C.BROWSER),
    Binding(S.BROWSER, "", "", Action.BROWSE_PAGE_UP, ("page_up",), C.BROWSER),
    Binding(S.BROWSER, "", "", Action.BROWSE_PAGE_DOWN, ("page_down",), C.BROWSER),
    Binding(S.BROWSER, "", "", Action.BROWSE_FIRST, ("home",), C.BROWSER),
    Binding(S.BROWSER, "", "", Action.BROWSE_LAST, ("end",), C.BROWSER),
    Binding(S.BROWSER, "Typing", "jump to the first entry whose name starts with the typed text\n"
            "(a typed path that matches no entry is opened as typed)", mouse=True, context=C.BROWSER),
    Binding(S.BROWSER, "Enter or left click", "open the model / enter the folder", Action.BROWSE_PICK,
            ("enter", "kp_enter"), C.BROWSER),
    Binding(S.BROWSER, "Backspace", "delete a typed character, else go up one folder", Action.BROWSE_PARENT,
            ("backspace",), C.BROWSER),
    Binding(S.BROWSER, "Esc", "close the browser (the current model stays)", Action.BROWSE_CANCEL, ("escape",),
            C.BROWSER),
)
del S, C

#: width of the help's left column
_LABEL_WIDTH = 22


def help_lines() -> list[tuple[str, bool]]:
    """The help text as ``(line, is_section_title)`` pairs, generated from
    :data:`KEYMAP` (rows with an empty label and help only dispatch)."""
    out: list[tuple[str, bool]] = []
    for section in Section:
        rows = [b for b in KEYMAP if b.section is section and (b.label or b.help)]
        if not rows:
            continue
        out.extend((line, True) for line in section.value.split("\n"))
        seen = set()
        for b in rows:
            if (b.label, b.help) in seen or not b.help:
                continue
            seen.add((b.label, b.help))
            first, *more = b.help.split("\n")
            pad = " " * (2 + b.indent)
            if b.label:
                out.append((f"{pad}{b.label:<{_LABEL_WIDTH - b.indent}} {first}".rstrip(), False))
                cont = " " * (2 + _LABEL_WIDTH + 1)
            else:
                out.append((f"{pad}{first}", False))
                cont = pad
            out.extend((cont + m, False) for m in more)
    return out


def help_text() -> str:
    """The help as one string (``splatedit edit --help`` epilog, README)."""
    return "\n".join(line for line, _ in help_lines()) + "\n"


# ---------------------------------------------------------------- dispatch
_TABLE: dict | None = None


def _table() -> dict:
    global _TABLE
    if _TABLE is None:
        t = {}
        for b in KEYMAP:
            if b.action is Action.NONE:
                continue
            for ch in b.chords:
                k = (ch.glfw_key(), ch.ctrl, ch.shift, b.context)
                if k in t and t[k] is not b.action:
                    raise ValueError(f"keymap: {ch} in {b.context} is bound twice ({t[k]} and {b.action})")
                t[k] = b.action
        _TABLE = t
    return _TABLE


def lookup(key: int, ctrl: bool, shift: bool, contexts) -> Action | None:
    """The action bound to glfw ``key`` with these modifiers in the first of
    ``contexts`` (an iterable of :class:`Context`, most specific first) that
    binds it, or None."""
    t = _table()
    for c in contexts:
        a = t.get((key, ctrl, shift, c))
        if a is not None:
            return a
    return None


def typed_char(key: int) -> str | None:
    """The character a TYPE_VALUE key types (digits, '.', '-')."""
    import glfw as g
    if g.KEY_0 <= key <= g.KEY_9:
        return str(key - g.KEY_0)
    if g.KEY_KP_0 <= key <= g.KEY_KP_9:
        return str(key - g.KEY_KP_0)
    if key in (g.KEY_PERIOD, g.KEY_KP_DECIMAL, g.KEY_COMMA):
        return "."
    if key in (g.KEY_MINUS, g.KEY_KP_SUBTRACT):
        return "-"
    return None


# ------------------------------------------------------------------ README
README_BEGIN = "<!-- controls: generated by `python -m splatedit.app.ui.keymap --write-readme` -->"
README_END = "<!-- controls: end -->"


def readme_block() -> str:
    """The README's controls list (between the markers), from the table."""
    return f"{README_BEGIN}\n```\n{help_text()}```\n{README_END}"


def readme_controls(text: str) -> str | None:
    """The controls block of a README text (markers included), or None."""
    m = re.search(re.escape(README_BEGIN) + r".*?" + re.escape(README_END), text, flags=re.S)
    return m.group(0) if m else None


def write_readme(path: Path) -> bool:
    """Rewrite the controls block of the README at ``path``; True when it changed."""
    text = path.read_text()
    old = readme_controls(text)
    if old is None:
        raise SystemExit(f"splatedit: error: {path}: no controls markers ({README_BEGIN!r})")
    new = text.replace(old, readme_block())
    if new != text:
        path.write_text(new)
    return new != text


def main(argv=None) -> int:
    import argparse
    p = argparse.ArgumentParser(prog="python -m splatedit.app.ui.keymap",
                                description="print the editor's controls, or rewrite the manual's list")
    p.add_argument("--write-readme", nargs="?", const="docs/editor.md", metavar="MANUAL",
                   help="rewrite the controls block of the editor manual (default ./docs/editor.md)")
    a = p.parse_args(argv)
    if a.write_readme:
        changed = write_readme(Path(a.write_readme))
        print(f"{a.write_readme}: {'updated' if changed else 'already in sync'}")
    else:
        sys.stdout.write(help_text())
    return 0


if __name__ == "__main__":
    sys.exit(main())
