"""Checks of a PLY file against its header's element counts: data after
the declared rows (a warning) and counts needing far more data than the file
holds (an error before any parsing allocates for them)."""

from __future__ import annotations

import os
import warnings
from typing import NamedTuple

import numpy as np
import plyfile

from splatedit.errors import InputError, InputWarning
from splatedit.tolerances import PLY_DECLARED_EXCESS_BYTES

#: PLY scalar type names -> numpy dtype codes
TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2",
          "int16": "i2", "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4",
          "uint": "u4", "uint32": "u4", "float": "f4", "float32": "f4", "double": "f8",
          "float64": "f8"}


#: how much of a file the header scans read: headers are a few hundred bytes
HEADER_SCAN_BYTES = 1 << 16


class PlyHead(NamedTuple):
    """The start of a PLY file (:func:`read_head`)."""
    #: the first HEADER_SCAN_BYTES of the file
    data: bytes
    #: offset of ``end_header``
    end: int
    #: offset of the body (after the newline ending ``end_header``); -1 when there is none
    body: int
    #: file size in bytes
    size: int

    def lines(self, errors: str = "replace") -> list[str]:
        """The header lines before ``end_header``, ``ply`` first (UnicodeDecodeError
        with ``errors="strict"`` for a header that is not ASCII)."""
        return self.data[:self.end].decode("ascii", errors).splitlines()


def read_head(path) -> PlyHead | None:
    """The header of ``path``, or None when the file cannot be read or does
    not start with ``ply`` and hold ``end_header`` in its first HEADER_SCAN_BYTES."""
    try:
        with open(path, "rb") as fh:
            data = fh.read(HEADER_SCAN_BYTES)
            size = os.fstat(fh.fileno()).st_size
    except OSError:
        return None
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        return None
    nl = data.find(b"\n", end)
    return PlyHead(data, end, -1 if nl < 0 else nl + 1, size)


#: the header comment of a PLY we write that carries the cloud's origin:
#: ``comment splatedit origin X Y Z`` (17 significant digits: exact)
ORIGIN_COMMENT = "splatedit origin"


def origin_comment(origin) -> str:
    """The comment text (without ``comment``) that stores ``origin`` (3,)."""
    return ORIGIN_COMMENT + " " + " ".join(f"{float(x):.17g}" for x in origin)


def stored_origin(path) -> np.ndarray | None:
    """(3,) float64 origin of a PLY header's last ``comment splatedit origin
    X Y Z`` line, or None (no such line, or not three finite numbers).
    Whether it suits the data is :func:`splatedit.io._build.local_origin`'s
    decision."""
    head = read_head(path)
    if head is None:
        return None
    found = None
    for line in head.lines():
        w = line.split()
        if len(w) == 6 and w[0] == "comment" and " ".join(w[1:3]) == ORIGIN_COMMENT:
            try:
                found = np.array([float(x) for x in w[3:]])
            except ValueError:
                continue
    return found if found is not None and np.isfinite(found).all() else None


def warn_trailing(path, what: str, nv: int, nf: int | None) -> None:
    """Warn (``InputWarning``) that rows after the header's counts (``nv`` vertices, ``nf`` faces) were ignored."""
    counts = f"'vertex {nv}'" + ("" if nf is None else f" and 'face {nf}'")
    warnings.warn(InputWarning(f"{path}: {what} after the rows the header declares ({counts}) "
                               f"were ignored: is a count in the header wrong?"), stacklevel=3)


def check_trailing(path, ply: plyfile.PlyData) -> None:
    """Warn when a file read by plyfile holds data after its declared rows
    (plyfile stops at the declared counts and says nothing)."""
    try:
        with open(path, "rb") as fh:
            data = fh.read(1 << 20) if not ply.text else fh.read()   # binary: the header only
            total = os.fstat(fh.fileno()).st_size
    except OSError:
        return
    end = data.find(b"end_header")
    nl = data.find(b"\n", end)
    if end < 0 or nl < 0:
        return
    body = data[nl + 1:]
    nv = ply["vertex"].count if "vertex" in ply else 0
    nf = ply["face"].count if "face" in ply else None
    if ply.text:
        rows = sum(el.count for el in ply.elements)
        lines = [i for i, ln in enumerate(body.split(b"\n")) if ln.strip()]
        if len(lines) > rows:
            first = data.count(b"\n", 0, nl + 1) + lines[rows] + 1
            warn_trailing(path, f"{len(lines) - rows} data line(s) from line {first}", nv, nf)
        return
    size = 0
    for el in ply.elements:
        for prop in el.properties:
            col = el.data[prop.name]
            if isinstance(prop, plyfile.PlyListProperty):
                items = (col.size if col.dtype != object
                         else sum(len(r) for r in col))
                size += (el.count * np.dtype(prop.len_dtype).itemsize
                         + items * np.dtype(prop.val_dtype).itemsize)
            else:
                size += el.count * np.dtype(prop.val_dtype).itemsize
    if total - (nl + 1) > size:
        warn_trailing(path, f"{total - (nl + 1) - size} byte(s)", nv, nf)


