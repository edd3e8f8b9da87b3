"""The editor's command-line options and controls list.

Kept apart from :mod:`splatedit.app.editor` so that the command line can offer
``splatedit edit --help`` without importing the window, Vulkan or glfw.
"""

from __future__ import annotations

import argparse
import re

from splatedit.app.ui.keymap import help_text
from splatedit.tolerances import IQR_DEFAULT_TOL

#: the controls list, generated from the keymap (splatedit.app.ui.keymap: no glfw import)
CONTROLS = help_text()


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


#: a comma-separated list of numbers (``-0.4,1,2``, ``-1e3,0,5.``)
_NUMBERS = re.compile(r"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?(\s*,\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?)*\s*$")


def join_negative_values(argv: list[str], options: tuple[str, ...]) -> list[str]:
    """``argv`` with ``OPT VALUE`` written ``OPT=VALUE`` where ``OPT`` is one
    of ``options`` and ``VALUE`` is numbers starting with a minus
    (``--eye -0.4,1,2``): argparse takes such a value for an option, not
    for the option's argument."""
    out: list[str] = []
    i = 0
    while i < len(argv):
        a = argv[i]
        if a == "--":                   # what follows is positional only
            out.extend(argv[i:])
            break
        if a in options and i + 1 < len(argv) and argv[i + 1].startswith("-") and _NUMBERS.match(argv[i + 1]):
            out.append(f"{a}={argv[i + 1]}")
            i += 2
            continue
        out.append(a)
        i += 1
    return out


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
                   help="frame-time budget (default 100 ms = 10 fps; moving frames aim at 30 fps "
                        "unless this is smaller)")
    p.add_argument("--status-file", help="test hook: a JSON file rewritten when the state changes")


def options_from_args(a) -> dict:
    """The :func:`splatedit.app.editor.run_editor` keyword options of parsed
    :func:`add_arguments` arguments."""
    return dict(size=tuple(a.size), save_as=a.save_as, method=a.method, tol=a.tol, vsync=not a.no_vsync,
                lod=not a.no_lod, budget_ms=a.budget_ms, status_file=a.status_file)
