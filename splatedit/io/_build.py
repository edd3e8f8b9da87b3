"""Shared by the readers: column checks, colours, polygon triangulation, and
the rule that turns whatever attributes a file has into splats."""

from __future__ import annotations

import contextvars
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Optional

import numpy as np

from splatedit.errors import InputError
from splatedit.model.cloud import SplatCloud, column_bounds
from splatedit.model.tangents import splats_from_normals, usable_normals
from splatedit.tolerances import (MAX_COORDINATE_ABS, MIN_EXTENT_ABS, REBASE_GRID_MIN, REBASE_MIN_ABS,
                                  REBASE_STORED_REACH)


def _located(message, path, element, row, prop, lines=None) -> InputError:
    if lines is not None:
        message = f"{message} (line {int(lines[row])})"
    err = InputError(message, path=path, element=element, row=row, prop=prop)
    if lines is not None:
        err.line = int(lines[row])
    return err


def check_finite(columns: dict, path, element: str = "vertex", lines=None) -> None:
    """Raise InputError naming the first row/property holding NaN, inf or a
    value beyond ``MAX_COORDINATE_ABS`` (1e15) in magnitude.

    Args:
        columns: property name -> (n,) numeric array.
        lines: optional (n,) 1-based file line numbers of the rows (text files).
    """
    first = None
    for name, col in columns.items():
        with np.errstate(invalid="ignore"):
            bad = ~(np.abs(np.asarray(col, dtype=np.float64)) <= MAX_COORDINATE_ABS)
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            if first is None or row < first[0]:
                first = (row, name, col[row])
    if first is not None:
        row, name, val = first
        what = ("value is NaN" if np.isnan(val) else "value is infinite" if np.isinf(val) else
                f"value {float(val):.6g} is beyond the supported magnitude {MAX_COORDINATE_ABS:g} "
                f"(rescale the model)")
        raise _located(what, path, element, row, name, lines)


def colors_from_columns(cols: list, names: list, path, element: str = "vertex",
                        lines=None) -> np.ndarray:
    """RGBA uint8 (n, 4) from 3 or 4 colour columns.

    Integer columns must lie in 0..255.  Float columns in 0..1 are scaled by
    255 and rounded; float columns with values above 1 (some tools write 0..255
    floats) must lie in 0..255 and are rounded.  A missing alpha is 255.
    """
    n = len(cols[0])
    out = np.full((n, 4), 255, dtype=np.uint8)
    for j, (col, name) in enumerate(zip(cols, names)):
        col = np.asarray(col)
        if col.dtype.kind in "iu":
            bad = (col < 0) | (col > 255)
            if bad.any():
                row = int(np.flatnonzero(bad)[0])
                raise _located(f"colour {col[row]} outside 0..255", path, element, row, name, lines)
            out[:, j] = col
            continue
        col = col.astype(np.float64)
        check_finite({name: col}, path, element, lines)
        scale = 255.0 if (len(col) == 0 or col.max() <= 1.0) else 1.0
        bad = (col < 0) | (col > 255.0 / scale)
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise _located(f"colour {col[row]} outside 0..1 (or 0..255)", path, element, row,
                           name, lines)
        out[:, j] = np.rint(col * scale).astype(np.uint8)
    return out


def triangulate(flat, lengths, n_vertices: int, path, element: str = "face",
                prop: str = "vertex_indices", lines=None) -> np.ndarray:
    """Fan-triangulate polygons given as concatenated vertex indices.

    Args:
        flat: (sum(lengths),) integer vertex indices of every polygon in turn.
        lengths: (m,) vertices per polygon (each >= 3).
        n_vertices: number of vertices, for the range check.
    Returns:
        (sum(lengths - 2), 3) int64 triangles ``(p0, p_i, p_{i+1})``, in
        polygon order.
    Raises:
        InputError naming the polygon row with fewer than 3 vertices or an
        index outside 0..n_vertices-1.
    """
    flat = np.asarray(flat)
    lengths = np.asarray(lengths, dtype=np.int64)
    m = len(lengths)
    if m == 0:
        return np.zeros((0, 3), dtype=np.int64)
    short = lengths < 3
    if short.any():
        row = int(np.flatnonzero(short)[0])
        raise _located(f"polygon with {lengths[row]} vertices (need at least 3)", path, element,
                       row, prop, lines)
    off = np.zeros(m, dtype=np.int64)
    np.cumsum(lengths[:-1], out=off[1:])
    # range check on the values as stored (integral floats, uint64): casting
    # first would wrap 1e300 or 2**63 to a negative int64
    bad = ~((flat >= 0) & (flat < n_vertices))
    if bad.any():
        pos = int(np.flatnonzero(bad)[0])
        row = int(np.searchsorted(off, pos, side="right") - 1)
        val = flat[pos]
        shown = f"{float(val):.6g}" if flat.dtype.kind == "f" else str(int(val))
        raise _located(f"vertex index {shown} out of range 0..{n_vertices - 1}", path,
                       element, row, prop, lines)
    flat = flat.astype(np.int64)
    if (lengths == 3).all():
        return flat.reshape(-1, 3)
    ntri = lengths - 2
    face = np.repeat(np.arange(m), ntri)
    tstart = np.zeros(m, dtype=np.int64)
    np.cumsum(ntri[:-1], out=tstart[1:])
    j = np.arange(len(face)) - tstart[face]
    base = off[face]
    return np.stack([flat[base], flat[base + j + 1], flat[base + j + 2]], axis=1)