_SIZES = {"i1": 1, "u1": 1, "i2": 2, "u2": 2, "i4": 4, "u4": 4, "f4": 4, "f8": 8}


def check_declared_sizes(path) -> None:
    """Refuse a header whose element counts need more bytes than the file
    holds, before any parsing allocates for them (a 188-byte file declaring
    400,000,000 faces took 26 s and 3.2 GB to fail).  The least a row can
    take: ascii, one character and a separator per scalar property and per
    list length; binary, the scalar sizes and the list length fields.
    Headers this cannot parse are left to plyfile."""
    head = read_head(path)
    if head is None or head.body < 0:
        return
    fmt, elements = None, []
    for line in head.lines()[1:]:
        w = line.split()
        if len(w) >= 2 and w[0] == "format":
            fmt = w[1]
        elif len(w) == 3 and w[0] == "element" and w[2].isdigit():
            elements.append([w[1], int(w[2]), 0])
        elif elements and len(w) == 3 and w[0] == "property" and w[1] in TYPES:
            elements[-1][2] += 2 if fmt == "ascii" else _SIZES[TYPES[w[1]]]
        elif elements and len(w) == 5 and w[0] == "property" and w[1] == "list" and w[2] in TYPES:
            elements[-1][2] += 2 if fmt == "ascii" else _SIZES[TYPES[w[2]]]
    body = head.size - head.body
    need = 0
    for name, count, row in elements:
        need += count * row
        # small shortfalls are left to the parser, which names the row where the data end
        if need > body and need - body > PLY_DECLARED_EXCESS_BYTES:
            raise InputError(f"header declares {count} rows of element {name!r}, at least "
                             f"{need} bytes of data, but the file has {body} bytes after its "
                             f"header (truncated, or a wrong count)", path=str(path), element=name)


def binary_layout(path):
    """Header of a binary PLY whose first element is ``vertex`` with scalar
    properties only and that has no other element, for the chunked reader.

    Returns (body offset, vertex count, numpy structured dtype with the file's
    byte order) or None for anything else (ascii, lists, faces, more
    elements, a header this cannot parse: plyfile then reads the file and
    reports problems in its own words).  A property declared twice raises
    :class:`InputError`.
    """
    head = read_head(path)
    if head is None or head.body < 0 or head.data[head.end:head.body].strip() != b"end_header":
        return None
    try:
        lines = head.lines("strict")
    except UnicodeDecodeError:
        return None
    fmt, elements = None, []
    for line in lines[1:]:
        w = line.split()
        if not w or w[0] in ("comment", "obj_info"):
            continue
        if w[0] == "format" and len(w) == 3 and w[2] == "1.0":
            fmt = w[1]
        elif w[0] == "element" and len(w) == 3 and w[2].isdigit():
            elements.append((w[1], int(w[2]), []))
        elif w[0] == "property" and elements and len(w) == 3 and w[1] in TYPES:
            if any(nm == w[2] for nm, _ in elements[-1][2]):
                raise InputError(f"header: property {w[2]!r} is declared twice", path=str(path),
                                 element=elements[-1][0])
            elements[-1][2].append((w[2], TYPES[w[1]]))
        else:
            return None
    order = {"binary_little_endian": "<", "binary_big_endian": ">"}.get(fmt)
    if order is None or len(elements) != 1 or elements[0][0] != "vertex" or not elements[0][2]:
        return None
    dtype = np.dtype([(nm, order + code) for nm, code in elements[0][2]])
    return head.body, elements[0][1], dtype
