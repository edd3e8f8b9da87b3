"""Recovery files of the editor (issue 19 item 1): when something goes wrong
while there are unsaved edits -- an internal error in an event handler, a
job's landing, a commit or a frame (:mod:`splatedit.app.crash_guard`), or the
process being ended (SIGTERM, Ctrl+C in its terminal) -- the current document
is written to a recovery folder, and the next start of the editor offers to
restore it (as Blender's autosave / *Recover Last Session* does).

One recovery entry is three files in :func:`recovery_dir`, each written
atomically (:mod:`splatedit.atomic`; the manifest last, so an entry with a
manifest is complete):

* ``NAME-STAMP.ply``: the document as it was (splats: splatedit's lossless
  PLY; a Gaussian scene: its 3DGS PLY);
* ``NAME-STAMP.edits.json``: its edit script (every committed edit since the
  source model was opened: ``splatedit deform SOURCE --edit`` replays it);
* ``NAME-STAMP.recovery.json``: the manifest (``source``: the model that was
  opened, ``bundled``, ``time`` (Unix seconds), ``reason``, ``edits``,
  ``label``: the history step it was at).

Restoring opens the recovered model with its edits as the document's
committed edits (one history step, unsaved), so Ctrl+S writes a file and a
script that replays from the original source; the entry is removed once the
restored document is saved, or when the user discards it.
"""

from __future__ import annotations

import contextlib
import itertools
import json
import os
import time
from dataclasses import dataclass
from pathlib import Path

from splatedit.errors import SplatEditError

#: environment variable naming the recovery folder (tests point it at a temporary folder)
RECOVERY_DIR_ENV = "SPLATEDIT_RECOVERY_DIR"
MANIFEST_SUFFIX = ".recovery.json"


def recovery_dir() -> Path:
    """``$SPLATEDIT_RECOVERY_DIR``, else ``$XDG_STATE_HOME/splatedit/recovery``
    (``~/.local/state/splatedit/recovery`` when XDG_STATE_HOME is unset),
    following the XDG base directory specification's state home."""
    env = os.environ.get(RECOVERY_DIR_ENV)
    if env:
        return Path(env).expanduser()
    state = os.environ.get("XDG_STATE_HOME") or str(Path.home() / ".local" / "state")
    return Path(state).expanduser() / "splatedit" / "recovery"


@dataclass(frozen=True)
class RecoveryEntry:
    """One recovery entry (paths of its three files and the manifest's fields)."""
    manifest: Path
    model: Path
    script: Path
    source: str | None
    bundled: bool
    time: float
    reason: str
    edits: int
    label: str

    @property
    def name(self) -> str:
        """The source model's file name (what the question shows)."""
        return Path(self.source).name if self.source else self.model.name

    def when(self) -> str:
        return time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(self.time))

    def files(self) -> tuple[Path, Path, Path]:
        return self.model, self.script, self.manifest


_serial = itertools.count(1)


def _stem(source) -> str:
    """``NAME-YYYYmmdd-HHMMSS-PID-N``: unique per process (N counts this process's copies)."""
    base = Path(source).stem if source else "model"
    safe = "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in base)[:80] or "model"
    return f"{safe}-{time.strftime('%Y%m%d-%H%M%S')}-{os.getpid()}-{next(_serial)}"


def write_recovery(session, source, *, bundled: bool = False, reason: str = "",
                   folder: Path | None = None) -> RecoveryEntry | None:
    """Write ``session``'s document (its cloud, or the Gaussian scene behind
    it, and its edit script) as a recovery entry; None when there is nothing
    to recover (no committed edit, or nothing unsaved).

    Raises:
        SplatEditError: the folder or a file cannot be written (an entry
            without its manifest is never offered).
    """
    from splatedit.app.document.gaussian import gaussians_of
    from splatedit.io import write, write_gaussians
    from splatedit.atomic import atomic_write_text
    if session is None or not session.edits or not session.dirty:
        return None
    folder = Path(folder) if folder is not None else recovery_dir()
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise SplatEditError(f"{folder}: cannot create the recovery folder ({exc.strerror or exc})") from None
    stem = _stem(source)
    model, script = folder / f"{stem}.ply", folder / f"{stem}.edits.json"
    manifest = folder / f"{stem}{MANIFEST_SUFFIX}"
    cloud = session.cloud
    scene = gaussians_of(cloud)
    if scene is not None:
        write_gaussians(str(model), scene, overwrite=True)
    else:
        write(str(model), cloud, overwrite=True)
    session.edit_script().save(script)
    label = session.history.current.label
    entry = RecoveryEntry(manifest, model, script, None if source is None else str(source), bool(bundled),
                          time.time(), reason, len(session.edits), label)
    atomic_write_text(manifest, json.dumps({
        "version": 1, "model": model.name, "script": script.name, "source": entry.source,
        "bundled": entry.bundled, "time": entry.time, "reason": reason, "edits": entry.edits,
        "label": label}, indent=1) + "\n")
    return entry


def read_entry(manifest: Path) -> RecoveryEntry | None:
    """The entry of ``manifest`` (None when it is unreadable or its files are gone)."""
    try:
        d = json.loads(Path(manifest).read_text())
        folder = Path(manifest).parent
        model, script = folder / str(d["model"]), folder / str(d["script"])
        if not (model.is_file() and script.is_file()):
            return None
        return RecoveryEntry(Path(manifest), model, script, d.get("source"), bool(d.get("bundled", False)),
                             float(d.get("time", 0.0)), str(d.get("reason", "")), int(d.get("edits", 0)),
                             str(d.get("label", "")))
    except (OSError, ValueError, KeyError, TypeError):
        return None


def entries(folder: Path | None = None) -> list[RecoveryEntry]:
    """The complete recovery entries in ``folder`` (default :func:`recovery_dir`), newest first."""
    folder = Path(folder) if folder is not None else recovery_dir()
    try:
        manifests = sorted(folder.glob(f"*{MANIFEST_SUFFIX}"))
    except OSError:
        return []
    got = [e for e in (read_entry(m) for m in manifests) if e is not None]
    return sorted(got, key=lambda e: e.time, reverse=True)


def discard(entry: RecoveryEntry) -> None:
    """Remove the entry's files (the manifest first: a half-removed entry is never offered)."""
    for p in (entry.manifest, entry.model, entry.script):
        with contextlib.suppress(OSError):
            p.unlink()
