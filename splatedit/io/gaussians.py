"""3D / 2D Gaussian Splatting PLY files (the format of Kerbl et al. 2023's reference code).

A PLY file is a Gaussian scene when its ``vertex`` element has ``f_dc_0`` or
both ``scale_0`` and ``rot_0``; such a file must then have all of::

    x y z                       centres
    [nx ny nz]                  optional (the reference writes zeros)
    f_dc_0 f_dc_1 f_dc_2        SH band 0 (RGB)
    f_rest_0 .. f_rest_{N-1}    SH bands 1..d, channel-major; N = 0, 9, 24 or 45 (d = 0..3)
    opacity                     logit of the opacity
    scale_0 scale_1 [scale_2]   natural log of the standard deviations (2 scales: 2DGS)
    rot_0 rot_1 rot_2 rot_3     quaternion, w first, not necessarily unit

Any other vertex property is kept (with its type and place) and written back.
Other elements (3DGS files have none) are ignored and not written.  The body is read as one structured numpy array (plyfile; binary
files are memory-mapped), never row by row.  Writing is binary little endian
with the file's own property order and types, so read -> write -> read is bit
for bit when nothing was edited.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import plyfile

from splatedit.errors import InputError
from splatedit.io._plycheck import check_declared_sizes, read_head
from splatedit.model.gaussians import GaussianCloud, GaussianKind

_DC = ("f_dc_0", "f_dc_1", "f_dc_2")
_ROT = ("rot_0", "rot_1", "rot_2", "rot_3")
_NORMALS = ("nx", "ny", "nz")
_REST = re.compile(r"f_rest_(\d+)$")
#: number of f_rest_* properties -> SH degree
REST_COUNTS = {0: 0, 9: 1, 24: 2, 45: 3}
_PLY_TYPE = {"i1": "char", "u1": "uchar", "i2": "short", "u2": "ushort", "i4": "int",
             "u4": "uint", "f4": "float", "f8": "double"}


def _vertex_header(path) -> list[str] | None:
    """Scalar property names of the first ``vertex`` element of a PLY header, or
    None when the file is not a PLY (or its header cannot be parsed here)."""
    head = read_head(path)
    if head is None:
        return None
    names, in_vertex = [], False
    for line in head.lines():
        w = line.split()
        if len(w) == 3 and w[0] == "element":
            if in_vertex:
                break
            in_vertex = w[1] == "vertex"
        elif in_vertex and len(w) >= 3 and w[0] == "property":
            names.append(w[-1])
    return names


def is_gaussian_ply(path) -> bool:
    """True when ``path`` is a PLY whose vertex element looks like a Gaussian
    scene (``f_dc_0``, or ``scale_0`` and ``rot_0``); plain splat PLYs are False."""
    names = _vertex_header(path)
    if not names:
        return False
    s = set(names)
    return "f_dc_0" in s or {"scale_0", "rot_0"} <= s


def _fail(path, prop, msg, row=None) -> InputError:
    return InputError(msg, path=str(path), element="vertex", prop=prop, row=row)


def _f32(data, name, path) -> np.ndarray:
    col = data[name]
    if col.dtype.kind != "f":
        raise _fail(path, name, f"has type {col.dtype}, expected a float")
    bad = ~np.isfinite(col)
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        raise _fail(path, name, f"non-finite value {col[row]}", row=row)
    return col


def _stack(data, names, path) -> np.ndarray:
    """(n, len(names)) float32 columns (float64 files are rounded: the
    in-memory contract is float32)."""
    out = np.empty((len(data), len(names)), dtype=np.float32)
    for j, nm in enumerate(names):
        out[:, j] = _f32(data, nm, path)
    return out


def read_gaussian_ply(path, *, progress=None) -> GaussianCloud:
    """Read a 3DGS or 2DGS PLY.

    Returns:
        GaussianCloud with ``layout`` = the file's vertex properties.
    Raises:
        InputError: naming the file and the property (and row) at fault.
    """
    from splatedit.io.ply import read_ply_data
    from splatedit.progress import report
    report(progress, "reading", 0.0)
    check_declared_sizes(path)
    ply = read_ply_data(path)
    if "vertex" not in ply:
        raise InputError("no 'vertex' element", path=str(path))
    el = ply["vertex"]
    data = el.data
    names = list(data.dtype.names or ())
    for p in el.properties:
        if isinstance(p, plyfile.PlyListProperty):
            raise _fail(path, p.name, "is a list property; a Gaussian scene has scalar properties only")
    if len(data) == 0:
        raise InputError("zero vertices: the file holds no Gaussians", path=str(path), element="vertex")
    have = set(names)
    n_scales = 3 if "scale_2" in have else 2
    required = ["x", "y", "z", *_DC, "opacity", *[f"scale_{i}" for i in range(n_scales)], *_ROT]
    for p in required:
        if p not in have:
            raise _fail(path, p, f"missing property {p!r}: a Gaussian splatting PLY needs "
                        "x y z, f_dc_0..2, opacity, scale_0..1 or 0..2 and rot_0..3")
    rest = sorted(int(m.group(1)) for nm in names if (m := _REST.match(nm)))
    if len(rest) not in REST_COUNTS or rest != list(range(len(rest))):
        missing = sorted(set(range(max(rest) + 1)) - set(rest)) if rest else []
        what = (f"f_rest_{missing[0]} is missing" if missing else
                f"{len(rest)} f_rest_* properties, expected 0, 9, 24 or 45 (SH degree 0..3)")
        raise _fail(path, f"f_rest_{missing[0]}" if missing else "f_rest_0", what)
    report(progress, "reading", 0.5)
    # float64 holds float32 (and double) centres exactly
    pos = np.column_stack([np.asarray(_f32(data, p, path), dtype=np.float64) for p in "xyz"])
    n = len(data)
    deg = REST_COUNTS[len(rest)]
    nk = (deg + 1) ** 2
    sh = np.empty((n, nk, 3), dtype=np.float32)
    sh[:, 0, :] = _stack(data, _DC, path)
    if nk > 1:
        flat = _stack(data, [f"f_rest_{i}" for i in range(len(rest))], path)
        sh[:, 1:, :] = flat.reshape(n, 3, nk - 1).transpose(0, 2, 1)
    rot = _stack(data, _ROT, path)
    zero = ~(np.abs(rot).max(axis=1) > 0)
    if zero.any():
        row = int(np.flatnonzero(zero)[0])
        raise _fail(path, "rot_0", "zero quaternion (rot_0..3 all 0): no rotation", row=row)
    normals = _stack(data, _NORMALS, path) if set(_NORMALS) <= have else None
    known = set(required) | {f"f_rest_{i}" for i in rest} | (set(_NORMALS) if normals is not None else set())
    extra = {nm: np.array(data[nm]) for nm in names if nm not in known}
    layout = tuple((nm, data.dtype[nm].newbyteorder("<").str) for nm in names)
    report(progress, "reading", 1.0)
    scene = GaussianCloud(
        positions=pos, log_scales=_stack(data, [f"scale_{i}" for i in range(n_scales)], path),
        rotations=rot, opacity_logits=_stack(data, ("opacity",), path)[:, 0], sh=sh,
        normals=normals, extra=extra,
        kind=GaussianKind.GS3D if n_scales == 3 else GaussianKind.GS2D,
        name=Path(path).name, source=str(path), layout=layout)
    check_gaussian_values(scene, str(path))
    return scene


def check_gaussian_values(g: GaussianCloud, path) -> None:
    """The one validation of a Gaussian scene's values, shared by every
    command (``info`` accepted a scene at 1e20 that ``render`` refused):
    centres within ``MAX_COORDINATE_ABS`` (property ``x``/``y``/``z``), the
    proxy disc's semi-axes (``GAUSSIAN_PROXY_SIGMAS`` standard deviations)
    too (property ``scale_j``, the file's own name, not the proxy's ``u``),
    and an extent of at least ``MIN_EXTENT_ABS`` unless all centres
    coincide.

    Raises:
        InputError: naming the file, row and property.
    """
    import math
    from splatedit.io._build import check_extent, check_finite
    from splatedit.model.cloud import column_bounds
    from splatedit.tolerances import GAUSSIAN_PROXY_SIGMAS, MAX_COORDINATE_ABS
    check_finite({p: g.positions[:, j] for j, p in enumerate("xyz")}, path)
    limit = math.log(MAX_COORDINATE_ABS / GAUSSIAN_PROXY_SIGMAS)
    big = g.log_scales > limit
    if big.any():
        row, j = (int(v[0]) for v in np.nonzero(big))
        v = float(g.log_scales[row, j])
        raise _fail(path, f"scale_{j}", f"log-scale {v:.6g} is a standard deviation of "
                    f"{math.exp(min(v, 709.0)):.3g}, beyond the supported magnitude "
                    f"{MAX_COORDINATE_ABS:g} at {GAUSSIAN_PROXY_SIGMAS:g} sigma (rescale the scene)",
                    row=row)
    check_extent(*column_bounds(g.positions), path)


def standard_layout(g: GaussianCloud) -> tuple[tuple[str, str], ...]:
    """The reference implementation's property order (all float32), then ``g.extra``."""
    nk = g.sh.shape[1]
    names = ["x", "y", "z"] + (list(_NORMALS) if g.normals is not None else [])
    names += list(_DC) + [f"f_rest_{i}" for i in range(3 * (nk - 1))] + ["opacity"]
    names += [f"scale_{i}" for i in range(g.log_scales.shape[1])] + list(_ROT)
    out = [(nm, "<f4") for nm in names]
    out += [(nm, np.asarray(a).dtype.newbyteorder("<").str) for nm, a in g.extra.items()]
    return tuple(out)


