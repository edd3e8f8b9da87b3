"""LAS and LAZ airborne/terrestrial LiDAR files (laspy, LAZ through lazrs).

Read: x y z (the file's 32-bit integers times ``scale`` plus ``offset``),
16-bit RGB (point formats 2, 3, 5, 7, 8, 10) as 8-bit colours (the high
byte), ``intensity`` (uint16) and ``classification``.  Files without RGB get
grey colours from the intensity (linear, the 99.5th percentile white).  The
other dimensions (GPS time, return numbers, scan angle, user data, point
source, extra bytes, ...) are kept in ``SplatCloud.point_fields`` and
written back by the LAS writer (same point format; extra bytes with their
types).  Normals and splat sizes are estimated (LAS has none).

Far coordinates are rebased to an origin on the file's own integer grid:
``origin = offset + X0 * scale``, the local coordinates are ``(X - X0) *
scale``, so writing back with the same scale and offset gives back the same
integers.  ``X0`` is 0 (the origin is the offset) when the offset suits the
points (:func:`splatedit.io._build.fits_origin`: within twice their longest
side), as in every file splatedit writes (a cloud not read from LAS is
written with its origin as the offset); else the grid origin of
:func:`splatedit.io._build.local_origin` moved onto the file's grid.  A cloud
written back (same scale and offset) is read with the same origin: the
offset again, or the same grid point unless an edit moved the box centre
across half a grid step.

Write: point format 3 (RGB) when the cloud has colours of its own, else 1,
LAS 1.2; formats 7 / 6 and LAS 1.4 when the source file was LAS 1.4-style
(format 6 or above) or a class is above 31 (1.2 holds 5-bit classes); the scale and offset of the file the cloud was read from, else
0.001 and the origin.  Colours are written as 16-bit ``c * 257``.
"""

from __future__ import annotations

import numpy as np

import os
import struct
import warnings

from splatedit.errors import InputError, InputWarning
from splatedit.io._build import build_cloud, fits_origin, local_origin
from splatedit.io._guard import RecordingStream, library_call
from splatedit.model.cloud import Quantization, SplatCloud, column_bounds
from splatedit.progress import report
from splatedit.tolerances import (LAS_DEFAULT_SCALE, LAS_MIN_SCALE, LAZ_MAX_POINTS_PER_BYTE,
                                  MAX_COORDINATE_ABS, REBASE_MIN_ABS)

_RGB_FORMATS = (2, 3, 5, 7, 8, 10)


def grey_from_intensity(intensity: np.ndarray) -> np.ndarray | None:
    """(n, 4) uint8 grey RGBA from (n,) intensities: linear, 0 black, the
    99.5th percentile and above white (a few bright returns would otherwise
    leave everything else dark).  None when every intensity is 0 (LAS
    always has the field; a writer without intensities leaves it 0): the
    default material then, not a black cloud."""
    if not intensity.any():
        return None
    hi = float(np.percentile(intensity, 99.5)) if len(intensity) else 0.0
    g = np.clip(intensity.astype(np.float32) * (255.0 / max(hi, 1.0)), 0, 255)
    out = np.empty((len(intensity), 4), dtype=np.uint8)
    out[:, :3] = np.rint(g)[:, None]
    out[:, 3] = 255
    return out


def grid_origin(world_lo, world_hi, scale, offset) -> np.ndarray:
    """(3,) float64 the origin :func:`read_las` gives a LAS file whose points
    span ``world_lo``..``world_hi`` (file units) on the grid ``scale`` /
    ``offset``: zeros for a file near 0, else ``offset + X0 * scale`` (see
    the module docstring).  The out-of-core COPC path gives a region of a
    file the origin of the whole file this way."""
    world_lo, world_hi = np.asarray(world_lo, float), np.asarray(world_hi, float)
    if max(np.abs(world_lo).max(), np.abs(world_hi).max()) <= REBASE_MIN_ABS:
        return np.zeros(3)
    scale, offset = np.asarray(scale, float), np.asarray(offset, float)
    return offset + _origin_step(world_lo, world_hi, scale, offset) * scale


