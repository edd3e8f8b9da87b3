"""PCD (Point Cloud Library) files: ``DATA ascii`` and ``DATA binary``.

Read: fields ``x y z`` (required), ``normal_x normal_y normal_z``, ``rgb`` /
``rgba`` (packed into one 4-byte float or uint, as PCL writes them),
``intensity``; other fields are skipped.  ``DATA binary_compressed`` (LZF)
is refused with a clear message (convert with ``pcl_convert_pcd_ascii_binary``).
Points with a NaN coordinate (PCL's "invalid" points of organised clouds)
are dropped with a warning giving their number; any other NaN or infinity
is an error naming the row.

Write: ``DATA binary``, ``x y z`` as F8 (world coordinates, exact),
``normal_x..z`` F4, ``rgb`` packed U4 when the cloud has colours,
``intensity`` U2 when it has intensities.
"""

from __future__ import annotations

import warnings

import numpy as np

from splatedit.errors import InputError, InputWarning
from splatedit.io._build import build_cloud, check_finite
from splatedit.io._text import scan_numbers
from splatedit.io.las import grey_from_intensity
from splatedit.model.cloud import SplatCloud

_KEYS = ("VERSION", "FIELDS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT", "VIEWPOINT", "POINTS", "DATA")


#: fields read as one value per point (a COUNT above 1 is refused for them)
_SCALAR_FIELDS = ("x", "y", "z", "normal_x", "normal_y", "normal_z", "rgb", "rgba", "intensity")


def _header(data: bytes, src: str):
    """Parse and validate a PCD header (every field list of one length, names
    unique, POINTS, SIZE and COUNT non-negative integers, one value per point
    for the fields read, a row no larger than the file).

    Returns:
        (field names, row dtype, POINTS, DATA kind, body offset, header lines)
    """
    fields = {}
    pos = 0
    line_no = 0
    while "DATA" not in fields:
        nl = data.find(b"\n", pos)
        if nl < 0:
            raise InputError("header: no DATA line (not a PCD file, or truncated)", path=src)
        line_no += 1
        line = data[pos:nl].decode("ascii", "replace").strip()
        pos = nl + 1
        if not line or line.startswith("#"):
            continue
        w = line.split()
        if w[0] not in _KEYS:
            raise InputError(f"header line {line_no}: unknown keyword {w[0]!r}", path=src)
        if w[0] in fields:
            raise InputError(f"header line {line_no}: {w[0]} given twice", path=src)
        fields[w[0]] = w[1:]
    for k in ("FIELDS", "SIZE", "TYPE", "POINTS"):
        if k not in fields:
            raise InputError(f"header: no {k} line", path=src)
    names = fields["FIELDS"]
    if not names:
        raise InputError("header: FIELDS lists no field", path=src)
    count = fields.get("COUNT", ["1"] * len(names))
    if not (len(fields["SIZE"]) == len(fields["TYPE"]) == len(count) == len(names)):
        raise InputError("header: FIELDS, SIZE, TYPE and COUNT differ in length", path=src)
    seen = set()
    for nm in names:
        if nm != "_" and nm in seen:
            raise InputError(f"header: field {nm!r} is listed twice in FIELDS", path=src)
        seen.add(nm)
    try:
        if len(fields["POINTS"]) != 1:
            raise ValueError
        npts = int(fields["POINTS"][0])
        sizes = [int(s) for s in fields["SIZE"]]
        counts = [int(c) for c in count]
    except ValueError:
        raise InputError("header: POINTS, SIZE and COUNT must be integers", path=src) from None
    if npts < 0:
        raise InputError(f"header: POINTS {npts} is negative", path=src)
    row_bytes = 0
    for nm, c, sz in zip(names, counts, sizes):
        if c < 1 or (nm in _SCALAR_FIELDS and c != 1):
            raise InputError(f"header: field {nm!r} has COUNT {c} (must be "
                             f"{'1' if nm in _SCALAR_FIELDS else 'at least 1'})", path=src)
        row_bytes += c * max(sz, 1)
    if row_bytes > len(data):
        raise InputError(f"header: a row of {row_bytes} bytes (SIZE times COUNT) cannot fit in a file "
                         f"of {len(data)} bytes", path=src)
    dt = []
    for nm, t, sz, c in zip(names, fields["TYPE"], sizes, counts):
        code = {"F": "f", "I": "i", "U": "u"}.get(t)
        if code is None or sz not in (1, 2, 4, 8) or (code == "f" and sz < 4):
            raise InputError(f"header: field {nm!r} has unsupported TYPE {t} SIZE {sz}", path=src)
        dt.append((nm if nm != "_" else f"_pad{len(dt)}", f"<{code}{sz}", (c,) if c > 1 else ()))
    kind = fields["DATA"][0] if fields["DATA"] else ""
    return names, np.dtype(dt), npts, kind, pos, line_no


