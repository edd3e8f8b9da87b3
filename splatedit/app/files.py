"""Files of the editor: checking the model before a window opens, the
default save path, the refusal to overwrite the opened model, and the save /
export jobs (worker threads; the editor polls them)."""

from __future__ import annotations

import os
from pathlib import Path

from splatedit.app.jobs import Job
from splatedit.errors import InputError


def default_save_path(src: Path | None, name: str, bundled: bool) -> Path:
    """``<stem>-edited.ply`` next to the input (the current directory for the
    bundled model or an unwritable folder), never an existing file."""
    stem = Path(name).stem if name else (src.stem if src else "model")
    folder = Path.cwd()
    if src is not None and not bundled and os.access(src.parent, os.W_OK):
        folder = src.parent
    p = folder / f"{stem}-edited.ply"
    k = 2
    while p.exists():
        p = folder / f"{stem}-edited-{k}.ply"
        k += 1
    return p


def script_path_for(ply: Path) -> Path:
    return ply.with_suffix("").with_name(ply.with_suffix("").name + ".edits.json")


def _same_file(a, b) -> bool:
    try:
        return Path(a).expanduser().resolve() == Path(b).expanduser().resolve()
    except (OSError, RuntimeError):     # e.g. a symlink loop: compare the spellings
        return Path(a) == Path(b)


def save_refusal(target, model) -> str | None:
    """Why the editor refuses to save to ``target`` (None when it may): saves
    never replace the opened model (a user's file or the bundled one), nor
    does the edit script written beside the save."""
    if model is None:
        return None
    for path in (target, script_path_for(Path(target))):
        if _same_file(path, model):
            return (f"not saved: {path} is the opened model, which saves never replace "
                    "(Ctrl+Shift+S: save under another name)")
    return None


def check_model_file(path) -> None:
    """Refuse a model the editor could not open, before any window exists:
    missing, a directory, an extension :func:`splatedit.io.read` does not
    know, or unreadable.  Raises :class:`InputError` (one line, exit 2)."""
    from splatedit.io import READ_EXTENSIONS
    p = Path(path)
    if not p.exists():
        raise InputError("no such file", path=str(path))
    if p.is_dir():
        raise InputError("is a directory, not a file", path=str(path))
    ext = p.suffix.lower()
    if ext not in READ_EXTENSIONS:
        raise InputError(f"unsupported file extension {ext or '(none)'!r} for reading; "
                         f"supported: {', '.join(READ_EXTENSIONS)}", path=str(path))
    try:
        with open(p, "rb") as f:
            f.read(1)
    except OSError as exc:
        raise InputError(f"cannot read the file ({exc.strerror or exc})", path=str(path)) from None


def load_job(path: Path, wake) -> Job:
    def work(progress):
        from splatedit.io import read
        cloud = read(str(path), progress=progress)
        if not cloud.name:
            cloud.name = path.name
        return cloud
    return Job("loading", work, wake)


def save(ed, path: Path) -> None:
    """Start saving the session's cloud to ``path`` and its edit script beside
    it (``ed``: the editor, or anything with ``session``, ``jobs``, ``path``,
    ``say``, ``wake``)."""
    s = ed.session
    if "save" in ed.jobs:
        ed.say("a save is already running")
        return
    refusal = save_refusal(path, ed.path)
    if refusal:
        ed.say(refusal)
        return
    cloud, script, pos = s.cloud, s.edit_script(), s.history.position
    ed.save_as = path
    spath = script_path_for(path)

    def work(progress):
        from splatedit.io import write
        progress("saving", 0.0)
        write(str(path), cloud, overwrite=True)
        script.save(spath)
        return path, spath, pos

    ed.jobs["save"] = Job("saving", work, ed.wake)
    ed.say(f"saving {path} ...")


def export_script(ed, target: Path) -> None:
    """Start writing only the edit script that belongs beside ``target``."""
    script = ed.session.edit_script()
    spath = script_path_for(target)

    def work(progress):
        script.save(spath)
        return spath

    ed.jobs["export"] = Job("exporting", work, ed.wake)