def origin_grid(lo, hi) -> float:
    """The grid step of :func:`local_origin` for the box ``lo``..``hi``: the
    largest power of two not above its longest side, at least
    ``REBASE_GRID_MIN`` (model units)."""
    side = float(np.max(np.asarray(hi, dtype=np.float64) - np.asarray(lo, dtype=np.float64)))
    if not side > REBASE_GRID_MIN:
        return REBASE_GRID_MIN
    return float(2.0 ** math.floor(math.log2(side)))


def local_origin(positions, bounds=None, stored=None) -> np.ndarray:
    """(3,) float64 origin for the positions (``bounds``: their (min, max), if known).

    The box is the main body's when a few points lie far outside it
    (:func:`body_bounds`; with ``positions`` given).
    Zeros when the box lies within ``REBASE_MIN_ABS`` of 0.  Else
    ``stored`` (the origin a file we wrote carries) when it suits the box
    (:func:`fits_origin`), so a model read, edited, written and read again
    keeps its origin; else the box centre rounded to a multiple of
    :func:`origin_grid` (a power of two between half the longest side and
    that side): local coordinates stay within the longest side of 0, so
    float32 keeps the precision of the extent, and an edit that moves the
    centre by less than its distance to the next half step keeps the origin.
    Grid origins are multiples of a power of two of at least 1, so ``x -
    origin`` and back are exact for the float64 ``x`` of a box small next
    to its distance from 0 (ulp(x) divides the origin, and the local value,
    a multiple of ulp(x) smaller than x, needs no more bits)."""
    lo, hi = column_bounds(positions) if bounds is None else bounds
    if max(np.abs(lo).max(), np.abs(hi).max()) <= REBASE_MIN_ABS:
        return np.zeros(3)
    if positions is not None:
        lo, hi = body_bounds(positions, (lo, hi))
        if max(np.abs(lo).max(), np.abs(hi).max()) <= REBASE_MIN_ABS:
            return np.zeros(3)
    if stored is not None and fits_origin(stored, lo, hi):
        return np.array(stored, dtype=np.float64)
    step = origin_grid(lo, hi)
    return np.round(0.5 * (lo + hi) / step) * step


def fits_origin(origin, lo, hi) -> bool:
    """True when ``origin`` (3,) is finite and the box ``lo``..``hi`` lies
    within ``REBASE_STORED_REACH`` times its longest side (at least
    ``REBASE_GRID_MIN``) of it: its local coordinates then lose at most one
    bit of float32 precision against the grid origin's."""
    o = np.asarray(origin, dtype=np.float64)
    if o.shape != (3,) or not (np.abs(o) <= MAX_COORDINATE_ABS).all():
        return False
    side = max(float(np.max(hi - lo)), REBASE_GRID_MIN)
    return bool(max(np.abs(lo - o).max(), np.abs(hi - o).max()) <= REBASE_STORED_REACH * side)


def rebase(positions, origin) -> np.ndarray:
    """``positions - origin``, in place when ``positions`` is a writeable
    float64 array (the readers' own), to keep the peak memory down."""
    if not origin.any():
        return positions
    if not (isinstance(positions, np.ndarray) and positions.dtype == np.float64
            and positions.flags.writeable and positions.ndim == 2):
        positions = np.array(positions, dtype=np.float64)
    # block by block against the origin repeated per row: a (3,) row broadcast
    # over (n, 3) runs numpy's length-3 inner loop n times, 3-4x slower
    step = 1 << 16
    rows = np.tile(np.asarray(origin, dtype=np.float64), (min(len(positions), step), 1))
    for lo in range(0, len(positions), step):
        blk = positions[lo:lo + step]
        np.subtract(blk, rows[:len(blk)], out=blk)
    return positions


