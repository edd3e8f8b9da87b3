"""PLY reading (binary files of vertex scalars: our chunked reader in
:mod:`splatedit.io._plybinary`; ascii: a vectorised parser; anything else:
plyfile) and writing (our own vectorised binary writer, 32 MB at a time).

Read: ascii, binary little/big endian; any numeric property type.  Vertex
properties used: ``x y z`` (required), ``nx ny nz`` (or ``normal_x ...``),
``red green blue [alpha]`` (or ``r g b a`` / ``diffuse_red ...``; uchar or
float), ``radius``, our ``ux uy uz vx vy vz``, and the scan attributes
``intensity`` and ``classification`` (kept, not turned into colours: a PLY
without colours keeps the default material).  Other properties and
elements are ignored.  A header line ``comment splatedit origin X Y Z`` (our
writer's) is the cloud's local origin when it suits the points
(:func:`splatedit.io._build.local_origin`).  A ``face`` element (``vertex_indices`` or
``vertex_index`` list) makes the file a mesh: polygons are fan-triangulated.

Written file layout (binary little endian by default)::

    comment written by splatedit from NAME
    comment splatedit origin X Y Z                          (if the cloud has a local origin)
    element vertex n
      double x y z            positions, bit-exact
      float  nx ny nz         unit normals, for other tools
      double ux uy uz vx vy vz  splat semi-axes, bit-exact   (axes=True)
      uchar  red green blue alpha                           (if colours)
      ushort intensity, uchar classification                (if the cloud has them)
    element face f
      list uchar int vertex_indices                         (if faces)
"""

from __future__ import annotations

import numpy as np
import plyfile

from splatedit.errors import InputError
from splatedit.io._build import build_cloud, check_finite, colors_from_columns, triangulate
from splatedit.io._plybinary import AXIS_FIELDS, COLOR_FIELDS, NORMAL_FIELDS, read_binary_chunked, scan_columns
from splatedit.io._plycheck import TYPES as _TYPES
from splatedit.io._plycheck import (binary_layout, check_declared_sizes, check_trailing, origin_comment,
                                   stored_origin, warn_trailing)
from splatedit.io._text import scan_numbers
from splatedit.model.cloud import SplatCloud
from splatedit.progress import report
from splatedit.tolerances import PLY_READ_CHUNK_BYTES

_FACE_LISTS = ("vertex_indices", "vertex_index")


def _wrap(exc: Exception, path) -> InputError:
    """A plyfile (or low-level) exception as an InputError naming the file."""
    if isinstance(exc, plyfile.PlyElementParseError):
        msg = exc.message
        if "end-of-file" in msg:
            msg += " (the file is truncated or the header's element count is wrong)"
        return InputError(msg, path=str(path),
                          element=exc.element.name if exc.element is not None else None,
                          row=exc.row, prop=exc.prop.name if exc.prop is not None else None)
    if isinstance(exc, plyfile.PlyHeaderParseError):
        where = f"header line {exc.line}: " if exc.line else "header: "
        return InputError(f"{where}{exc.message}", path=str(path))
    if isinstance(exc, OSError):
        return InputError(f"cannot read file: {exc.strerror or exc}", path=str(path))
    if isinstance(exc, ValueError) and "occurs more than once" in str(exc):
        return InputError(f"header: a property is declared twice ({exc})", path=str(path))
    return InputError(f"malformed PLY file: {exc}", path=str(path))


def read_ply_data(path) -> plyfile.PlyData:
    """The whole PLY file at ``path`` as :class:`plyfile.PlyData` (face lists
    read as triangles); a malformed or unreadable file is an
    :class:`~splatedit.errors.InputError` naming it."""
    known = {"face": {name: 3 for name in _FACE_LISTS}}
    errors = (plyfile.PlyParseError, ValueError, TypeError, UnicodeDecodeError, IndexError,
              EOFError, OSError, MemoryError, OverflowError)
    try:
        try:
            # Triangle meshes: memory-map the faces as an (f, 3) array.
            return plyfile.PlyData.read(str(path), known_list_len=known)
        except plyfile.PlyElementParseError as exc:
            if exc.message != "unexpected list length":
                raise
        return plyfile.PlyData.read(str(path))   # polygons: plyfile reads row by row
    except errors as exc:
        raise _wrap(exc, path) from None


def _column(data, name, path) -> np.ndarray:
    col = data[name]
    if col.dtype.kind not in "iuf":
        raise InputError("is a list property, expected a number", path=str(path),
                         element="vertex", prop=name)
    return col


