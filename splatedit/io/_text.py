"""Vectorised parsing of whitespace-separated numeric text (XYZ, OFF bodies).

The text is processed in blocks of whole lines.  Per block, numpy finds the
token starts and the line each token belongs to from a byte mask, and
``np.fromstring(..., sep=' ')`` parses every number in one C call.  Only when
that call fails does a slow per-line Python pass run, to name the bad line and
token in the error message.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from splatedit.errors import InputError
from splatedit.progress import report
from splatedit.tolerances import TEXT_BLOCK_BYTES

_COMMENT = re.compile(rb"#[^\n]*")
_WS = np.zeros(256, dtype=bool)
_WS[[9, 10, 11, 12, 13, 32]] = True


@dataclass
class NumberTable:
    """Numbers of the non-blank lines of a text, in file order.

    Attributes:
        values: (t,) float64, every number of every non-blank line.
        start: (L,) int64, index into ``values`` of each line's first number.
        count: (L,) int64, numbers on each line.
        line: (L,) int64, 1-based line number of each line in the file.
    """

    values: np.ndarray
    start: np.ndarray
    count: np.ndarray
    line: np.ndarray

    def __len__(self) -> int:
        return len(self.count)


def _bad_token(block: bytes, first_line: int, rows_before: int, path) -> InputError:
    """Slow pass over a block that failed to parse: find the first bad token.

    ``rows_before`` is the number of non-blank lines before the block, so the
    error carries the 0-based data row as well as the 1-based file line.
    """
    row = rows_before
    for i, raw in enumerate(block.split(b"\n")):
        toks = raw.split()
        for j, tok in enumerate(toks):
            try:
                float(tok)
            except ValueError:
                shown = tok.decode("utf-8", "replace")
                err = InputError(f"column {j + 1}: not a number: {shown!r} "
                                 f"(line {first_line + i})", path=path, row=row)
                err.line = first_line + i
                return err
        row += bool(toks)
    err = InputError(f"unparseable text near line {first_line}", path=path)
    err.line = first_line
    return err


def scan_numbers(data: bytes, path, *, first_line: int = 1, progress=None,
                 stage: str = "reading") -> NumberTable:
    """Parse ``data`` (whole lines of text) into a :class:`NumberTable`.

    ``#`` starts a comment running to the end of the line; blank lines are
    dropped.  ``first_line`` is the 1-based file line number of ``data[0]``.

    Raises:
        InputError: naming ``path`` and the line and column of the first token
            that is not a number.
    """
    values, starts, counts, lines = [], [], [], []
    pos, line0, total, nval, nrows = 0, first_line, max(len(data), 1), 0, 0
    while pos < len(data):
        end = min(pos + TEXT_BLOCK_BYTES, len(data))
        if end < len(data):
            nl = data.rfind(b"\n", pos, end)
            end = nl + 1 if nl >= pos else data.find(b"\n", end) + 1 or len(data)
        block = data[pos:end]
        if b"#" in block:
            block = _COMMENT.sub(b"", block)
        arr = np.frombuffer(block, dtype=np.uint8)
        ws = _WS[arr]
        is_start = ~ws
        is_start[1:] &= ws[:-1]
        tok = np.flatnonzero(is_start)
        newlines = np.flatnonzero(arr == 10)
        nlines_block = len(newlines) + (0 if block.endswith(b"\n") else 1)
        tok_line = np.searchsorted(newlines, tok)
        cnt = np.bincount(tok_line, minlength=nlines_block)
        try:
            vals = (np.fromstring(block.decode("latin-1"), dtype=np.float64, sep=" ")
                    if len(tok) else np.zeros(0))
        except ValueError:
            raise _bad_token(block, line0, nrows, path) from None
        if len(vals) != len(tok):  # defensive: must never happen
            raise _bad_token(block, line0, nrows, path)
        keep = np.flatnonzero(cnt)
        c = cnt[keep].astype(np.int64)
        s = np.zeros(len(c), dtype=np.int64)
        np.cumsum(c[:-1], out=s[1:])
        values.append(vals)
        starts.append(s + nval)
        counts.append(c)
        lines.append(keep.astype(np.int64) + line0)
        nval += len(vals)
        nrows += len(keep)
        line0 += len(newlines)
        pos = end
        report(progress, stage, pos / total)
    if not values:
        z = np.zeros(0, dtype=np.int64)
        return NumberTable(np.zeros(0), z, z, z)
    return NumberTable(np.concatenate(values), np.concatenate(starts),
                       np.concatenate(counts), np.concatenate(lines))


def read_bytes(path) -> bytes:
    """The whole file as bytes; a missing or unreadable file is an InputError."""
    try:
        with open(path, "rb") as fh:
            return fh.read()
    except OSError as exc:
        raise InputError(f"cannot read file: {exc.strerror or exc}", path=str(path)) from None


def line_error(message: str, path: str, row: int, line) -> InputError:
    """An :class:`InputError` for data row ``row`` (0-based) ending in
    ``(line N)`` (1-based file line), with ``line`` set on it."""
    err = InputError(f"{message} (line {line})", path=path, row=row)
    err.line = int(line)
    return err


def point_rows(path, *, columns: tuple[int, ...], expected: str, noun: str, check_count: bool,
               progress=None) -> tuple[np.ndarray, np.ndarray]:
    """The rows of a text point file (XYZ, PTS): one point per line, every
    line with the column count of the first (one of ``columns``).  A first
    line holding one number equal to the count of the lines after it (the
    PTS point-count line) is skipped; with ``check_count`` a first line of
    one number that is not that count is an error.

    Returns:
        (values (n, ncol) float64, 1-based file line of each row (n,) int)
    Raises:
        InputError: an empty file (``zero {noun}``); ``expected {expected},
            got {ncol}`` for a first row of another width; ``wrong column
            count`` naming the first row that differs from it.
    """
    src = str(path)
    tab = scan_numbers(read_bytes(path), src, progress=progress)
    if len(tab) == 0:
        raise InputError(f"empty file: no data lines (zero {noun})", path=src)
    start = 0
    if tab.count[0] == 1 and len(tab) > 1:
        declared = tab.values[tab.start[0]]
        if declared == len(tab) - 1:
            start = 1
        elif check_count:
            raise line_error(f"the count line says {declared:g} points but {len(tab) - 1} follow",
                             src, 0, tab.line[0])
    count, line = tab.count[start:], tab.line[start:]
    ncol = int(count[0])
    if ncol not in columns:
        raise line_error(f"expected {expected}, got {ncol}", src, 0, line[0])
    bad = count != ncol
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        raise line_error(f"wrong column count: expected {ncol} like line {line[0]}, got {count[row]}",
                         src, row, line[row])
    return tab.values[tab.start[start]:].reshape(-1, ncol), line
