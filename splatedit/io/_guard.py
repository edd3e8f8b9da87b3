"""Calls into file-format libraries (laspy/lazrs, pye57/libE57Format) made safe
for the one-line error contract.

:func:`library_call` turns whatever such a library raises (its own exception
types, ``ValueError``, ``MemoryError``, ...) into one :class:`InputError`
naming the file, and captures what the library prints on the process's
standard error (libE57Format prints debug lines; a C library bypasses
``sys.stderr``): on failure that text is folded into the error's single line,
on success it is dropped.  Used by every reader and writer that calls such a
library; the readers validate what they can (counts against the file size,
finite scales) *before* the call, this is the net behind those checks.

The capture redirects the process's file descriptor 2 for the call: what
another thread prints on stderr meanwhile (the editor reads files in the
background) lands in the capture too and is dropped on success.
"""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
import threading

from splatedit.errors import InputError, SplatEditError

_LOCK = threading.RLock()
#: at most this many characters of a library's stderr output go into the message
_MAX_LIBRARY_TEXT = 300


def _one_line(text: str) -> str:
    """``text`` as one line: its non-blank lines joined by ' / ', shortened."""
    parts = [ln.strip() for ln in text.splitlines() if ln.strip()]
    line = " / ".join(parts)
    return line if len(line) <= _MAX_LIBRARY_TEXT else line[:_MAX_LIBRARY_TEXT - 3] + "..."


def _os_error_in(exc: BaseException):
    """The first OSError with a ``strerror`` in ``exc``'s cause/context chain
    (lazrs wraps the OSError of a full disk as 'Failed to call write')."""
    seen = 0
    while exc is not None and seen < 8:
        if isinstance(exc, OSError) and exc.strerror:
            return exc
        exc = exc.__cause__ or exc.__context__
        seen += 1
    return None


@contextlib.contextmanager
def _captured_fd2():
    """Redirect file descriptor 2 to a temporary file for the block; yields
    a list that holds the captured text (one str) after the block.  Without
    a usable fd 2 (an embedded interpreter) nothing is captured."""
    box: list[str] = []
    try:
        sys.stderr.flush()
        saved = os.dup(2)
    except (OSError, ValueError, AttributeError):
        yield box
        return
    with _LOCK, tempfile.TemporaryFile() as tmp:
        try:
            os.dup2(tmp.fileno(), 2)
            yield box
        finally:
            with contextlib.suppress(OSError, ValueError):
                sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            box.append(tmp.read(1 << 16).decode("utf-8", "replace"))


class RecordingStream:
    """A binary file object passed to a library in place of ``fh``: the
    OSError of a failed write (disk full) is kept in ``error``, since some
    libraries replace it by their own message (lazrs: 'Failed to call
    write')."""

    def __init__(self, fh):
        self._fh = fh
        self.error: OSError | None = None

    def write(self, data):
        try:
            return self._fh.write(data)
        except OSError as exc:
            self.error = exc
            raise

    def __getattr__(self, name):
        return getattr(self._fh, name)


@contextlib.contextmanager
def library_call(path, what: str, stream: RecordingStream | None = None):
    """Run the block calling a format library on ``path``.

    Args:
        path: the file named in the error.
        what: the start of the message, e.g. ``"not a readable LAS/LAZ file"``
            or ``"cannot write E57"``.
        stream: the :class:`RecordingStream` the library writes to, if any:
            its OSError's reason is added to the message.
    Raises:
        InputError: ``{path}: {what}: {the library's message}
        [(library output: ...)]`` for any exception (a Rust library's panic
        too, a BaseException) but our own errors and KeyboardInterrupt /
        SystemExit, which pass unchanged.
    """
    with _captured_fd2() as out:
        try:
            yield
        except (SplatEditError, KeyboardInterrupt, SystemExit, GeneratorExit):
            raise
        except MemoryError:
            failure = "not enough memory"
        except BaseException as exc:   # noqa: BLE001 - pyo3's PanicException is a BaseException
            text = str(exc).strip()
            failure = text.splitlines()[0].strip() if text else type(exc).__name__
            cause = _os_error_in(exc) or (stream.error if stream is not None else None)
            if cause is not None:       # disk full in our own file object, under the library's wrapper
                failure = cause.strerror if cause is exc else f"{failure}: {cause.strerror}"
        else:
            return
    said = _one_line("\n".join(ln for ln in (out[0] if out else "").splitlines()
                               if failure not in ln))
    extra = f" (library output: {said})" if said else ""
    raise InputError(f"{what}: {failure}{extra}", path=str(path)) from None
