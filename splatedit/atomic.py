"""Atomic file replacement: write to a temporary file beside the target, then rename.

A crash or error half-way never leaves a truncated file where a good one was.
A temporary file left by a killed process (SIGKILL cannot be caught) is
recognised by its name and removed on the next write to the same target.
"""

from __future__ import annotations

import contextlib
import os
import re
import tempfile
from pathlib import Path
from typing import IO, Iterator

from splatedit.errors import InputError


def check_writable_target(path: str | Path, *, overwrite: bool, protect: str | Path | None = None) -> Path:
    """Check, before any long work, that ``path`` can be written.

    Refuses to clobber an existing file (or the input ``protect``) unless
    ``overwrite``; the parent must be an existing directory.

    Raises:
        InputError: naming the path.
    """
    p = Path(path)
    parent = p.parent if str(p.parent) else Path(".")
    try:
        if not parent.exists():
            raise InputError("directory does not exist", path=str(parent))
        if not parent.is_dir():
            raise InputError("is not a directory", path=str(parent))
        if p.is_dir():
            raise InputError("is a directory", path=str(p))
        if p.exists() and not p.is_file():
            raise InputError("is not a regular file (a FIFO, device or socket)", path=str(p))
        if (protect is not None and p.exists() and Path(protect).exists()
                and p.resolve() == Path(protect).resolve() and not overwrite):
            raise InputError("refusing to overwrite the input file (pass overwrite/--force to do so)", path=str(p))
        if p.exists() and not overwrite:
            raise InputError("file exists (pass overwrite/--force to replace it)", path=str(p))
        if not os.access(parent, os.W_OK | os.X_OK):
            raise InputError("directory is not writable", path=str(parent))
        # the temporary file's name (see atomic_open) is the longest we create:
        # a name too long for the file system fails here, before the work
        os.stat(parent / (_temp_prefix(p) + "x" * 8 + _TEMP_SUFFIX))
    except FileNotFoundError:
        pass
    except OSError as exc:      # a name too long, a loop of links, no permission to look
        raise InputError(f"cannot write there: {exc.strerror or exc}", path=str(p)) from None
    except ValueError as exc:   # an embedded NUL byte
        raise InputError(f"not a usable file name: {exc}", path=repr(str(p))) from None
    return p


def _current_umask() -> int:
    """The process umask, read without changing it (os.umask would race with
    other threads creating files); falls back to 0o022."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    return 0o022


_TEMP_SUFFIX = ".tmp"


def _temp_prefix(path: Path) -> str:
    """Our temporary files for ``path``: ``.NAME.PID.RANDOM.tmp`` beside it;
    the writer's process id tells a stale one (its writer is gone: killed
    by SIGKILL or a power cut) from one being written right now."""
    return f".{path.name}.{os.getpid()}."


def remove_stale_temporaries(path: str | Path) -> list[Path]:
    """Delete the temporary files a killed splatedit left beside ``path``:
    regular files named ``.NAME.PID.RANDOM.tmp`` whose process PID no longer
    runs.  Others' files and live writers' files are left alone.

    Returns:
        the paths removed.
    """
    p = Path(path)
    directory = p.parent if str(p.parent) else Path(".")
    pattern = re.compile(re.escape(f".{p.name}.") + r"(\d+)\.[A-Za-z0-9_]{8}" + re.escape(_TEMP_SUFFIX))
    removed = []
    try:
        candidates = [e for e in os.scandir(directory) if e.name.startswith(f".{p.name}.")]
    except OSError:
        return removed
    for entry in candidates:
        m = pattern.fullmatch(entry.name)
        if m is None or not entry.is_file(follow_symlinks=False) or _process_alive(int(m.group(1))):
            continue
        with contextlib.suppress(OSError):
            os.unlink(entry.path)
            removed.append(Path(entry.path))
    return removed


def _process_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, OSError):
        return True       # exists (another user's) or cannot tell: keep the file
    return True


@contextlib.contextmanager
def atomic_open(path: str | Path, mode: str = "wb") -> Iterator[IO]:
    """Open a temp file beside ``path``; on success rename it onto ``path``.

    On any exception the temporary file is removed and ``path`` is untouched;
    an ``OSError`` becomes an :class:`InputError` naming ``path``.
    """
    p = Path(path)
    directory = p.parent if str(p.parent) else Path(".")
    if not directory.is_dir():
        raise InputError("directory does not exist" if not directory.exists() else "is not a directory",
                         path=str(directory))
    # keep an existing file's permissions; new files get the usual 0666 & ~umask
    # (mkstemp itself creates 0600 files)
    if p.exists():
        perms = p.stat().st_mode & 0o777
    else:
        perms = 0o666 & ~_current_umask()
    remove_stale_temporaries(p)
    try:
        fd, tmp = tempfile.mkstemp(prefix=_temp_prefix(p), suffix=_TEMP_SUFFIX, dir=directory)
    except OSError as exc:
        raise InputError(f"cannot write: {exc.strerror or exc}", path=str(p)) from None
    try:
        with os.fdopen(fd, mode) as fh:
            # best effort: some file systems (vfat) refuse chmod, the data matter more
            with contextlib.suppress(OSError):
                os.fchmod(fh.fileno(), perms)
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, p)
    except OSError as exc:   # disk full, permissions, target became a directory, ...
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise InputError(f"cannot write: {exc.strerror or exc}", path=str(p)) from None
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def atomic_write_text(path: str | Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    with atomic_open(path, "w") as fh:
        fh.write(text)