def _face_lists(ply, path):
    """(flat indices, lengths, property name) of the face element, or None."""
    if "face" not in ply:
        return None
    el = ply["face"]
    names = [p.name for p in el.properties]
    prop = next((nm for nm in _FACE_LISTS if nm in names), None)
    if prop is None:
        raise InputError(f"no vertex index list (expected one of {', '.join(_FACE_LISTS)})",
                         path=str(path), element="face")
    data = el.data[prop]
    if el.count == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), prop
    if data.dtype != object and data.ndim == 2:       # memory-mapped fixed-length lists
        return data.reshape(-1), np.full(len(data), data.shape[1]), prop
    lengths = np.fromiter((len(p) for p in data), dtype=np.int64, count=len(data))
    flat = (np.concatenate([np.asarray(p).ravel() for p in data]) if lengths.sum()
            else np.zeros(0, dtype=np.int64))
    return flat, lengths, prop


def _faces(lists, n_vertices, path):
    if lists is None:
        return None
    flat, lengths, prop = lists
    if flat.dtype.kind not in "iu":
        if not (flat.dtype.kind == "f" and np.all(flat == np.floor(flat))):
            raise InputError("vertex indices are not integers", path=str(path),
                             element="face", prop=prop)
    return triangulate(flat, lengths, n_vertices, str(path), "face", prop)


# ------------------------------------------------------ fast ascii reading

def _add_property(element, name: str, dtype, path) -> None:
    """Append a property to a parsed header element; a name declared twice is
    an error (numpy cannot hold two fields of one name, nor can we pick one)."""
    if any(nm == name for nm, _ in element[2]):
        raise InputError(f"header: property {name!r} is declared twice", path=str(path),
                         element=element[0])
    element[2].append((name, dtype))


def _ascii_layout(data: bytes, path=None):
    """Header of an ascii PLY that the vectorised reader handles: a ``vertex``
    element of scalar properties, optionally followed by a ``face`` element
    whose only property is the index list.  Returns (body offset, header line
    count, vertex count, [(name, dtype)], face count or None, face list name)
    or None for anything else (plyfile then reads the file)."""
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        return None
    nl = data.find(b"\n", end)
    body = len(data) if nl < 0 else nl + 1
    try:
        lines = data[:end].decode("ascii").splitlines()
    except UnicodeDecodeError:
        return None
    elements = []
    fmt = None
    for line in lines[1:]:
        w = line.split()
        if not w or w[0] in ("comment", "obj_info"):
            continue
        if w[0] == "format" and len(w) == 3:
            fmt = w[1]
        elif w[0] == "element" and len(w) == 3 and w[2].isdigit():
            elements.append((w[1], int(w[2]), []))
        elif w[0] == "property" and elements and len(w) == 3 and w[1] in _TYPES:
            _add_property(elements[-1], w[2], _TYPES[w[1]], path)
        elif (w[0] == "property" and elements and len(w) == 5 and w[1] == "list"
              and w[2] in _TYPES and w[3] in _TYPES):
            _add_property(elements[-1], w[4], None, path)
        else:
            return None
    if fmt != "ascii" or not elements or elements[0][0] != "vertex":
        return None
    vname, nv, vprops = elements[0]
    if not vprops or any(t is None for _, t in vprops):
        return None
    if len(elements) == 1:
        return body, data.count(b"\n", 0, body), nv, vprops, None, None
    if len(elements) != 2 or elements[1][0] != "face" or len(elements[1][2]) != 1:
        return None
    fprop, ftype = elements[1][2][0]
    if ftype is not None or fprop not in _FACE_LISTS:
        return None
    return body, data.count(b"\n", 0, body), nv, vprops, elements[1][1], fprop


