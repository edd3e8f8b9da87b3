"""Leica PTX (ASCII): one or more scans, each a 10-line header and then its
grid of points, one per line, column by column.

Header of a scan::

    C                 columns of the scan grid
    R                 rows
    px py pz          scanner position (registered coordinates)
    ax ay az          scanner X axis
    bx by bz          scanner Y axis
    cx cy cz          scanner Z axis
    m00 m01 m02 0     4x4 transform, row vectors: a point p (scanner
    m10 m11 m12 0     coordinates) lies at [p 1] @ M in registered
    m20 m21 m22 0     coordinates (the translation is the 4th row; the
    tx  ty  tz  1     last column must be 0 0 0 1)

then C x R lines of ``x y z intensity`` or ``x y z intensity r g b``.
A point ``0 0 0 i`` is a missing return (the scanner got no echo there) and
is dropped.  Intensity is 0..1 and is kept like LAS's (uint16, 0..65535:
``round(i * 65535)``); colours are 0..255, and scans without colours get
grey from the intensity (:func:`splatedit.io.las.grey_from_intensity`).
The scanner position and axes are not needed (the transform places the
points) and are read only to check the header.  PTX is only read.

Every problem is an :class:`~splatedit.errors.InputError` naming the file
and, for a bad line, its 1-based line number (its ``row`` is the point's
index in its scan, or the header line's 0..9).
"""

from __future__ import annotations

import numpy as np

from splatedit.errors import InputError
from splatedit.io._build import build_cloud, check_finite, colors_from_columns
from splatedit.io._text import line_error, read_bytes, scan_numbers
from splatedit.io.las import grey_from_intensity
from splatedit.model.cloud import SplatCloud

#: numbers on each header line, and what the line holds
_HEADER = ((1, "the column count"), (1, "the row count"), (3, "the scanner position"),
           (3, "the scanner X axis"), (3, "the scanner Y axis"), (3, "the scanner Z axis"),
           (4, "transform row 1"), (4, "transform row 2"), (4, "transform row 3"), (4, "transform row 4"))
#: header line (0..9) of each of the 30 header numbers
_LINE_OF_VALUE = np.repeat(np.arange(len(_HEADER)), [want for want, _ in _HEADER])
#: the largest column / row count taken (a bigger one is a corrupt header)
_MAX_GRID = 1 << 24


def read_ptx(path, *, progress=None) -> SplatCloud:
    """Read a ``.ptx`` file, every scan in it merged (see the module docstring).

    Returns:
        SplatCloud of the returns in registered coordinates, float64 on
        reading; ``intensity`` (n,) uint16, ``colors`` (n, 4) uint8.
    Raises:
        InputError: an empty file, a header line with the wrong count of
            numbers, a bad grid size or transform, fewer point lines than
            the header says, a point line of other than 4 or 7 numbers,
            non-finite values, intensity outside 0..1, colours outside
            0..255, or no point that is not a missing return.
    """
    src = str(path)
    tab = scan_numbers(read_bytes(path), src, progress=progress)
    if len(tab) == 0:
        raise InputError("empty file: no data lines (zero points)", path=src)
    positions, intensity, colours = [], [], []
    i, scan = 0, 0
    while i < len(tab):
        scan += 1
        if len(tab) - i < len(_HEADER):
            raise line_error(f"scan {scan}: the header is cut short ({len(tab) - i} of its "
                             f"{len(_HEADER)} lines)", src, i, tab.line[i])
        for h, (want, what) in enumerate(_HEADER):
            if tab.count[i + h] != want:
                raise line_error(f"scan {scan} header: expected {want} number{'s' * (want > 1)} "
                                 f"({what}), got {tab.count[i + h]}", src, i + h, tab.line[i + h])
        head = tab.values[tab.start[i]:tab.start[i + len(_HEADER) - 1] + 4]
        for h, value in enumerate(head[:2]):
            if not (0 <= value <= _MAX_GRID and value == np.floor(value)):
                raise line_error(f"scan {scan} header: {_HEADER[h][1]} {value:g} is not an integer "
                                 f"in 0..{_MAX_GRID}", src, i + h, tab.line[i + h])
        bad_head = np.flatnonzero(~np.isfinite(head))
        if len(bad_head):
            h = int(_LINE_OF_VALUE[bad_head[0]])
            raise line_error(f"scan {scan} header: {_HEADER[h][1]} is not finite", src, i + h, tab.line[i + h])
        m = head[14:30].reshape(4, 4)
        if not np.array_equal(m[:, 3], [0.0, 0.0, 0.0, 1.0]):
            raise line_error(f"scan {scan} header: the transform's last column is "
                             f"{' '.join(f'{v:g}' for v in m[:, 3])}, not 0 0 0 1 (PTX stores row "
                             f"vectors: the translation is row 4)", src, i + 6, tab.line[i + 6])
        n = int(head[0]) * int(head[1])
        first = i + len(_HEADER)
        if len(tab) - first < n:
            raise line_error(f"scan {scan}: the header says {int(head[0])} x {int(head[1])} = {n} points "
                             f"but only {len(tab) - first} line{'s' * (len(tab) - first != 1)} follow",
                             src, i, tab.line[i])
        i = first + n
        if n == 0:
            continue
        count, line = tab.count[first:i], tab.line[first:i]
        ncol = int(count[0])
        if ncol not in (4, 7):
            raise line_error(f"scan {scan}: expected 4 or 7 columns (x y z intensity [r g b]), got {ncol}",
                             src, 0, line[0])
        off = np.flatnonzero(count != ncol)
        if len(off):
            row = int(off[0])
            raise line_error(f"wrong column count: expected {ncol} like line {line[0]}, got {count[row]}",
                             src, row, line[row])
        vals = tab.values[tab.start[first]:tab.start[first] + n * ncol].reshape(n, ncol)
        check_finite({nm: vals[:, j] for j, nm in enumerate("xyz")} | {"intensity": vals[:, 3]},
                     src, None, line)
        raw = vals[:, 3]
        out = (raw < 0) | (raw > 1)
        if out.any():
            row = int(np.flatnonzero(out)[0])
            raise line_error(f"intensity {raw[row]:g} is not in 0..1", src, row, line[row])
        rgb = None
        if ncol == 7:
            rgb = colors_from_columns([np.rint(vals[:, j]).astype(np.int64) for j in (4, 5, 6)],
                                      ["r", "g", "b"], src, None, line)
        hit = np.any(vals[:, :3] != 0.0, axis=1)
        positions.append(vals[hit, :3] @ m[:3, :3] + m[3, :3])
        intensity.append(np.rint(raw[hit] * 65535.0).astype(np.uint16))
        colours.append(None if rgb is None else rgb[hit])
    pos = np.concatenate(positions) if positions else np.zeros((0, 3))
    if len(pos) == 0:
        raise InputError(f"no points: {scan} scan{'s' * (scan > 1)}, every point a missing return (0 0 0)",
                         path=src)
    inten = np.concatenate(intensity)
    colors = None
    if any(c is not None for c in colours):
        parts = []
        for c, k in zip(colours, intensity):
            if c is None:
                c = grey_from_intensity(k)
                c = np.full((len(k), 4), 255, dtype=np.uint8) if c is None else c
            parts.append(c)
        colors = np.concatenate(parts)
    else:
        colors = grey_from_intensity(inten)
    return build_cloud(path, np.ascontiguousarray(pos), colors=colors, progress=progress, intensity=inten)