def _origin_step(world_lo, world_hi, scale, offset) -> np.ndarray:
    """(3,) int64 ``X0`` of the origin ``offset + X0 * scale`` of a far
    LAS file (world box ``world_lo``..``world_hi``): 0, the offset itself,
    when it suits the box (:func:`fits_origin`; files we write carry the
    origin there), else the grid point of :func:`local_origin` moved onto the
    file's integer grid."""
    if fits_origin(offset, world_lo, world_hi):
        return np.zeros(3, dtype=np.int64)
    grid = local_origin(None, bounds=(world_lo, world_hi))
    return np.round((grid - offset) / scale).astype(np.int64)


#: bytes of a point record of each LAS point format (0..10), the least a
#: record length may be (extra bytes come on top)
_RECORD_BYTES = (20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67)
#: LAS public header fields up to the offsets (the part every version has)
_HEADER = struct.Struct("<4s H H 16s B B 32s 32s H H H I I B H I 5I 3d 3d 6d")


def check_las_header(path) -> int:
    """Validate the public header of a LAS/LAZ file against the file itself,
    before laspy reads it (laspy trusts the header: 'LASF' and random bytes
    made it allocate without end).

    Checks: the signature and a complete header; header size, point-data
    offset and the variable-length-record count within the file; a known
    point format whose record length holds its fields; finite offsets and
    finite scales of at least ``LAS_MIN_SCALE`` in magnitude (a scale of 0
    collapses the cloud onto one point); the point count against the bytes
    there are: an uncompressed file must hold exactly that many records
    (fewer: an error, as a truncated PLY; more: an :class:`InputWarning`,
    as PLY's rows after the declared count), a LAZ file at most
    ``LAZ_MAX_POINTS_PER_BYTE`` points per byte of point data.

    Returns:
        the number of points the header declares.
    Raises:
        InputError: naming the file and the header field at fault.
    """
    src = str(path)
    try:
        size = os.stat(path).st_size
        with open(path, "rb") as fh:
            head = fh.read(375)
    except OSError as exc:
        raise InputError(f"cannot read file: {exc.strerror or exc}", path=src) from None
    if head[:4] != b"LASF":
        raise InputError("not a LAS/LAZ file (no 'LASF' signature)", path=src)
    if len(head) < _HEADER.size:
        raise InputError(f"truncated LAS header: {len(head)} bytes, a header has at least "
                         f"{_HEADER.size}", path=src)
    f = _HEADER.unpack_from(head)
    major, minor = f[4], f[5]
    header_size, data_offset, n_vlr, fmt_byte, rec_len, legacy_count = f[10:16]
    scale, offset = np.array(f[21:24]), np.array(f[24:27])
    if major != 1 or minor > 4:
        raise InputError(f"header: unsupported LAS version {major}.{minor}", path=src)
    if not _HEADER.size <= header_size <= data_offset <= size:
        raise InputError(f"header: header size {header_size} and point data offset {data_offset} "
                         f"do not fit a file of {size} bytes", path=src)
    if n_vlr * 54 > data_offset - header_size:
        raise InputError(f"header: {n_vlr} variable-length records do not fit in the "
                         f"{data_offset - header_size} bytes before the points", path=src)
    compressed = bool(fmt_byte & 0xC0)
    fmt = fmt_byte & 0x3F
    if fmt >= len(_RECORD_BYTES):
        raise InputError(f"header: unknown point format {fmt}", path=src)
    if rec_len < _RECORD_BYTES[fmt]:
        raise InputError(f"header: point record length {rec_len} is below the {_RECORD_BYTES[fmt]} "
                         f"bytes of point format {fmt}", path=src)
    for name, vals in (("scale", scale), ("offset", offset)):
        bad = ~np.isfinite(vals)
        if bad.any():
            j = int(np.flatnonzero(bad)[0])
            raise InputError(f"header: {'xyz'[j]} {name} is {vals[j]} (must be finite)", path=src)
    if (np.abs(scale) < LAS_MIN_SCALE).any():
        j = int(np.flatnonzero(np.abs(scale) < LAS_MIN_SCALE)[0])
        raise InputError(f"header: {'xyz'[j]} scale {scale[j]:g} is degenerate (it must be at least "
                         f"{LAS_MIN_SCALE:g} in magnitude; 0 puts every point in one place)", path=src)
    if (np.abs(scale) > MAX_COORDINATE_ABS).any():
        j = int(np.argmax(np.abs(scale)))
        raise InputError(f"header: {'xyz'[j]} scale {scale[j]:g} is beyond the supported magnitude "
                         f"{MAX_COORDINATE_ABS:g}", path=src)
    if (np.abs(offset) > MAX_COORDINATE_ABS).any():
        j = int(np.argmax(np.abs(offset)))
        raise InputError(f"header: {'xyz'[j]} offset {offset[j]:g} is beyond the supported magnitude "
                         f"{MAX_COORDINATE_ABS:g}", path=src)
    count = legacy_count
    end = size
    if minor >= 4 and len(head) >= 255:
        first_evlr, n_evlr, count14 = struct.unpack_from("<Q I Q", head, 235)
        count = count14 or legacy_count
        if n_evlr:
            _check_evlrs(path, first_evlr, n_evlr, data_offset, size, src)
            end = first_evlr
    body = end - data_offset
    if compressed:
        if count > max(body, 1) * LAZ_MAX_POINTS_PER_BYTE:
            raise InputError(f"header: {count} points cannot be compressed into {body} bytes "
                             f"(the count is wrong or the file is truncated)", path=src)
        _check_laszip_vlr(path, header_size, n_vlr, data_offset, count, src)
        _check_chunk_table(path, data_offset, size, src)
        return count
    records = body // rec_len
    if count > records:
        raise InputError(f"early end-of-file: the header says {count} points but the file holds "
                         f"{records} point records (truncated, or the count is wrong)", path=src)
    if records > count:
        warnings.warn(InputWarning(f"{src}: {records - count} point record(s) after the {count} the "
                                   f"header declares were ignored"), stacklevel=3)
    return count