def _read_ascii_fast(path, progress):
    """Vectorised reading of common ascii PLY files.

    Returns (vertex structured array, face lists or None), or None when the
    file is not of the handled layout or is malformed in any way: plyfile
    then reads it and reports the problem in its own words.
    """
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError:
        return None
    layout = _ascii_layout(data, path)
    if layout is None:
        return None
    body, nhead, nv, vprops, nf, fprop = layout
    if b"#" in data[body:]:
        return None
    try:
        tab = scan_numbers(data[body:], str(path), first_line=nhead + 1, progress=progress)
    except InputError:
        return None
    nf_ = nf or 0
    if len(tab) < nv + nf_ or nv == 0:
        return None
    if len(tab) > nv + nf_:
        warn_trailing(path, f"{len(tab) - nv - nf_} data line(s) from line {int(tab.line[nv + nf_])}",
                       nv, nf)
    npr = len(vprops)
    if np.any(tab.count[:nv] != npr):
        return None
    vals = tab.values[tab.start[0]:tab.start[0] + nv * npr].reshape(nv, npr)
    vert = np.empty(nv, dtype=[(nm, t) for nm, t in vprops])
    for j, (nm, t) in enumerate(vprops):
        col = vals[:, j]
        if t[0] in "iu":
            info = np.iinfo(t)
            if not np.all((col == np.floor(col)) & (col >= info.min) & (col <= info.max)):
                return None
        elif t == "f4":
            over = np.isfinite(col) & (np.abs(col) > np.finfo(np.float32).max)
            if over.any():
                row = int(np.flatnonzero(over)[0])
                raise InputError(f"value {col[row]:.6g} does not fit the declared type float "
                                 f"(float32 holds at most 3.4e+38)", path=str(path),
                                 element="vertex", row=row, prop=nm)
        vert[nm] = col
    if nf is None:
        return vert, None
    fstart, fcount = tab.start[nv:nv + nf], tab.count[nv:nv + nf]
    k = tab.values[fstart] if nf else np.zeros(0)
    if np.any(fcount != k + 1) or np.any(k != np.floor(k)) or np.any(k < 0):
        return None
    k = k.astype(np.int64)
    kstart = np.zeros(nf, dtype=np.int64)
    np.cumsum(k[:-1], out=kstart[1:])
    owner = np.repeat(np.arange(nf), k)
    flat = tab.values[fstart[owner] + 1 + (np.arange(int(k.sum())) - kstart[owner])]
    if np.any(flat != np.floor(flat)):
        return None
    return vert, (flat, k, fprop)


def read_ply(path, *, progress=None) -> SplatCloud:
    """Read a PLY point cloud, splat cloud or mesh.

    Returns:
        SplatCloud (axes from the file or derived, see
        :func:`splatedit.io._build.build_cloud`).
    Raises:
        InputError: naming the file and, where known, element/row/property.
    """
    report(progress, "reading", 0.0)
    check_declared_sizes(path)
    layout = binary_layout(path)
    stored = stored_origin(path)
    if layout is not None:
        return read_binary_chunked(path, layout, progress, stored_origin=stored)
    fast = _read_ascii_fast(path, progress)
    if fast is not None:
        data, face_lists = fast
    else:
        ply = read_ply_data(path)
        if "vertex" not in ply:
            raise InputError("no 'vertex' element", path=str(path))
        check_trailing(path, ply)
        data = ply["vertex"].data
        face_lists = _face_lists(ply, path)
    report(progress, "reading", 0.5)
    names = set(data.dtype.names or ())
    for p in ("x", "y", "z"):
        if p not in names:
            raise InputError(f"missing property {p!r} (need x, y and z)", path=str(path),
                             element="vertex", prop=p)
    if len(data) == 0:
        raise InputError("zero vertices: the file holds no points", path=str(path),
                         element="vertex")
    cols = {p: _column(data, p, path) for p in ("x", "y", "z")}
    normals = radius = u = v = colors = None
    nn = next((t for t in NORMAL_FIELDS if set(t) <= names), None)
    if nn:
        cols.update({p: _column(data, p, path) for p in nn})
    if "radius" in names:
        cols["radius"] = _column(data, "radius", path)
    have_axes = set(AXIS_FIELDS) <= names
    if have_axes:
        cols.update({p: _column(data, p, path) for p in AXIS_FIELDS})
    check_finite(cols, str(path))
    f64 = {k: np.asarray(c, dtype=np.float64) for k, c in cols.items()}
    positions = np.column_stack([f64["x"], f64["y"], f64["z"]])
    if nn:
        normals = np.column_stack([f64[p] for p in nn])
    if "radius" in f64:
        radius = f64["radius"]
    if have_axes:
        u = np.column_stack([f64[p] for p in AXIS_FIELDS[:3]])
        v = np.column_stack([f64[p] for p in AXIS_FIELDS[3:]])
    cn = next((t for t in COLOR_FIELDS if set(t[:3]) <= names), None)
    if cn:
        use = [p for p in cn if p in names]
        colors = colors_from_columns([_column(data, p, path) for p in use], use, str(path))
    faces = _faces(face_lists, len(positions), path)
    intensity, classification = scan_columns(lambda nm: _column(data, nm, path), names, str(path))
    report(progress, "reading", 1.0)
    return build_cloud(path, positions, normals=normals, radius=radius, u=u, v=v,
                       colors=colors, faces=faces, progress=progress, intensity=intensity,
                       classification=classification, stored_origin=stored)


