"""The file browser (Ctrl+O): a list drawn in the overlay, driven by keys and
the mouse, that opens a model in the same window.

Why not a native dialog: imgui-bundle's ``portable_file_dialogs`` run
``zenity`` / ``kdialog`` (on Linux) as a separate process with its own
window; neither is installed here nor on a typical headless test machine,
their window cannot be driven reliably by xdotool under Xvfb, and the editor
would block on (or poll) another process.  A list of our own works wherever
the editor works, is tested through real key presses, and needs no package.

The list: the recent files first (:mod:`splatedit.app.ui.recent`), then the
folder's parent (``..``), its sub-folders and the files whose extension
:func:`splatedit.io.read` knows (:data:`splatedit.io.READ_EXTENSIONS`);
hidden entries are left out.  Up / Down / PageUp / PageDown / Home / End
move, typing a name jumps to the first entry starting with it (a typed path
that matches nothing is opened as typed, relative to the folder), Enter or
a click opens a file or enters a folder, Backspace deletes a typed character
or goes up a folder, the wheel scrolls, Esc cancels.
"""

from __future__ import annotations

import enum
import os
from dataclasses import dataclass
from pathlib import Path

from splatedit.app.ui import overlay as ov
from splatedit.app.ui.keymap import Action, Section
from splatedit.app.tools.base import Tool

BROWSER_FONT = 14
BROWSER_TITLE_RGB = (140, 190, 255)
BROWSER_SELECTED_RGB = (255, 220, 120)
BROWSER_RECENT_RGB = (170, 230, 170)
BROWSER_DIR_RGB = (150, 200, 255)
BROWSER_ERROR_RGB = (255, 120, 120)
#: lines of the browser that are not entries (title, folder, footer)
_CHROME_LINES = 3
#: the widest entry row in characters (longer names are cut in the middle)
BROWSER_MAX_CHARS = 90


class EntryKind(enum.Enum):
    RECENT = "recent"
    PARENT = "parent"
    FOLDER = "folder"
    FILE = "file"


@dataclass(frozen=True)
class Entry:
    """One row of the browser: ``path`` (absolute) and what it is."""
    path: Path
    kind: EntryKind

    @property
    def name(self) -> str:
        return ".." if self.kind is EntryKind.PARENT else self.path.name

    def label(self) -> str:
        if self.kind is EntryKind.RECENT:
            return f"recent  {self.path.name}   ({_cut(str(self.path.parent), 50)})"
        if self.kind is EntryKind.PARENT:
            return "../"
        if self.kind is EntryKind.FOLDER:
            return self.name + "/"
        try:
            size = self.path.stat().st_size
        except OSError:
            return self.name
        return f"{self.name:<40} {_size_text(size):>9}"


def _size_text(n: int) -> str:
    for unit in ("B", "kB", "MB", "GB"):
        if n < 1000 or unit == "GB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1000.0
    return f"{n:.1f} GB"