def _check_evlrs(path, first: int, count: int, data_offset: int, size: int, src: str) -> None:
    """LAS 1.4 extended variable-length records: they must start after the
    point data offset and each (60-byte header plus its 64-bit length) end
    within the file; laspy reads each length in one piece."""
    if not data_offset <= first <= size or count * 60 > size - first:
        raise InputError(f"header: {count} extended variable-length records from byte {first} do not "
                         f"fit a file of {size} bytes", path=src)
    pos = first
    try:
        with open(path, "rb") as fh:
            for i in range(count):
                fh.seek(pos + 20)
                (length,) = struct.unpack("<Q", fh.read(8))
                pos += 60 + length
                if pos > size:
                    raise InputError(f"extended variable-length record {i}: {length} bytes do not fit "
                                     f"a file of {size} bytes", path=src)
    except (OSError, struct.error):
        raise InputError("cannot read the extended variable-length records (truncated?)",
                         path=src) from None


#: the chunk size of a LAZ file whose chunks vary in size
_VARIABLE_CHUNKS = 0xFFFFFFFF


def _check_laszip_vlr(path, header_size: int, n_vlr: int, data_offset: int, count: int, src: str) -> None:
    """The 'laszip encoded' record of a LAZ file: its points per chunk, for
    which lazrs allocates a buffer, may not exceed the file's points (or
    laszip's default 50,000): a damaged chunk size of 5.3e8 aborted the
    process (a failed allocation)."""
    pos = header_size
    try:
        with open(path, "rb") as fh:
            for _ in range(n_vlr):
                fh.seek(pos)
                head = fh.read(54)
                if len(head) < 54:
                    break
                _, user, rec_id, length = struct.unpack_from("<H16sHH", head)
                if user.rstrip(b"\0") == b"laszip encoded" and rec_id == 22204 and length >= 20:
                    (chunk,) = struct.unpack("<I", fh.read(20)[12:16])
                    if chunk != _VARIABLE_CHUNKS and chunk > max(count, 50_000):
                        raise InputError(f"LAZ record: {chunk} points per chunk for {count} points: "
                                         f"the file is damaged", path=src)
                    return
                pos += 54 + length
                if pos > data_offset:
                    break
    except OSError as exc:
        raise InputError(f"cannot read file: {exc.strerror or exc}", path=src) from None
    raise InputError("a LAZ file without its 'laszip encoded' record (damaged, or not LAZ)", path=src)


