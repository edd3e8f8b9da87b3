"""The editor's recent files: a small JSON list in the user's config folder.

``$XDG_CONFIG_HOME/splatedit/recent.json`` (``~/.config/splatedit/recent.json``
when the variable is unset), written atomically
(:func:`splatedit.atomic.atomic_write_text`)::

    {"version": 1, "files": ["/abs/path/newest.ply", "/abs/path/older.xyz"]}

Most recent first, at most :data:`RECENT_MAX` entries, absolute paths; files
that no longer exist are dropped when the list is read.  A missing, unreadable
or malformed list is an empty one (recent files are a convenience: they never
stop the editor), and a list that cannot be written is reported once.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from splatedit.errors import SplatEditError

#: how many recent files are kept
RECENT_MAX = 10
RECENT_VERSION = 1


def config_dir() -> Path:
    """The user's splatedit config folder (``$XDG_CONFIG_HOME/splatedit``)."""
    base = os.environ.get("XDG_CONFIG_HOME", "").strip()
    root = Path(base) if base and Path(base).is_absolute() else Path.home() / ".config"
    return root / "splatedit"


def recent_path() -> Path:
    return config_dir() / "recent.json"


class RecentFiles:
    """The recent-files list at ``path`` (default :func:`recent_path`, read
    each time: several editors may share it)."""

    def __init__(self, path: Path | None = None):
        self.path = Path(path) if path is not None else recent_path()

    def _read(self) -> list[str]:
        try:
            data = json.loads(self.path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return []
        files = data.get("files") if isinstance(data, dict) else None
        if not isinstance(files, list):
            return []
        return [f for f in files if isinstance(f, str) and f]

    def files(self) -> list[Path]:
        """Existing recent files, most recent first (at most :data:`RECENT_MAX`)."""
        out: list[Path] = []
        for f in self._read():
            p = Path(f)
            if p.is_file() and p not in out:
                out.append(p)
        return out[:RECENT_MAX]

    def clear(self) -> None:
        """Forget every recent file (raises like :meth:`add`)."""
        self._write([])

    def add(self, path) -> None:
        """Put ``path`` first (made absolute) and write the list.

        Raises:
            SplatEditError: the list cannot be written (message names it).
        """
        p = Path(os.path.abspath(Path(path).expanduser()))
        files = [p] + [f for f in self.files() if f != p]
        self._write(files[:RECENT_MAX])

    def _write(self, files: list[Path]) -> None:
        from splatedit.atomic import atomic_write_text
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise SplatEditError(f"{self.path.parent}: cannot keep the recent files: "
                                 f"{exc.strerror or exc}") from None
        text = json.dumps({"version": RECENT_VERSION, "files": [str(f) for f in files]}, indent=1)
        atomic_write_text(self.path, text + "\n")


def menu_labels(files: list[Path]) -> list[str]:
    """Menu rows for ``files``: the file name, followed by its folder
    (``scan.ply  (/data/site-a)``) when another entry has the same name."""
    names = [f.name for f in files]
    return [f"{f.name}  ({f.parent})" if names.count(f.name) > 1 else f.name for f in files]