def _unpack_rgb(col) -> np.ndarray:
    """(n, 4) uint8 RGBA from PCL's packed 4-byte rgb (0x00RRGGBB as float bits or uint)."""
    packed = np.ascontiguousarray(col).view(np.uint32) if col.dtype.itemsize == 4 else \
        np.asarray(col, dtype=np.uint32)
    out = np.empty((len(packed), 4), dtype=np.uint8)
    out[:, 0] = (packed >> 16) & 0xFF
    out[:, 1] = (packed >> 8) & 0xFF
    out[:, 2] = packed & 0xFF
    out[:, 3] = 255
    return out


def read_pcd(path, *, progress=None) -> SplatCloud:
    """Read a PCD file (see the module docstring)."""
    src = str(path)
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as exc:
        raise InputError(f"cannot read file: {exc.strerror or exc}", path=src) from None
    names, dtype, n, kind, body, nhead = _header(data, src)
    if n == 0:
        raise InputError("zero points: POINTS is 0", path=src)
    if "x" not in names or "y" not in names or "z" not in names:
        raise InputError("missing field x, y or z", path=src)
    if kind == "binary_compressed":
        raise InputError("DATA binary_compressed (LZF) is not supported; save the cloud as "
                         "binary or ascii PCD (e.g. pcl_convert_pcd_ascii_binary)", path=src)
    if kind == "binary":
        need = n * dtype.itemsize
        if len(data) - body < need:
            row = (len(data) - body) // dtype.itemsize
            raise InputError(f"early end-of-file: POINTS says {n} but the data hold {row} rows "
                             f"(the file is truncated or POINTS is wrong)", path=src, row=row)
        if len(data) - body > need:
            warnings.warn(InputWarning(f"{src}: {len(data) - body - need} byte(s) after the {n} points "
                                       f"POINTS declares were ignored"), stacklevel=3)
        rec = np.frombuffer(data, dtype=dtype, count=n, offset=body)
    elif kind == "ascii":
        tab = scan_numbers(data[body:], src, first_line=nhead + 1, progress=progress)
        width = sum(int(np.prod(dtype[i].shape)) or 1 for i in range(len(dtype)))
        if len(tab) < n:
            raise InputError(f"early end-of-file: {len(tab)} data lines but POINTS says {n} "
                             f"(truncated, or POINTS is wrong)", path=src)
        if len(tab) > n:
            warnings.warn(InputWarning(f"{src}: {len(tab) - n} data line(s) from line {tab.line[n]} "
                                       f"after the {n} points POINTS declares were ignored"),
                          stacklevel=3)
        bad = tab.count[:n] != width
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise InputError(f"expected {width} numbers, got {tab.count[row]} "
                             f"(line {tab.line[row]})", path=src, row=row)
        vals = tab.values[tab.start[0]:tab.start[0] + n * width].reshape(n, width)
        rec = np.empty(n, dtype=dtype)
        col = 0
        for nm in dtype.names:
            w = int(np.prod(dtype[nm].shape)) or 1
            if nm == "rgb" or nm == "rgba":      # written as the float or int of the packed bits
                v = vals[:, col]
                rec[nm] = (v.astype(np.float32) if dtype[nm].kind == "f" else v.astype(np.uint32))
            else:
                v = vals[:, col:col + w]
                kind_nm = dtype[nm].base
                if kind_nm.kind in "iu":
                    info = np.iinfo(kind_nm)
                    bad = ~((v >= info.min) & (v <= info.max))
                    if bad.any():
                        row = int(np.flatnonzero(bad.any(axis=1))[0])
                        raise InputError(f"value {v[row][bad[row]][0]:g} does not fit the declared "
                                         f"type {kind_nm} (line {tab.line[row]})", path=src, row=row,
                                         prop=nm)
                rec[nm] = v.reshape(rec[nm].shape)
            col += w
    else:
        raise InputError(f"header: DATA {kind!r} (expected ascii or binary)", path=src)
    invalid = np.isnan(rec["x"]) | np.isnan(rec["y"]) | np.isnan(rec["z"])
    if invalid.any():                   # PCL's organised clouds mark missing returns so
        warnings.warn(InputWarning(f"{src}: {int(invalid.sum())} of {n} points have NaN "
                                   f"coordinates (PCL's invalid points) and were dropped"),
                      stacklevel=3)
        rec = rec[~invalid]
        n = len(rec)
    if n == 0:
        raise InputError("zero points: the file holds no (valid) points", path=src)
    cols = {p: rec[p] for p in ("x", "y", "z")}
    has_n = {"normal_x", "normal_y", "normal_z"} <= set(names)
    if has_n:
        cols.update({p: rec[p] for p in ("normal_x", "normal_y", "normal_z")})
    check_finite(cols, src, element=None)
    positions = np.column_stack([np.asarray(rec[p], dtype=np.float64) for p in "xyz"])
    normals = (np.column_stack([np.asarray(rec[p], dtype=np.float64)
                                for p in ("normal_x", "normal_y", "normal_z")]) if has_n else None)
    intensity = None
    if "intensity" in names:
        raw = np.asarray(rec["intensity"], dtype=np.float64)
        if raw.size and raw.max() <= 1.0:      # PCL often stores 0..1 floats
            raw = raw * 65535.0
        intensity = np.clip(np.rint(raw), 0, 65535).astype(np.uint16)
    colors = None
    cname = "rgb" if "rgb" in names else "rgba" if "rgba" in names else None
    if cname:
        colors = _unpack_rgb(rec[cname])
    elif intensity is not None:
        colors = grey_from_intensity(intensity)
    return build_cloud(path, positions, normals=normals, colors=colors, progress=progress,
                       intensity=intensity)