def _check_chunk_table(path, data_offset: int, size: int, src: str) -> None:
    """A LAZ file's point data start with the offset of its chunk table (or
    -1 for none); the table starts with a version and the number of chunks,
    for which lazrs allocates 16 bytes each: a damaged count (1.4e9 chunks
    in an 891-byte file) aborted the process (a failed 21 GB allocation).
    Every chunk takes at least one byte of the data before the table."""
    try:
        with open(path, "rb") as fh:
            fh.seek(data_offset)
            raw = fh.read(8)
            if len(raw) < 8:
                raise InputError("truncated LAZ data: no chunk table offset", path=src)
            (table,) = struct.unpack("<q", raw)
            if table == -1:
                return
            if not data_offset + 8 <= table <= size - 8:
                raise InputError(f"LAZ chunk table offset {table} lies outside the point data "
                                 f"({data_offset + 8}..{size - 8}): the file is truncated or damaged",
                                 path=src)
            fh.seek(table)
            _, chunks = struct.unpack("<II", fh.read(8))
    except OSError as exc:
        raise InputError(f"cannot read file: {exc.strerror or exc}", path=src) from None
    if chunks > table - data_offset - 8 + 1:
        raise InputError(f"LAZ chunk table declares {chunks} chunks in {table - data_offset - 8} bytes "
                         f"of point data: the file is truncated or damaged", path=src)


def read_las(path, *, progress=None) -> SplatCloud:
    """Read a ``.las`` or ``.laz`` file (see the module docstring; the header is
    checked first by :func:`check_las_header`)."""
    src = str(path)
    report(progress, "reading", 0.0)
    declared = check_las_header(path)
    if declared == 0:
        raise InputError("zero points: the file holds no points", path=src)
    with library_call(src, "not a readable LAS/LAZ file"):
        import laspy
        las = laspy.read(src)
    n = len(las.points)
    if n != declared:
        raise InputError(f"the header says {declared} points but {n} were decoded "
                         f"(truncated, or the count is wrong)", path=src)
    scale = np.asarray(las.header.scales, dtype=np.float64)
    offset = np.asarray(las.header.offsets, dtype=np.float64)
    ints = np.empty((n, 3), dtype=np.int64)
    for j, d in enumerate("XYZ"):
        ints[:, j] = las[d]
    lo_i, hi_i = column_bounds(ints)
    world_lo, world_hi = lo_i * scale + offset, hi_i * scale + offset
    for world in (world_lo, world_hi):
        if (np.abs(world) > MAX_COORDINATE_ABS).any():
            j = int(np.argmax(np.abs(world)))
            raise InputError(f"{'xyz'[j]} coordinate {world[j]:g} (integers times scale plus offset) "
                             f"is beyond the supported magnitude {MAX_COORDINATE_ABS:g}", path=src)
    if max(np.abs(world_lo).max(), np.abs(world_hi).max()) > REBASE_MIN_ABS:
        ref = _origin_step(world_lo, world_hi, scale, offset)
        origin = offset + ref * scale
        ints -= ref
        positions = ints.astype(np.float64)
        positions *= scale
    else:
        origin = np.zeros(3)
        positions = ints.astype(np.float64)
        positions *= scale
        positions += offset
    del ints
    names = set(las.point_format.dimension_names)
    intensity = np.asarray(las.intensity, dtype=np.uint16) if "intensity" in names else None
    classification = (np.asarray(las.classification, dtype=np.uint8)
                      if "classification" in names else None)
    colors = None
    if {"red", "green", "blue"} <= names:
        rgb = np.column_stack([np.asarray(las[c]) for c in ("red", "green", "blue")])
        # 16-bit per the standard; some writers store 8-bit values
        shift = 8 if rgb.max() > 255 else 0
        colors = np.full((n, 4), 255, dtype=np.uint8)
        colors[:, :3] = rgb >> shift
    elif intensity is not None:
        colors = grey_from_intensity(intensity)
    quant = Quantization(tuple(scale.tolist()), tuple(offset.tolist()),
                         int(las.header.point_format.id))
    handled = {"X", "Y", "Z", "intensity", "classification", "red", "green", "blue"}
    fields = {nm: np.array(las[nm]) for nm in las.point_format.dimension_names if nm not in handled}
    report(progress, "reading", 1.0)
    return build_cloud(path, positions, colors=colors, progress=progress, origin=origin,
                       already_local=True, intensity=intensity, classification=classification,
                       quantization=quant, point_fields=fields or None)