#: set by :func:`columns_only`: :func:`build_cloud` returns the columns it was given
_COLUMNS_ONLY = contextvars.ContextVar("splatedit_columns_only", default=False)


@dataclass
class PointColumns:
    """What a reader found in a file, before any splat is derived (see
    :func:`splatedit.io.read_columns`): positions relative to ``origin``
    and whichever optional columns the file had (None where it had none).

    Attributes:
        source: the path the cloud will name (``file.e57#2`` for one scan).
        positions: (n, 3) float64, model units, relative to ``origin``.
        origin: (3,) float64 world offset (``world = positions + origin``).
        normals, u, v: (n, 3) float64 or None; radius: (n,) float64 or None.
        colors: (n, 4) uint8 or None; faces: (f, 3) int64 or None;
        intensity, classification, quantization, point_fields: the scanner
        attributes of :class:`SplatCloud`.
    """

    source: str
    positions: np.ndarray
    origin: np.ndarray
    normals: Optional[np.ndarray] = None
    radius: Optional[np.ndarray] = None
    u: Optional[np.ndarray] = None
    v: Optional[np.ndarray] = None
    colors: Optional[np.ndarray] = None
    faces: Optional[np.ndarray] = None
    intensity: Optional[np.ndarray] = None
    classification: Optional[np.ndarray] = None
    quantization: Optional[object] = None
    point_fields: Optional[dict] = None

    @property
    def n(self) -> int:
        return len(self.positions)

    def needs_estimation(self) -> bool:
        """True when :func:`build_cloud` would derive splats from neighbours
        (rules 4 and 5: no splat axes, no faces, not both normals and radii)."""
        if self.u is not None and self.v is not None:
            return False
        if self.faces is not None:
            return False
        return not (self.normals is not None and self.radius is not None and usable_normals(self.normals))

    def with_axes(self, u, v) -> "PointColumns":
        """A copy whose splat axes are ``u``, ``v`` ((n, 3) float64, model units)."""
        return replace(self, u=np.asarray(u, dtype=np.float64), v=np.asarray(v, dtype=np.float64))

    @classmethod
    def of_cloud(cls, cloud: SplatCloud) -> "PointColumns":
        """The columns of a cloud that was read whole (a Gaussian scene's proxy splats)."""
        return cls(cloud.source or cloud.name, cloud.positions, np.asarray(cloud.origin, dtype=np.float64),
                   u=cloud.u, v=cloud.v, colors=cloud.colors, faces=cloud.faces, intensity=cloud.intensity,
                   classification=cloud.classification, quantization=cloud.quantization,
                   point_fields=cloud.point_fields)


class columns_only:
    """Context manager: inside it :func:`build_cloud` returns a
    :class:`PointColumns` instead of deriving splats (every reader ends in it)."""

    def __enter__(self):
        self._token = _COLUMNS_ONLY.set(True)
        return self

    def __exit__(self, *exc):
        _COLUMNS_ONLY.reset(self._token)
        return False


def cloud_from_columns(cols: PointColumns, *, progress=None) -> SplatCloud:
    """:func:`build_cloud` of columns read by :func:`columns_only` (the same rule)."""
    return build_cloud(cols.source, cols.positions, normals=cols.normals, radius=cols.radius, u=cols.u,
                       v=cols.v, colors=cols.colors, faces=cols.faces, progress=progress,
                       origin=np.asarray(cols.origin, dtype=np.float64), already_local=True,
                       intensity=cols.intensity, classification=cols.classification,
                       quantization=cols.quantization, point_fields=cols.point_fields)


def check_extent(lo, hi, path) -> None:
    """Refuse a model whose bounding box ``lo``..``hi`` ((3,) each) is
    positive but below ``MIN_EXTENT_ABS`` across: its squared distances
    underflow float64, so sizes, normals and framing come out as nonsense
    (a sphere 1e-300 across rendered as rings with exit 0).  All points in
    one place (extent 0) stay valid: a single splat."""
    side = float(np.max(np.asarray(hi, dtype=np.float64) - np.asarray(lo, dtype=np.float64)))
    if 0.0 < side < MIN_EXTENT_ABS:
        raise InputError(f"the model is {side:.3g} across, below the smallest supported extent "
                         f"{MIN_EXTENT_ABS:g} (rescale the model)", path=str(path))