def _columns(g: GaussianCloud) -> dict[str, np.ndarray]:
    """Every property's (n,) column by name."""
    n, nk = len(g), g.sh.shape[1]
    cols = {p: g.positions[:, j] for j, p in enumerate("xyz")}
    if g.normals is not None:
        cols.update({p: g.normals[:, j] for j, p in enumerate(_NORMALS)})
    cols.update({p: g.sh[:, 0, j] for j, p in enumerate(_DC)})
    if nk > 1:
        flat = g.sh[:, 1:, :].transpose(0, 2, 1).reshape(n, 3 * (nk - 1))
        cols.update({f"f_rest_{i}": flat[:, i] for i in range(flat.shape[1])})
    cols["opacity"] = g.opacity_logits
    cols.update({f"scale_{i}": g.log_scales[:, i] for i in range(g.log_scales.shape[1])})
    cols.update({p: g.rotations[:, j] for j, p in enumerate(_ROT)})
    cols.update(g.extra)
    return cols


def check_gaussians(g: GaussianCloud) -> None:
    """Raise :class:`InputError` (naming the property and row) when a scene
    cannot be written: shapes that disagree, non-finite values, zero quaternions."""
    n = len(g)
    src = g.source
    nk = g.sh.shape[1] if g.sh.ndim == 3 else -1
    if n == 0:
        raise InputError("no Gaussians", path=src)
    if g.sh.ndim != 3 or g.sh.shape[0] != n or g.sh.shape[2] != 3 or nk not in (1, 4, 9, 16):
        raise InputError(f"sh has shape {g.sh.shape}, expected ({n}, 1|4|9|16, 3)", path=src, prop="sh")
    for nm, a, shape in (("log_scales", g.log_scales, (n, 3 if g.kind == GaussianKind.GS3D else 2)),
                         ("rotations", g.rotations, (n, 4)), ("opacity_logits", g.opacity_logits, (n,)),
                         ("positions", g.positions, (n, 3))):
        if a.shape != shape:
            raise InputError(f"has shape {a.shape}, expected {shape}", path=src, prop=nm)
    for nm, col in _columns(g).items():
        if len(col) != n:
            raise InputError(f"has {len(col)} rows, expected {n}", path=src, prop=nm)
        if col.dtype.kind == "f":
            bad = ~np.isfinite(col)
            if bad.any():
                row = int(np.flatnonzero(bad)[0])
                raise InputError(f"non-finite value {col[row]}", path=src, element="vertex",
                                 row=row, prop=nm)
    zero = ~(np.abs(g.rotations).max(axis=1) > 0)
    if zero.any():
        raise InputError("zero quaternion", path=src, element="vertex",
                         row=int(np.flatnonzero(zero)[0]), prop="rot_0")
    check_gaussian_values(g, src)