def quantize(cloud: SplatCloud, scale, offset, path) -> np.ndarray:
    """(n, 3) int64 ``round((positions + origin - offset) / scale)``, computed
    as ``round(positions / scale) + round((origin - offset) / scale)`` so
    that coordinates read from the same grid come back exactly.

    Raises:
        InputError when a value does not fit LAS's signed 32-bit integers.
    """
    scale = np.asarray(scale, dtype=np.float64)
    base = np.asarray(cloud.origin, dtype=np.float64) - np.asarray(offset, dtype=np.float64)
    ref = np.round(base / scale)
    ints = np.rint(cloud.positions / scale).astype(np.int64) + ref.astype(np.int64)
    frac = base / scale - ref        # an origin off the grid (a cloud not read from LAS)
    if np.any(frac != 0):
        ints = np.rint((cloud.positions + base) / scale).astype(np.int64)
    lo, hi = column_bounds(ints)
    if lo.min() < -2**31 or hi.max() > 2**31 - 1:
        raise InputError(f"coordinates do not fit LAS's 32-bit integers at scale "
                         f"{scale.tolist()} (extent too large)", path=str(path))
    return ints


def write_las(fh, cloud: SplatCloud, path, *, compress: bool) -> None:
    """Write ``cloud`` as LAS (or LAZ with ``compress``) to the open binary file ``fh``."""
    import laspy
    q = cloud.quantization
    own_rgb = cloud.colors is not None and (q is None or q.point_format in _RGB_FORMATS
                                            or q.point_format is None)
    # LAS 1.4 formats (6+) hold 8-bit classes; 1.2's formats 1/3 only 0..31
    wide = (q is not None and (q.point_format or 0) >= 6) or (
        cloud.classification is not None and int(cloud.classification.max()) > 31)
    fmt = (7 if own_rgb else 6) if wide else (3 if own_rgb else 1)
    fields = cloud.point_fields or {}
    if fields and q is not None and q.point_format is not None:
        # fields read from a LAS file: its own point format keeps them all
        fmt = q.point_format
        if own_rgb and fmt not in _RGB_FORMATS:
            fmt = {0: 2, 1: 3, 4: 5, 6: 7, 9: 10}.get(fmt, fmt)
    header = laspy.LasHeader(point_format=fmt, version="1.4" if fmt >= 6 or wide else "1.2")
    standard = set(header.point_format.dimension_names)
    extra = [laspy.ExtraBytesParams(nm, a.dtype) for nm, a in fields.items()
             if nm not in standard and a.ndim == 1]
    if extra:
        header.add_extra_dims(extra)
    if q is not None:
        scale, offset = np.array(q.scale), np.array(q.offset)
    else:
        scale = np.full(3, LAS_DEFAULT_SCALE)
        offset = np.array(cloud.origin, dtype=np.float64)
    header.scales = scale
    header.offsets = offset
    ints = quantize(cloud, scale, offset, path)
    las = laspy.LasData(header)
    las.X, las.Y, las.Z = ints[:, 0], ints[:, 1], ints[:, 2]
    del ints
    if cloud.intensity is not None:
        las.intensity = cloud.intensity
    if cloud.classification is not None:
        las.classification = cloud.classification
    for nm, arr in fields.items():
        if nm in set(las.point_format.dimension_names):
            las[nm] = arr
    if own_rgb:
        c = cloud.colors.astype(np.uint16) * 257
        las.red, las.green, las.blue = c[:, 0], c[:, 1], c[:, 2]
    stream = RecordingStream(fh)
    with library_call(path, f"cannot write {'LAZ' if compress else 'LAS'}", stream):
        las.write(stream, do_compress=compress,
                  laz_backend=laspy.LazBackend.Lazrs if compress else None)