# ----------------------------------------------------------------- writing
def _vertex_dtype(cloud: SplatCloud, axes: bool, byte_order: str) -> np.dtype:
    e = byte_order
    fields = [(p, e + "f8") for p in ("x", "y", "z")]
    if axes:
        fields += [(p, e + "f4") for p in ("nx", "ny", "nz")]
        fields += [(p, e + "f8") for p in AXIS_FIELDS]
    if cloud.colors is not None:
        fields += [(p, "u1") for p in ("red", "green", "blue", "alpha")]
    if cloud.intensity is not None:
        fields.append(("intensity", e + "u2"))
    if cloud.classification is not None:
        fields.append(("classification", "u1"))
    return np.dtype(fields)


def _vertex_array(cloud: SplatCloud, dtype: np.dtype, rows: slice = slice(None)) -> np.ndarray:
    """The vertex records of ``rows`` (a chunk: the writer never holds a
    full copy of a large cloud)."""
    world = cloud.world_positions(rows)
    arr = np.empty(len(world), dtype=dtype)
    if cloud.intensity is not None:
        arr["intensity"] = cloud.intensity[rows]
    if cloud.classification is not None:
        arr["classification"] = cloud.classification[rows]
    for j, p in enumerate("xyz"):
        arr[p] = world[:, j]
    if "ux" in dtype.names:
        u, v = cloud.u[rows], cloud.v[rows]
        nrm = np.cross(u, v)
        nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
        for j, p in enumerate(("nx", "ny", "nz")):
            arr[p] = nrm[:, j]
        for j, p in enumerate(AXIS_FIELDS[:3]):
            arr[p] = u[:, j]
        for j, p in enumerate(AXIS_FIELDS[3:]):
            arr[p] = v[:, j]
    if cloud.colors is not None:
        for j, p in enumerate(("red", "green", "blue", "alpha")):
            arr[p] = cloud.colors[rows, j]
    return arr


_PLY_TYPE = {"f8": "double", "f4": "float", "u1": "uchar", "u2": "ushort", "i4": "int"}


def _header(dtype: np.dtype, n: int, n_faces: int | None, fmt: str, comment: str | None,
            origin=None) -> bytes:
    lines = ["ply", f"format {fmt} 1.0"]
    if comment:
        # PLY headers are ASCII: escape anything else (e.g. a file name like été.ply)
        safe = comment.encode("ascii", "backslashreplace").decode("ascii")
        lines += [f"comment {c}" for c in safe.splitlines()]
    if origin is not None and np.any(origin):
        lines.append(f"comment {origin_comment(origin)}")     # the last one counts when read
    lines.append(f"element vertex {n}")
    for name in dtype.names:
        lines.append(f"property {_PLY_TYPE[dtype[name].str[1:]]} {name}")
    if n_faces is not None:
        lines += [f"element face {n_faces}", "property list uchar int vertex_indices"]
    lines.append("end_header")
    return ("\n".join(lines) + "\n").encode("ascii")


def write_ply(fh, cloud: SplatCloud, *, binary: bool = True, axes: bool = True,
              comment: str | None = None) -> None:
    """Write ``cloud`` as PLY to the open binary file ``fh``.

    Args:
        binary: binary little endian (default) or ascii.  Both are lossless:
            ascii prints doubles with 17 and floats with 9 significant digits.
        axes: write normals and the splat axes ``ux..vz``.  ``axes=False``
            writes only positions, colours and faces ("geometry only"); a
            reader then derives the splats again (from the mesh if there are
            faces).

    Positions are world coordinates; a cloud with a local origin also gets
    the header line ``comment splatedit origin X Y Z``, which the reader
    takes as the origin again (:func:`splatedit.io._build.local_origin`).
    """
    dtype = _vertex_dtype(cloud, axes, "<")
    faces = cloud.faces
    fh.write(_header(dtype, cloud.n, None if faces is None else len(faces),
                     "binary_little_endian" if binary else "ascii", comment, cloud.origin))
    if binary:
        step = max(1, PLY_READ_CHUNK_BYTES // dtype.itemsize)
        for lo in range(0, cloud.n, step):
            fh.write(_vertex_array(cloud, dtype, slice(lo, lo + step)).tobytes())
        if faces is not None:
            fa = np.empty(len(faces), dtype=[("n", "u1"), ("i", "<i4", (3,))])
            fa["n"] = 3
            fa["i"] = faces
            fh.write(fa.tobytes())
        return
    fmt = {"f8": "%.17g", "f4": "%.9g", "u1": "%d", "u2": "%d"}
    np.savetxt(fh, _vertex_array(cloud, dtype), fmt=[fmt[dtype[nm].str[1:]] for nm in dtype.names])
    if faces is not None:
        np.savetxt(fh, faces, fmt="3 %d %d %d")
