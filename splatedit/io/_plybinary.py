"""Binary PLY at scan scale: the body is read through a
``PLY_READ_CHUNK_BYTES`` buffer and each chunk, viewed as a structured array
with the header's dtype (``np.frombuffer``), is checked and converted into
the arrays kept; also the ``intensity`` / ``classification`` columns shared
with the plyfile path.  Used by :func:`splatedit.io.ply.read_ply`."""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from splatedit.errors import InputError
from splatedit.io._build import build_cloud, check_finite, colors_from_columns, local_origin
from splatedit.io._plycheck import warn_trailing
from splatedit.model.cloud import SplatCloud, column_bounds
from splatedit.progress import report
from splatedit.tolerances import MAX_COORDINATE_ABS, PLY_READ_CHUNK_BYTES

#: the property names of a normal, per naming convention (first match wins)
NORMAL_FIELDS = (("nx", "ny", "nz"), ("normal_x", "normal_y", "normal_z"))
#: the property names of a colour (RGB + alpha), per naming convention
COLOR_FIELDS = (("red", "green", "blue", "alpha"), ("diffuse_red", "diffuse_green", "diffuse_blue",
                                               "diffuse_alpha"), ("r", "g", "b", "a"))
#: the property names of a splat's two tangent axes (splatedit's splat PLY)
AXIS_FIELDS = ("ux", "uy", "uz", "vx", "vy", "vz")

# --------------------------------------------------- scan attributes

def scan_columns(get, names, src):
    """(intensity uint16 or None, classification uint8 or None) from the
    ``intensity`` and ``classification`` vertex properties (rounded, clipped
    to their types' ranges; NaN is an error naming the row)."""
    out = []
    for nm, top, dt in (("intensity", 65535, np.uint16), ("classification", 255, np.uint8)):
        if nm not in names:
            out.append(None)
            continue
        col = get(nm)
        if col.dtype.kind == "f":
            check_finite({nm: col}, src)
            col = np.rint(col)
        out.append(np.clip(col, 0, top).astype(dt))
    return out


# --------------------------------------------------- fast binary reading

def _shift_row(exc: InputError, lo: int) -> InputError:
    """``exc`` (raised on a chunk) with its row made absolute."""
    if exc.row is None:
        return exc
    return InputError(exc.reason, path=exc.path, element=exc.element, row=exc.row + lo,
                      prop=exc.prop)


def columns_view(buf, dtype, names, rows: int):
    """(rows, k) view of ``k`` consecutive fields of one type in the record
    buffer (one strided copy instead of k), or None when they are not
    laid out that way."""
    first = dtype.fields[names[0]]
    t, off = first[0], first[1]
    for j, nm in enumerate(names):
        f = dtype.fields[nm]
        if f[0] != t or f[1] != off + j * t.itemsize:
            return None
    return np.ndarray((rows, len(names)), dtype=t, buffer=buf, offset=off,
                      strides=(dtype.itemsize, t.itemsize))