def gaussian_vertex_array(g: GaussianCloud) -> np.ndarray:
    """The (n,) structured little-endian vertex array in ``g.layout`` order (or
    :func:`standard_layout` when the scene has none, or when its arrays no
    longer match that layout, e.g. a changed SH degree)."""
    cols = _columns(g)
    layout = g.layout
    if layout is None or {nm for nm, _ in layout} != set(cols):
        layout = standard_layout(g)
    arr = np.empty(len(g), dtype=[(nm, t) for nm, t in layout])
    for nm, _ in layout:
        arr[nm] = cols[nm]
    return arr


def write_gaussian_ply(fh, g: GaussianCloud, *, comment: str | None = None) -> None:
    """Write ``g`` as a binary little-endian Gaussian PLY to the open binary file ``fh``."""
    check_gaussians(g)
    vert = gaussian_vertex_array(g)
    lines = ["ply", "format binary_little_endian 1.0"]
    if comment:
        safe = comment.encode("ascii", "backslashreplace").decode("ascii")
        lines += [f"comment {c}" for c in safe.splitlines()]
    lines.append(f"element vertex {len(vert)}")
    for nm in vert.dtype.names:
        code = vert.dtype[nm].str[1:]
        if code not in _PLY_TYPE:
            raise InputError(f"property type {vert.dtype[nm]} has no PLY equivalent", path=g.source, prop=nm)
        lines.append(f"property {_PLY_TYPE[code]} {nm}")
    lines.append("end_header")
    fh.write(("\n".join(lines) + "\n").encode("ascii"))
    fh.write(vert.tobytes())

