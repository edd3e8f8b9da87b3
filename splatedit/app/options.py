"""The editor's command-line options and controls list.

Kept apart from :mod:`splatedit.app.editor` so that the command line can offer
``splatedit edit --help`` without importing the window, Vulkan or glfw.
"""

from __future__ import annotations

import argparse

from splatedit.tolerances import IQR_DEFAULT_TOL

CONTROLS = """\
Camera
  Middle drag            orbit around the pivot          (laptop: Alt + left drag)
  Shift + middle drag    pan                             (laptop: Alt + Shift + left drag)
  Ctrl + middle drag     dolly
  Wheel                  zoom to the cursor
  Home                   frame the whole model
  F  or  numpad .        frame the selection (handle, else support)
  Numpad 1 / 3 / 7       front / right / top view (Ctrl: back / left / bottom)
Selection (paper Sect. 3: support = blue, handles = green, the active one brighter)
  Left drag              paint with the brush: 3D, every splat in the sphere under the circle
  V                      brush mode: 3D (front and back) / visible splats only
  Ctrl + left drag       erase with the brush            (E toggles erase mode)
  1 / 2                  brush paints the support / the active handle (inside the support)
  Tab                    one handle: toggle support / handle brush; several: next handle (Shift: previous)
  N                      new handle (becomes active; paint it with the handle brush)
  Delete                 remove the active handle
  [ / ]  or  Ctrl+wheel  brush radius
  C / Shift+C            clear the selection / clear the handles
  Ctrl + =  /  Ctrl + -  grow / shrink the brush target by one ring (numpad + / - too)
  L / Shift+L            add the connected part under the cursor within the brush / all of it
  Ctrl + I               invert the brush target (support: handles cleared; handle: within the support)
  After each stroke or tool the selection is closed (holes, back sides); additions flash yellow
Deformation (the basis of all handles and the curve is fitted in the background;
             at most 16 columns: 4 per handle + 1 per curve point)
  Left drag on a handle  make it active and move it in the view plane
  Left drag on an arrow  move the active handle along that axis (gizmo: X red, Y green, Z blue)
  Left drag on a ring    rotate the active handle about that axis, through its centre
  Left drag outer circle scale the active handle about its centre (outward: larger)
  M                      deformation of new edits: ROTATION (default: handles' rotations are blended,
                         bends and twists keep their thickness) / LINEAR (the paper's)
  G / R / S              grab / rotate / scale the active handle with the mouse
    X / Y / Z            constrain to that world axis (again: free)
    0-9 . -              type a value: distance, degrees or factor (G X 0.1 Enter)
    Enter or left click  done (one handle, no curve: the edit is applied at once)
    Esc or right click   cancel this move
  With several handles or a curve the moves are kept (the other handles keep theirs):
    Enter                apply all of them as one edit (the result becomes the new base)
    Esc                  discard the pending moves
Control curve (paper Sect. 3 end, Fig. 3 and 7)
  K                      curve tool on / off (Shift+K: clear the curve)
  Left click on support  add a curve point (2..16); the curve through them is drawn as it will act
  Left drag on a dot     move that point in the view plane (X / Y / Z: along an axis)
  Backspace              remove the last curve point
  Enter / Esc            apply the bent curve as an edit (the curve is consumed) / discard moves
Distortion
  D                      heat map on / off: the support coloured by stretch (1x grey .. 3x red)
                         (the panel shows "stretch max N.Nx, K > 3x" while a pose is moved)
File and history
  Ctrl+Z / Ctrl+Shift+Z  undo / redo (edits and selections; Ctrl+Y also redoes)
  Ctrl+S                 save <name>-edited.ply (+ <name>-edited.edits.json edit script)
  Ctrl+Shift+S           save as: type a path, Enter
  Ctrl+E                 export only the edit script
  F1  or  H              show / hide this help
  Q                      quit (asks first when there are unsaved changes: Y or Q again quits, N or Esc stays;
                         Esc never quits)
"""


def parse_size(text: str) -> tuple[int, int]:
    """``"1280x720"`` -> (1280, 720); argparse type for window and image sizes."""
    try:
        w, h = (int(x) for x in str(text).lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"size must look like 1280x720, got {text!r}") from None
    if not (1 <= w <= 16384 and 1 <= h <= 16384):
        raise argparse.ArgumentTypeError(f"size must be between 1x1 and 16384x16384, got {text!r}")
    return w, h


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0 (tolerances, budgets)."""
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number, got {text!r}") from None
    if not (x > 0 and x != float("inf")):
        raise argparse.ArgumentTypeError(f"must be a finite number > 0, got {text!r}")
    return x


def add_arguments(p) -> None:
    """Add the ``splatedit edit`` options to an argparse parser."""
    p.add_argument("file", nargs="?", help="model to open (default: the bundled bunny)")
    p.add_argument("--save-as", help="save path (default: <name>-edited.ply next to the input, "
                   "or in the current directory for the bundled model)")
    p.add_argument("--size", type=parse_size, default=(1280, 720), help="window size WxH (default 1280x720)")
    p.add_argument("--method", default="auto", choices=("auto", "lu", "iqr"),
                   help="solver (also written to the exported edit script)")
    p.add_argument("--tol", type=positive_float, default=IQR_DEFAULT_TOL, help="IQR relative tolerance")
    p.add_argument("--no-vsync", action="store_true", help="present without vsync (MAILBOX/IMMEDIATE)")
    p.add_argument("--no-lod", action="store_true", help="never draw a level of detail while moving")
    p.add_argument("--budget-ms", type=positive_float, default=100.0,
                   help="frame-time budget while moving (default 100 ms = 10 fps)")
    p.add_argument("--status-file", help="test hook: a JSON file rewritten when the state changes")


def options_from_args(a) -> dict:
    """The :func:`splatedit.app.editor.run_editor` keyword options of parsed
    :func:`add_arguments` arguments."""
    return dict(size=tuple(a.size), save_as=a.save_as, method=a.method, tol=a.tol, vsync=not a.no_vsync,
                lod=not a.no_lod, budget_ms=a.budget_ms, status_file=a.status_file)