def write_pcd(fh, cloud: SplatCloud) -> None:
    """Write ``cloud`` as binary PCD (see the module docstring)."""
    fields = [("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("normal_x", "<f4"),
              ("normal_y", "<f4"), ("normal_z", "<f4")]
    if cloud.colors is not None:
        fields.append(("rgb", "<u4"))
    if cloud.intensity is not None:
        fields.append(("intensity", "<u2"))
    arr = np.empty(cloud.n, dtype=fields)
    world = cloud.world_positions()
    nrm = cloud.normals
    for j, p in enumerate("xyz"):
        arr[p] = world[:, j]
        arr["normal_" + p] = nrm[:, j]
    if cloud.colors is not None:
        c = cloud.colors.astype(np.uint32)
        arr["rgb"] = (c[:, 0] << 16) | (c[:, 1] << 8) | c[:, 2]
    if cloud.intensity is not None:
        arr["intensity"] = cloud.intensity
    names = [f for f, _ in fields]
    head = ["# .PCD v0.7 - written by splatedit", "VERSION 0.7", "FIELDS " + " ".join(names),
            "SIZE " + " ".join(t[2] for _, t in fields),
            "TYPE " + " ".join({"f": "F", "u": "U"}[t[1]] for _, t in fields),
            "COUNT " + " ".join("1" for _ in fields), f"WIDTH {cloud.n}", "HEIGHT 1",
            "VIEWPOINT 0 0 0 1 0 0 0", f"POINTS {cloud.n}", "DATA binary"]
    fh.write(("\n".join(head) + "\n").encode("ascii"))
    fh.write(arr.tobytes())