def body_bounds(positions, bounds):
    """The box the local origin is chosen for: ``bounds`` (the full box of
    ``positions``, (lo, hi)) when it lies within ``REBASE_MIN_ABS`` of 0,
    else the main body's box (:func:`splatedit.model.extent.framing_extent`).
    One glitch point 1e9 away moved the origin of a scan near 0 to 5e8: the
    main body's splats then sat at 5e8 in local coordinates, too coarse for
    float32 and refused as degenerate; a UTM scan with a glitch at (0, 0, 0)
    is rebased onto the scan, not between the two."""
    lo, hi = bounds
    if max(np.abs(lo).max(), np.abs(hi).max()) <= REBASE_MIN_ABS:
        return bounds
    from splatedit.model.extent import framing_extent
    ext = framing_extent(positions)
    return (ext.lo, ext.hi) if ext.robust else bounds


def build_cloud(path, positions, *, normals=None, radius=None, u=None, v=None, colors=None,
                faces=None, progress=None, origin=None, already_local=False, intensity=None,
                classification=None, quantization=None, point_fields=None,
                stored_origin=None) -> SplatCloud:
    """Apply the axes rule (first match wins):

    1. ``u`` and ``v`` given (our ``ux..vz`` properties): used as they are;
    2. normals and radius: a tangent frame of that radius;
    3. faces: vertex splats of the mesh (:func:`cloud_from_mesh`), using the
       file's normals where present;
    4. normals only: sized from the neighbour spacing;
    5. nothing: normals estimated, oriented and sized
       (:func:`estimate_splats`).

    Faces are kept in every case.  Positions are first rebased (in place) to
    ``origin``, by default :func:`local_origin` of the positions and the
    file's ``stored_origin`` (``already_local``: the
    reader did that, as the LAS reader does on the file's integer grid); ``intensity``, ``classification`` and
    ``quantization`` are stored with the cloud.
    """
    name, source = Path(path).name, str(path)
    if len(positions) == 0:
        raise InputError("zero vertices: the file holds no points", path=source, element="vertex")
    bounds = column_bounds(positions)
    check_extent(*bounds, path)
    if origin is None:
        origin = local_origin(positions, bounds=bounds, stored=stored_origin)
    if not already_local:
        positions = rebase(positions, origin)
    scan = dict(origin=origin, intensity=intensity, classification=classification,
                quantization=quantization, point_fields=point_fields)
    if faces is not None and len(faces) == 0:
        faces = None
    if _COLUMNS_ONLY.get():
        return PointColumns(source, positions, np.asarray(origin, dtype=np.float64), normals=normals,
                            radius=radius, u=u, v=v, colors=colors, faces=faces, **{
                                k: scan[k] for k in ("intensity", "classification", "quantization",
                                                     "point_fields")})
    if u is not None and v is not None:
        # every reader checks its columns (check_finite) before calling here
        return SplatCloud(positions, u, v, colors, faces, name=name, source=source,
                          values_checked=True, **scan)
    if radius is not None:
        bad = ~(radius > 0)
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise InputError(f"radius must be > 0, got {radius[row]}", path=source,
                             element="vertex", row=row, prop="radius")
    if normals is not None and radius is not None and usable_normals(normals):
        # the file says where the surface faces and how large each splat is:
        # discs straight from that, no neighbour search (no scipy import)
        cloud = splats_from_normals(positions, normals, radius, colors, faces, name=name, source=source,
                                    progress=progress)
        return _with_scan_fields(cloud, scan, origin)
    # estimation needs scipy (0.5-1 s to import): readers of files that carry
    # their splats, and `info`'s lean path, never load it
    from splatedit.model.estimate import estimate_splats
    from splatedit.model.mesh import cloud_from_mesh
    if faces is not None and not (normals is not None and radius is not None):
        cloud = cloud_from_mesh(positions, faces, normals=normals, colors=colors, name=name,
                                source=source, progress=progress)
    else:
        cloud = estimate_splats(positions, normals, colors, progress, radius=radius, faces=faces,
                                name=name, source=source)
    return _with_scan_fields(cloud, scan, origin)


def _with_scan_fields(cloud: SplatCloud, scan: dict, origin) -> SplatCloud:
    """``cloud`` with the reader's origin and scan attributes set (validated)."""
    if origin.any() or any(scan[k] is not None for k in ("intensity", "classification", "quantization",
                                                         "point_fields")):
        for k, val in scan.items():
            setattr(cloud, k, val)
        cloud.validate()
    return cloud