def body_chunks(path, layout):
    """Read the vertex rows of a binary PLY (``layout`` from
    :func:`splatedit.io._plycheck.binary_layout`) through one buffer of at
    most ``PLY_READ_CHUNK_BYTES`` (and at most an eighth of the file: small
    next to the arrays kept at any size).

    Yields:
        (lo, hi, buf): rows ``lo..hi`` of the body in ``buf`` (reused: view
        it, e.g. ``np.frombuffer(buf, dtype, hi - lo)``, before the next step).
    Raises:
        InputError: the file cannot be opened, or ends before the declared rows.
    Warns:
        InputWarning: bytes after the declared rows.
    """
    body, n, dtype = layout
    src = str(path)
    size = dtype.itemsize
    rows = max(1, min(PLY_READ_CHUNK_BYTES // size, max(4096, -(-n // 8))))
    buf = bytearray(min(rows, n) * size)
    try:
        fh = open(path, "rb")
    except OSError as exc:
        raise InputError(f"cannot read file: {exc.strerror or exc}", path=src) from None
    with fh:
        total = os.fstat(fh.fileno()).st_size
        fh.seek(body)
        for lo in range(0, n, rows):
            hi = min(n, lo + rows)
            want = (hi - lo) * size
            got = 0
            with memoryview(buf) as mv:
                while got < want:
                    k = fh.readinto(mv[got:want])
                    if not k:
                        break
                    got += k
            if got < want:
                raise InputError("early end-of-file (the file is truncated or the header's "
                                 "element count is wrong)", path=src, element="vertex",
                                 row=lo + got // size)
            yield lo, hi, buf
    extra = total - body - n * size
    if extra > 0:
        warn_trailing(path, f"{extra} byte(s)", n, None)


def in_range(arr) -> bool:
    """True when every value of ``arr`` is finite and at most
    ``MAX_COORDINATE_ABS`` in magnitude (NaN propagates through max/min: one
    test per block, the per-column search only when it fails)."""
    return bool(arr.max() <= MAX_COORDINATE_ABS and arr.min() >= -MAX_COORDINATE_ABS)


def grow_bounds(blk, lo_b, hi_b) -> bool:
    """Widen the running bounds ``lo_b``/``hi_b`` (3,) by the (m, 3) block;
    True when the block is :func:`in_range`."""
    bmin, bmax = column_bounds(blk)
    np.minimum(lo_b, bmin, out=lo_b)
    np.maximum(hi_b, bmax, out=hi_b)
    return bool(bmax.max() <= MAX_COORDINATE_ABS and bmin.min() >= -MAX_COORDINATE_ABS)


@dataclass(frozen=True)
class VertexColumns:
    """Which vertex properties of a binary PLY a reader uses.

    Attributes:
        names: every property name of the vertex element.
        normals: the normal triple found (``nx ny nz`` or ``normal_x ...``) or None.
        axes: the file has our splat axes ``ux .. vz``.
        colors: the colour properties found (3 or 4 names, possibly none).
        int_colors: the colour properties are integers (else floats).
        checked: the properties checked for NaN / magnitude.
    """
    names: frozenset
    normals: tuple | None
    axes: bool
    colors: list
    int_colors: bool
    checked: list


def vertex_columns(layout, src: str) -> VertexColumns:
    """:class:`VertexColumns` of a :func:`~splatedit.io._plycheck.binary_layout`.

    Raises:
        InputError: no ``x y z`` or zero vertices.
    """
    _, n, dtype = layout
    names = frozenset(dtype.names)
    for p in ("x", "y", "z"):
        if p not in names:
            raise InputError(f"missing property {p!r} (need x, y and z)", path=src,
                             element="vertex", prop=p)
    if n == 0:
        raise InputError("zero vertices: the file holds no points", path=src, element="vertex")
    nn = next((t for t in NORMAL_FIELDS if set(t) <= names), None)
    have_axes = set(AXIS_FIELDS) <= names
    cn = next((t for t in COLOR_FIELDS if set(t[:3]) <= names), None)
    use_c = [p for p in cn if p in names] if cn else []
    checked = ["x", "y", "z"] + list(nn or ()) + (["radius"] if "radius" in names else []) \
        + (list(AXIS_FIELDS) if have_axes else [])
    return VertexColumns(names, nn, have_axes, use_c, all(dtype[p].kind in "iu" for p in use_c),
                         checked)


def read_binary_chunked(path, layout, progress, stored_origin=None) -> SplatCloud:
    """Read a binary PLY holding only a vertex element of scalars (any
    types, either byte order) through a ``PLY_READ_CHUNK_BYTES`` buffer:
    each chunk is viewed as a structured array (``np.frombuffer`` with the
    header's dtype), checked and converted into the arrays kept.  No
    per-splat Python, no full-size temporary copy; the normals are not kept
    when the file has our splat axes (they are ``u x v``).  ``stored_origin``:
    the origin the header carries, if any (:func:`local_origin`)."""
    _, n, dtype = layout
    src = str(path)
    spec = vertex_columns(layout, src)
    names, nn, have_axes, use_c = spec.names, spec.normals, spec.axes, spec.colors
    out = {"positions": (np.empty((n, 3)), ("x", "y", "z"))}
    if have_axes:
        out["u"] = (np.empty((n, 3)), AXIS_FIELDS[:3])
        out["v"] = (np.empty((n, 3)), AXIS_FIELDS[3:])
    elif nn:
        out["normals"] = (np.empty((n, 3)), nn)
    if "radius" in names and not have_axes:
        out["radius"] = (np.empty((n, 1)), ("radius",))
    scan_cols = [p for p in ("intensity", "classification") if p in names]
    raw_s = {p: np.empty(n, dtype=dtype[p]) for p in scan_cols}
    colors = raw_c = None
    if use_c and spec.int_colors:
        colors = np.full((n, 4), 255, dtype=np.uint8)
    elif use_c:
        raw_c = np.empty((n, len(use_c)), dtype=np.result_type(*[dtype[p] for p in use_c]))
    lo_b, hi_b = np.full(3, np.inf), np.full(3, -np.inf)
    for lo, hi, buf in body_chunks(path, layout):
        rec = np.frombuffer(buf, dtype=dtype, count=hi - lo)
        ok = True
        for key, (arr, cols) in out.items():
            view = columns_view(buf, dtype, cols, hi - lo)
            blk = arr[lo:hi]
            if view is not None:
                blk[...] = view
            else:
                for j, p in enumerate(cols):
                    blk[:, j] = rec[p]
            if key == "positions":        # per column: the bounds come with the test
                ok = grow_bounds(blk, lo_b, hi_b) and ok
            else:
                ok = ok and in_range(blk)
        if have_axes and nn:        # normals not kept, still checked
            ok = ok and all(in_range(rec[p]) for p in nn)
        try:
            if not ok:
                check_finite({p: rec[p] for p in spec.checked}, src)
            if colors is not None:
                colors[lo:hi] = colors_from_columns([rec[p] for p in use_c], use_c, src)
        except InputError as exc:
            raise _shift_row(exc, lo) from None
        if raw_c is not None:
            for j, p in enumerate(use_c):
                raw_c[lo:hi, j] = rec[p]
        for p, arr in raw_s.items():
            arr[lo:hi] = rec[p]
        del rec
        report(progress, "reading", 0.5 * hi / n)
    if raw_c is not None:
        colors = colors_from_columns(list(raw_c.T), use_c, src)
        del raw_c
    report(progress, "reading", 1.0)
    get = {k: a for k, (a, _) in out.items()}
    radius = get["radius"][:, 0] if "radius" in get else None
    intensity, classification = scan_columns(raw_s.__getitem__, raw_s, src)
    del raw_s
    return build_cloud(path, get["positions"], normals=get.get("normals"), radius=radius,
                       u=get.get("u"), v=get.get("v"), colors=colors, progress=progress,
                       origin=local_origin(get["positions"], bounds=(lo_b, hi_b), stored=stored_origin),
                       intensity=intensity, classification=classification)