def _cut(text: str, n: int) -> str:
    return text if len(text) <= n else text[:n // 2 - 1] + "..." + text[-(n - n // 2 - 2):]


def list_folder(folder: Path) -> tuple[list[Entry], str | None]:
    """``(entries, error)`` of ``folder``: its parent, sub-folders and
    readable model files (hidden ones left out), each group sorted by name
    ignoring case; ``error`` says why the folder cannot be listed."""
    from splatedit.io import READ_EXTENSIONS
    entries: list[Entry] = []
    if folder.parent != folder:
        entries.append(Entry(folder.parent, EntryKind.PARENT))
    folders, models = [], []
    try:
        with os.scandir(folder) as it:
            for d in it:
                if d.name.startswith("."):
                    continue
                try:
                    if d.is_dir():
                        folders.append(Entry(folder / d.name, EntryKind.FOLDER))
                    elif d.is_file() and Path(d.name).suffix.lower() in READ_EXTENSIONS:
                        models.append(Entry(folder / d.name, EntryKind.FILE))
                except OSError:
                    continue
    except OSError as exc:
        return entries, f"cannot list {folder}: {exc.strerror or exc}"
    key = lambda e: e.name.lower()  # noqa: E731
    return entries + sorted(folders, key=key) + sorted(models, key=key), None


class FileBrowserTool(Tool):
    """The Ctrl+O file browser (modal while shown).  ``ed.file_actions.open_path(path)``
    opens the picked file; ``ed.file_actions.recent_files()`` gives the recent list."""
    section = Section.BROWSER

    def __init__(self, ed):
        super().__init__(ed)
        self.ed = ed                 # a modal dialog of the editor's files, not a view tool
        self.shown = False
        self.folder = Path.cwd()
        self.entries: list[Entry] = []
        self.error: str | None = None
        self.index = 0
        self.top = 0
        self.rows = 1               # entry rows that fit (last layout)
        self.typed = ""
        self.box: tuple[int, int, int, int] | None = None   # x, y, w, h of the last drawing
        self.row0 = 0              # y of the first entry row
        self.line_h = 1

    # ------------------------------------------------------------ state
    def open(self, folder=None) -> None:
        """Show the browser in ``folder`` (default: the opened model's folder,
        else the current one)."""
        if folder is None:
            p = self.ed.path
            folder = p.parent if p is not None and not self.ed.bundled else Path.cwd()
        self.shown = True
        self.chdir(Path(folder))

    def close(self) -> None:
        self.shown = False
        self.typed = ""
        self.box = None

    def chdir(self, folder: Path, select: Path | None = None) -> None:
        folder = Path(os.path.abspath(folder))
        listed, self.error = list_folder(folder)
        if self.error is not None and not listed:
            self.ed.say(self.error)
        self.folder = folder
        recent = [Entry(p, EntryKind.RECENT) for p in self.ed.file_actions.recent_files()]
        self.entries = recent + listed
        self.typed = ""
        self.index = self.top = 0
        if select is not None:
            for i, e in enumerate(self.entries):
                if e.kind is EntryKind.FOLDER and e.path == select:
                    self.index = i
                    break
        elif recent:
            self.index = 0
        else:   # skip ".." so that Enter opens the first model
            self.index = next((i for i, e in enumerate(self.entries) if e.kind is EntryKind.FILE), 0)
        self._scroll_to()

    @property
    def selected(self) -> Entry | None:
        return self.entries[self.index] if 0 <= self.index < len(self.entries) else None

    def move(self, delta: int) -> None:
        if self.entries:
            self.index = min(max(self.index + delta, 0), len(self.entries) - 1)
        self.typed = ""
        self._scroll_to()

    def _scroll_to(self) -> None:
        r = max(self.rows, 1)
        if self.index < self.top:
            self.top = self.index
        elif self.index >= self.top + r:
            self.top = self.index - r + 1
        self.top = max(min(self.top, max(len(self.entries) - r, 0)), 0)

    def scroll(self, lines: int) -> None:
        r = max(self.rows, 1)
        self.top = max(min(self.top + lines, max(len(self.entries) - r, 0)), 0)

    def type_char(self, ch: str) -> None:
        """A typed character: jump to the first entry whose name starts with
        the typed text (case ignored)."""
        if not ch.isprintable():
            return
        self.typed += ch
        t = self.typed.lower()
        for i, e in enumerate(self.entries):
            if e.kind is not EntryKind.PARENT and e.name.lower().startswith(t):
                self.index = i
                self._scroll_to()
                return

    def backspace(self) -> None:
        if self.typed:
            self.typed = self.typed[:-1]
        elif self.folder.parent != self.folder:
            self.chdir(self.folder.parent, select=self.folder)

    def pick(self) -> None:
        """Enter: open the selected file / enter the selected folder; a typed
        name that matches no entry is taken as a path (relative to the folder)."""
        e = self.selected
        if self.typed and (e is None or not e.name.lower().startswith(self.typed.lower())):
            target = self.folder / Path(self.typed).expanduser()
            if target.is_dir():
                self.chdir(target)
            else:
                self._open(target)
            return
        if e is None:
            return
        if e.kind in (EntryKind.PARENT, EntryKind.FOLDER):
            self.chdir(e.path, select=self.folder if e.kind is EntryKind.PARENT else None)
        else:
            self._open(e.path)

    def _open(self, path: Path) -> None:
        self.close()
        self.ed.file_actions.open_path(path)

    def actions(self) -> dict:
        return {Action.BROWSE_UP: lambda: self.move(-1), Action.BROWSE_DOWN: lambda: self.move(1),
                Action.BROWSE_PAGE_UP: lambda: self.move(-max(self.rows - 1, 1)),
                Action.BROWSE_PAGE_DOWN: lambda: self.move(max(self.rows - 1, 1)),
                Action.BROWSE_FIRST: lambda: self.move(-len(self.entries)),
                Action.BROWSE_LAST: lambda: self.move(len(self.entries)),
                Action.BROWSE_PICK: self.pick, Action.BROWSE_PARENT: self.backspace,
                Action.BROWSE_CANCEL: self.cancel}

    def cancel(self) -> None:
        self.close()
        self.ed.say("open cancelled")

    # ------------------------------------------------------------ mouse
    def row_at(self, x: float, y: float) -> int | None:
        """The entry index under pixel (x, y) of the last drawing, or None."""
        if self.box is None:
            return None
        bx, by, bw, bh = self.box
        if not (bx <= x < bx + bw):
            return None
        k = int((y - self.row0) // self.line_h)
        if y < self.row0 or not 0 <= k < self.rows:
            return None
        i = self.top + k
        return i if i < len(self.entries) else None

    def click(self, x: float, y: float) -> None:
        """A left click: the row under it is picked; outside the list nothing happens."""
        i = self.row_at(x, y)
        if i is not None:
            self.index = i
            self.typed = ""
            self.pick()

    # ------------------------------------------------------------ drawing
    def lines(self, h: int, line_h: int, pad: int) -> list:
        """The browser's text rows for a window ``h`` pixels tall with rows of
        ``line_h`` pixels: title, folder, the entries that fit (sets
        :attr:`rows`, scrolls to the selection), footer; [(text, rgb)]."""
        self.rows = max((h - 40 - 2 * pad) // max(line_h, 1) - _CHROME_LINES, 1)
        self._scroll_to()
        shown = self.entries[self.top:self.top + self.rows]
        lines: list = [("Open a model - Enter: open   Backspace: up   type: jump to a name   Esc: cancel",
                        BROWSER_TITLE_RGB),
                       (_cut(str(self.folder), BROWSER_MAX_CHARS), BROWSER_TITLE_RGB)]
        for k, e in enumerate(shown):
            sel = self.top + k == self.index
            text = ("> " if sel else "  ") + _cut(e.label(), BROWSER_MAX_CHARS)
            col = (BROWSER_SELECTED_RGB if sel else BROWSER_RECENT_RGB if e.kind is EntryKind.RECENT
                   else BROWSER_DIR_RGB if e.kind in (EntryKind.FOLDER, EntryKind.PARENT) else (235, 235, 235))
            lines.append((text, col))
        if self.error:
            foot = (self.error[:BROWSER_MAX_CHARS], BROWSER_ERROR_RGB)
        elif self.typed:
            foot = (f"name: {self.typed}_   (Enter opens it; Backspace deletes)", BROWSER_SELECTED_RGB)
        else:
            n = sum(e.kind is EntryKind.FILE for e in self.entries)
            foot = (f"{n} model file(s) here   {self.top + 1}-{self.top + len(shown)} of {len(self.entries)}",
                    (200, 200, 200))
        lines.append(foot)
        return lines

    def placed(self, box: tuple[int, int, int, int], pad: int, line_h: int) -> None:
        """Record where the rows were drawn (``box`` x, y, w, h) for :meth:`row_at`."""
        self.box = box
        self.row0, self.line_h = box[1] + pad + 2 * line_h, line_h

    def overlay(self, w: int, h: int) -> list:
        if not self.shown:
            return []
        f = ov.font(BROWSER_FONT)
        asc, desc = f.getmetrics()
        lh = asc + desc + 2
        pad = 8
        lines = self.lines(h, lh, pad)
        img = ov.text_panel(tuple(lines), size=BROWSER_FONT, bg=(12, 16, 26, 240), pad=pad, min_width=560)
        img = img[:max(h, 1), :max(w, 1)]
        x, y = max((w - img.shape[1]) // 2, 0), max((h - img.shape[0]) // 2, 0)
        self.placed((x, y, img.shape[1], img.shape[0]), pad, lh)
        return [ov.Patch(x, y, img)]
