"""COPC (Cloud Optimized Point Cloud) files: one LAZ 1.4 file whose points are
stored octree node by octree node, so that a region at a level of detail is
read without touching the rest (https://copc.io).

Layout (the facts of the COPC 1.0 specification this module relies on):

* a LAS 1.4 header (375 bytes) with point data record format 6, 7 or 8
  (LAZ-compressed: bit 7 of the format byte set);
* the first VLR is the COPC info record (user "copc", id 1, 160 bytes): the
  octree's centre (3 doubles), half size (the root node is the cube centre
  +- half size), the point spacing at the root (halved per level), the
  offset and size of the root hierarchy page, the GPS-time range, 88 bytes
  reserved;
* the laszip VLR with variable-size chunks: every octree node's points are
  one LAZ chunk (independently decodable), followed by the LAZ chunk table;
* hierarchy pages in an EVLR (user "copc", id 1000): entries of 32 bytes,
  key ``(depth, x, y, z)`` as four int32, the chunk's file offset (uint64),
  byte size (int32) and point count (int32; -1: the offset/size are those of
  a child hierarchy page; 0: a node without points that has descendants).
  Node ``(d, x, y, z)`` is the cube of side ``2 * halfsize / 2**d`` at
  ``centre - halfsize + (x, y, z) * side``; each point lies in its node's
  cube, and the nodes above a node in the tree are listed too.

:class:`CopcFile` reads the header and the hierarchy only (cheap: a few
hundred kB for 10^8 points); :meth:`CopcFile.read` decompresses the chunks of
the nodes asked for (lazrs, the byte ranges read with ``os.pread``).
:func:`rewrite_copc` streams a file into a new one node by node, copying the
compressed bytes of the nodes an edit leaves alone.  :func:`write_copc` and
:func:`convert_to_copc` build the octree (see :class:`_Octree`).

Coordinates: ``PointBlock.xyz`` is in file units (``X * scale + offset``,
float64); the integers are kept in ``PointBlock.records`` so that a node
rewritten without a move gives back the same integers.
"""

from __future__ import annotations

import math
import os
import struct
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterable, Iterator

import numpy as np

from splatedit.errors import InputError
from splatedit.progress import report
from splatedit.tolerances import COPC_FINE_DEPTH, COPC_LEAF_POINTS, COPC_NODE_POINTS

# --------------------------------------------------------------------------- format facts

#: LAS 1.4 public header (375 bytes)
_HEADER14 = struct.Struct("<4sHH16sBB32s32sHHHIIBHI5I3d3d6dQQIQ15Q")
assert _HEADER14.size == 375
_VLR_HEAD = struct.Struct("<H16sHH32s")          # 54 bytes
_EVLR_HEAD = struct.Struct("<H16sHQ32s")         # 60 bytes
_COPC_INFO = struct.Struct("<3dddQQdd11Q")       # 160 bytes
assert _COPC_INFO.size == 160
_ENTRY = np.dtype([("d", "<i4"), ("x", "<i4"), ("y", "<i4"), ("z", "<i4"),
                   ("offset", "<u8"), ("byte_size", "<i4"), ("point_count", "<i4")])
assert _ENTRY.itemsize == 32
_LASZIP_USER, _LASZIP_ID = b"laszip encoded", 22204
_COPC_USER = b"copc"
_INFO_ID, _HIERARCHY_ID = 1, 1000
#: the deepest octree level accepted in a file (2**31 cells per axis)
_MAX_DEPTH = 30

_BASE_FIELDS = [("X", "<i4"), ("Y", "<i4"), ("Z", "<i4"), ("intensity", "<u2"),
                ("returns", "u1"), ("flags", "u1"), ("classification", "u1"),
                ("user_data", "u1"), ("scan_angle", "<i2"), ("point_source_id", "<u2"),
                ("gps_time", "<f8")]
_RGB_FIELDS = [("red", "<u2"), ("green", "<u2"), ("blue", "<u2")]
_RECORD_BYTES = {6: 30, 7: 36, 8: 38}


def record_dtype(point_format: int, record_length: int) -> np.dtype:
    """The numpy dtype of one point record of LAS point format 6, 7 or 8
    with ``record_length`` bytes (extra bytes as one ``extra`` u1 field)."""
    fields = list(_BASE_FIELDS)
    if point_format in (7, 8):
        fields += _RGB_FIELDS
    if point_format == 8:
        fields.append(("nir", "<u2"))
    extra = record_length - _RECORD_BYTES[point_format]
    if extra > 0:
        fields.append(("extra", "u1", (extra,)))
    dt = np.dtype(fields)
    assert dt.itemsize == record_length
    return dt


# --------------------------------------------------------------------------- public records


@dataclass(frozen=True, order=True)
class NodeKey:
    """A COPC voxel key: octree ``depth`` (0 = root) and the cell ``x, y, z``
    (each in ``0 .. 2**depth - 1``)."""
    depth: int
    x: int
    y: int
    z: int

    def parent(self) -> "NodeKey":
        """The key one level up (the root's parent is an error)."""
        if self.depth == 0:
            raise ValueError("the root has no parent")
        return NodeKey(self.depth - 1, self.x >> 1, self.y >> 1, self.z >> 1)

    def children(self) -> list["NodeKey"]:
        """The 8 keys one level down."""
        d = self.depth + 1
        return [NodeKey(d, (self.x << 1) | (i & 1), (self.y << 1) | ((i >> 1) & 1),
                        (self.z << 1) | ((i >> 2) & 1)) for i in range(8)]


ROOT = NodeKey(0, 0, 0, 0)


@dataclass(frozen=True)
class CopcNode:
    """One octree node with points: its key, point count, the byte range of
    its LAZ chunk and its cube ``bounds`` ((2, 3) float64 min / max, file
    units)."""
    key: NodeKey
    point_count: int
    offset: int
    byte_size: int
    bounds: np.ndarray = field(compare=False, repr=False)


@dataclass
class PointBlock:
    """Points of some nodes.

    Attributes:
        xyz: (n, 3) float64 positions in file units (``X * scale + offset``).
        node: (n,) int32 index into ``keys`` of each point's node.
        row: (n,) int32 row of the point within its node's chunk.
        keys: the nodes' keys.
        colour: (n, 3) uint8 (the high byte of the 16-bit RGB) or None.
        intensity: (n,) uint16 or None.
        records: (n,) the raw point records (numpy structured array, see
            :func:`record_dtype`; X/Y/Z are the file's integers); the other
            LAS fields (GPS time, classification, returns, ...) live here.
    """
    xyz: np.ndarray
    node: np.ndarray
    row: np.ndarray
    keys: list
    colour: np.ndarray | None = None
    intensity: np.ndarray | None = None
    records: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.xyz)

    def take(self, index) -> "PointBlock":
        """The points ``index`` (a boolean mask or integer indices) of this block."""
        return PointBlock(self.xyz[index], self.node[index], self.row[index], self.keys,
                          None if self.colour is None else self.colour[index],
                          None if self.intensity is None else self.intensity[index],
                          None if self.records is None else self.records[index])


@dataclass
class WriteReport:
    """What :func:`rewrite_copc` / :func:`write_copc` did.

    Attributes:
        path: the written file.
        point_count: points written.
        nodes: nodes with points in the written file.
        copied: nodes copied verbatim (compressed bytes) from the source.
        encoded: nodes compressed anew.
        created: nodes that did not exist in the source.
        moved: points that changed node (left their node's cube).
        bytes: size of the written file.
    """
    path: Path
    point_count: int
    nodes: int
    copied: int = 0
    encoded: int = 0
    created: int = 0
    moved: int = 0
    bytes: int = 0


# --------------------------------------------------------------------------- reading


@dataclass
class _Header:
    """The LAS 1.4 header fields this module uses (and the raw bytes)."""
    raw: bytes
    point_format: int
    record_length: int
    header_size: int
    data_offset: int
    n_vlr: int
    scale: np.ndarray
    offset: np.ndarray
    mins: np.ndarray
    maxs: np.ndarray
    first_evlr: int
    n_evlr: int
    point_count: int
    by_return: tuple
    global_encoding: int
    file_source_id: int
    guid: bytes
    system_id: bytes
    software: bytes


def _parse_header(raw: bytes, path: str) -> _Header:
    f = _HEADER14.unpack_from(raw)
    fmt_byte = f[13]
    fmt = fmt_byte & 0x3F
    if (f[4], f[5]) != (1, 4):
        raise InputError(f"not a COPC file: LAS version {f[4]}.{f[5]} (COPC is LAS 1.4)", path=path)
    if fmt not in _RECORD_BYTES or not fmt_byte & 0x80:
        raise InputError(f"not a COPC file: point format {fmt}{'' if fmt_byte & 0x80 else ' uncompressed'}"
                         f" (COPC is LAZ with point format 6, 7 or 8)", path=path)
    if f[14] < _RECORD_BYTES[fmt]:
        raise InputError(f"header: point record length {f[14]} is below the {_RECORD_BYTES[fmt]} "
                         f"bytes of point format {fmt}", path=path)
    mx = f[27:33]
    return _Header(raw=raw, point_format=fmt, record_length=f[14], header_size=f[10],
                   data_offset=f[11], n_vlr=f[12], scale=np.array(f[21:24]), offset=np.array(f[24:27]),
                   mins=np.array(mx[1::2]), maxs=np.array(mx[0::2]), first_evlr=f[34], n_evlr=f[35],
                   point_count=f[36] or f[15], by_return=tuple(f[37:52]), global_encoding=f[2],
                   file_source_id=f[1], guid=f[3], system_id=f[6], software=f[7])


def _pread(fd: int, size: int, offset: int, path: str, what: str) -> bytes:
    data = os.pread(fd, size, offset)
    if len(data) != size:
        raise InputError(f"truncated file: {what} ({size} bytes at byte {offset}) ends past the end "
                         f"of the file", path=path)
    return data


class CopcFile:
    """An open COPC file: header, COPC info and the whole node hierarchy in
    memory, the point data on disk (read on demand by :meth:`read`).

    Attributes:
        path: the file.
        point_count: points in the file (header).
        bounds: (2, 3) float64 the root node's cube (min, max), file units.
        point_bounds: (2, 3) float64 the header's min / max of the points.
        spacing: point spacing at the root (COPC info), halved per level.
        max_depth: the deepest level with points.
        nodes: every node with points, by key.
        has_colour: point format 7 or 8 (16-bit RGB).
        has_intensity: always True (formats 6-8 carry intensity).
        scale, offset: (3,) float64 the LAS integer grid.
        point_format, record_length: the LAS point record.
    """

    def __init__(self, path, header: _Header, info: tuple, vlrs: list, laszip: bytes,
                 nodes: dict, structure: set, evlrs: list, fd: int):
        self.path = Path(path)
        self._h = header
        self._fd = fd
        center = np.array(info[0:3], dtype=np.float64)
        self.halfsize = float(info[3])
        self.center = center
        self.spacing = float(info[4])
        self.gps_range = (float(info[7]), float(info[8]))
        self.bounds = np.stack([center - self.halfsize, center + self.halfsize])
        self.point_bounds = np.stack([header.mins, header.maxs])
        self.point_count = int(header.point_count)
        self.point_format = header.point_format
        self.record_length = header.record_length
        self.scale = header.scale
        self.offset = header.offset
        self.dtype = record_dtype(header.point_format, header.record_length)
        self.has_colour = header.point_format in (7, 8)
        self.has_intensity = True
        self.nodes: dict[NodeKey, CopcNode] = nodes
        self.max_depth = max((k.depth for k in nodes), default=0)
        self.laszip_vlr = laszip
        self._vlrs = vlrs            # (user, id, description, data) of the other VLRs
        self._evlrs = evlrs          # the same for EVLRs other than hierarchy pages
        self._structure = structure  # keys of point-less nodes listed in the hierarchy

    # -- opening

    @classmethod
    def open(cls, path) -> "CopcFile":
        """Read the header, the VLRs and every hierarchy page of ``path``
        (no point data).

        Raises:
            InputError: naming the file, for anything that is not a valid
            COPC file (truncated, wrong version or format, no COPC info VLR
            first, hierarchy entries outside the file or counts that do not
            add up to the header's).
        """
        src = str(path)
        import stat
        try:
            mode = os.stat(src).st_mode
        except OSError as exc:
            raise InputError(f"cannot read file: {exc.strerror or exc}", path=src) from None
        except ValueError as exc:
            raise InputError(f"not a usable file name: {exc}", path=repr(src)) from None
        if stat.S_ISDIR(mode):
            raise InputError("is a directory, not a file", path=src)
        if not stat.S_ISREG(mode):        # a FIFO would block the open
            raise InputError("is not a regular file (a FIFO, device or socket); splatedit reads files",
                             path=src)
        from splatedit.io.las import check_las_header
        check_las_header(path)
        try:
            fd = os.open(src, os.O_RDONLY)
        except OSError as exc:
            raise InputError(f"cannot read file: {exc.strerror or exc}", path=src) from None
        try:
            return cls._open(src, fd)
        except BaseException:
            os.close(fd)
            raise

    @classmethod
    def _open(cls, src: str, fd: int) -> "CopcFile":
        size = os.fstat(fd).st_size
        h = _parse_header(_pread(fd, 375, 0, src, "the LAS 1.4 header"), src)
        pos, vlrs, info, laszip = h.header_size, [], None, None
        for i in range(h.n_vlr):
            user, rid, length, desc, data = _read_vlr(fd, pos, src, size)
            if i == 0:
                if user != _COPC_USER or rid != _INFO_ID or length != _COPC_INFO.size:
                    raise InputError("not a COPC file: its first VLR is not the COPC info record "
                                     "(user 'copc', id 1, 160 bytes)", path=src)
                info = _COPC_INFO.unpack(data)
            elif user == _LASZIP_USER and rid == _LASZIP_ID:
                laszip = data
            else:
                vlrs.append((user, rid, desc, data))
            pos += _VLR_HEAD.size + length
        if info is None:
            raise InputError("not a COPC file: no COPC info VLR", path=src)
        if laszip is None:
            raise InputError("not a COPC file: no laszip VLR", path=src)
        if not (np.isfinite(info[:5]).all() and info[3] > 0 and info[4] >= 0):
            raise InputError(f"COPC info: centre {info[0:3]}, half size {info[3]}, spacing {info[4]} "
                             f"are not a valid octree", path=src)
        evlrs, pages = [], []
        pos = h.first_evlr
        for _ in range(h.n_evlr):
            head = _pread(fd, _EVLR_HEAD.size, pos, src, "an extended VLR header")
            _, user, rid, length, desc = _EVLR_HEAD.unpack(head)
            user = user.rstrip(b"\0")
            if not (user == _COPC_USER and rid == _HIERARCHY_ID):
                evlrs.append((user, rid, desc, _pread(fd, length, pos + 60, src, "an extended VLR")))
            pos += 60 + length
        root_off, root_size = info[5], info[6]
        if root_size % 32 or not h.data_offset <= root_off <= size - root_size:
            raise InputError(f"COPC info: root hierarchy page at byte {root_off} ({root_size} bytes) "
                             f"does not fit a file of {size} bytes", path=src)
        nodes, structure = {}, set()
        todo = [(root_off, root_size)]
        total = 0
        seen_pages = set()
        while todo:
            off, sz = todo.pop()
            if (off, sz) in seen_pages:
                raise InputError("COPC hierarchy: a page is listed twice (a loop)", path=src)
            seen_pages.add((off, sz))
            if sz % 32 or not h.data_offset <= off <= size - sz:
                raise InputError(f"COPC hierarchy: page at byte {off} ({sz} bytes) does not fit a file "
                                 f"of {size} bytes", path=src)
            page = np.frombuffer(_pread(fd, sz, off, src, "a hierarchy page"), dtype=_ENTRY)
            for e in page.tolist():
                d, x, y, z, eoff, ebytes, count = e
                key = NodeKey(d, x, y, z)
                lim = 1 << d if 0 <= d <= _MAX_DEPTH else 0
                if not (0 <= x < lim and 0 <= y < lim and 0 <= z < lim):
                    raise InputError(f"COPC hierarchy: key {tuple(e[:4])} is not an octree cell", path=src)
                if count == -1:
                    todo.append((eoff, ebytes))
                elif count == 0:
                    structure.add(key)
                elif count > 0:
                    if ebytes <= 0 or not h.data_offset < eoff <= size - ebytes:
                        raise InputError(f"COPC hierarchy: node {tuple(e[:4])} chunk at byte {eoff} "
                                         f"({ebytes} bytes) lies outside the point data", path=src)
                    if key in nodes:
                        raise InputError(f"COPC hierarchy: node {tuple(e[:4])} listed twice", path=src)
                    side = 2 * info[3] / (1 << d)
                    lo = np.array(info[0:3]) - info[3] + np.array([x, y, z]) * side
                    nodes[key] = CopcNode(key, count, eoff, ebytes, np.stack([lo, lo + side]))
                    total += count
                else:
                    raise InputError(f"COPC hierarchy: node {tuple(e[:4])} has point count {count}",
                                     path=src)
        if total != h.point_count:
            raise InputError(f"COPC hierarchy: its nodes hold {total} points, the header says "
                             f"{h.point_count}", path=src)
        return cls(src, h, info, vlrs, laszip, nodes, structure, evlrs, fd)

    # -- queries

    @property
    def structure_keys(self) -> set:
        """Keys listed in the hierarchy without points (they have
        descendants with points)."""
        return self._structure

    def node_bounds(self, key: NodeKey) -> np.ndarray:
        """(2, 3) float64 the cube of node ``key`` (it need not exist)."""
        side = 2 * self.halfsize / (1 << key.depth)
        lo = self.bounds[0] + np.array([key.x, key.y, key.z]) * side
        return np.stack([lo, lo + side])

    def select(self, bounds=None, max_depth: int | None = None) -> list[CopcNode]:
        """The nodes whose cube intersects the box ``bounds`` ((2, 3) min /
        max, file units; None: everywhere), at depth ``max_depth`` or less,
        in file order (increasing offset)."""
        out = []
        if bounds is not None:
            bounds = np.asarray(bounds, dtype=np.float64)
        for node in self.nodes.values():
            if max_depth is not None and node.key.depth > max_depth:
                continue
            if bounds is not None and (np.any(node.bounds[0] > bounds[1])
                                       or np.any(node.bounds[1] < bounds[0])):
                continue
            out.append(node)
        out.sort(key=lambda n: n.offset)
        return out

    def read_compressed(self, key: NodeKey) -> bytes:
        """The LAZ chunk of node ``key`` as stored in the file."""
        n = self.nodes[key]
        return _pread(self._fd, n.byte_size, n.offset, str(self.path), f"node {_kt(key)}")

    def read_records(self, keys: Iterable[NodeKey]) -> tuple[list[NodeKey], np.ndarray]:
        """The raw records of the nodes ``keys`` (structured array, nodes in
        the order given, each node's rows in file order)."""
        keys = list(keys)
        nodes = [self.nodes[k] for k in keys]
        total = sum(n.point_count for n in nodes)
        out = np.empty(total, dtype=self.dtype)
        if not nodes:
            return keys, out
        data = b"".join(_pread(self._fd, n.byte_size, n.offset, str(self.path), f"node {_kt(n.key)}")
                        for n in nodes)
        import lazrs
        try:
            lazrs.decompress_points_with_chunk_table(
                data, self.laszip_vlr, out.view(np.uint8),
                [(n.point_count, n.byte_size) for n in nodes])
        except Exception as exc:       # lazrs raises its own LazrsError
            raise InputError(f"cannot decompress the points of node(s) {', '.join(_kt(k) for k in keys[:3])}"
                             f"{'...' if len(keys) > 3 else ''}: {exc}", path=str(self.path)) from None
        return keys, out

    def read(self, keys: Iterable, progress=None, *, batch_points: int = 2_000_000) -> PointBlock:
        """Decompress the points of the nodes ``keys`` (NodeKey or CopcNode),
        ``batch_points`` at a time (one lazrs call each, which decodes its
        chunks in parallel).

        Returns:
            a :class:`PointBlock`, the nodes in the order given.
        """
        keys = [k.key if isinstance(k, CopcNode) else k for k in keys]
        counts = np.array([self.nodes[k].point_count for k in keys], dtype=np.int64)
        total = int(counts.sum())
        records = np.empty(total, dtype=self.dtype)
        start, done, i = 0, 0, 0
        report(progress, "reading COPC nodes", 0.0)
        while i < len(keys):
            j, pts = i, 0
            while j < len(keys) and (j == i or pts + counts[j] <= batch_points):
                pts += int(counts[j])
                j += 1
            _, recs = self.read_records(keys[i:j])
            records[start:start + pts] = recs
            start += pts
            i = j
            done += pts
            report(progress, "reading COPC nodes", done / max(total, 1))
        return self.block(keys, records, counts)

    def block(self, keys: list, records: np.ndarray, counts=None) -> PointBlock:
        """A :class:`PointBlock` of ``records`` holding the points of the
        nodes ``keys`` in order (``counts[i]`` rows each; by default each
        node's point count)."""
        if counts is None:
            counts = np.array([self.nodes[k].point_count for k in keys], dtype=np.int64)
        counts = np.asarray(counts, dtype=np.int64)
        node = np.repeat(np.arange(len(keys), dtype=np.int32), counts)
        starts = np.cumsum(counts) - counts
        row = (np.arange(len(records), dtype=np.int64) - np.repeat(starts, counts)).astype(np.int32)
        return PointBlock(self.positions(records), node, row, list(keys),
                          _colour8(records) if self.has_colour else None,
                          records["intensity"].copy(), records)

    def positions(self, records: np.ndarray) -> np.ndarray:
        """(n, 3) float64 ``X * scale + offset`` of ``records``."""
        xyz = np.empty((len(records), 3), dtype=np.float64)
        for j, c in enumerate("XYZ"):
            np.multiply(records[c], self.scale[j], out=xyz[:, j])
            xyz[:, j] += self.offset[j]
        return xyz

    def close(self) -> None:
        """Close the file (idempotent)."""
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass


def _kt(key: NodeKey) -> str:
    return f"{key.depth}-{key.x}-{key.y}-{key.z}"


def _colour8(records: np.ndarray) -> np.ndarray:
    """(n, 3) uint8 the high bytes of the 16-bit RGB of ``records``."""
    out = np.empty((len(records), 3), dtype=np.uint8)
    for j, c in enumerate(("red", "green", "blue")):
        out[:, j] = records[c] >> 8
    return out


def _read_vlr(fd: int, pos: int, src: str, size: int):
    head = _pread(fd, _VLR_HEAD.size, pos, src, "a VLR header")
    _, user, rid, length, desc = _VLR_HEAD.unpack(head)
    data = _pread(fd, length, pos + _VLR_HEAD.size, src, "a VLR")
    return user.rstrip(b"\0"), rid, length, desc, data


def is_copc(path) -> bool:
    """True when ``path`` is a LAS 1.4 file whose first VLR is the COPC info
    record (a cheap sniff: 429 bytes).  Anything but a regular file is
    False, unopened (a FIFO would block the open)."""
    import stat
    try:
        if not stat.S_ISREG(os.stat(path).st_mode):
            return False
        with open(path, "rb") as fh:
            head = fh.read(375 + 54)
    except (OSError, ValueError):
        return False
    if len(head) < 429 or head[:4] != b"LASF":
        return False
    hs = struct.unpack_from("<H", head, 94)[0]
    if hs != 375:
        return False
    _, user, rid, _, _ = _VLR_HEAD.unpack_from(head, 375)
    return user.rstrip(b"\0") == _COPC_USER and rid == _INFO_ID


# --------------------------------------------------------------------------- writing


def _pad(b: bytes, n: int) -> bytes:
    return b[:n].ljust(n, b"\0")


def _vlr_bytes(user: bytes, rid: int, desc: bytes, data: bytes) -> bytes:
    return _VLR_HEAD.pack(0, _pad(user, 16), rid, len(data), _pad(desc, 32)) + data


def compress_chunk(vlr, records: np.ndarray) -> bytes:
    """One LAZ chunk (the bytes a COPC node's entry points at) holding
    ``records`` (structured array of the file's record dtype)."""
    import lazrs
    out = bytes(lazrs.compress_points(vlr, np.ascontiguousarray(records).view(np.uint8), False))
    (table,) = struct.unpack_from("<q", out, 0)
    return out[8:table]


class _Writer:
    """Writes a COPC file: header and VLRs (rewritten at the end with the
    final counts), then LAZ chunks one node at a time (compressed here or
    copied), the chunk table and one hierarchy page."""

    def __init__(self, fh, *, point_format: int, record_length: int, scale, offset, center,
                 halfsize: float, spacing: float, laszip_vlr: bytes | None = None,
                 vlrs=(), evlrs=(), template: _Header | None = None):
        import lazrs
        self.fh = fh
        self.point_format, self.record_length = point_format, record_length
        self.dtype = record_dtype(point_format, record_length)
        self.scale, self.offset = np.asarray(scale, float), np.asarray(offset, float)
        self.center, self.halfsize, self.spacing = np.asarray(center, float), float(halfsize), float(spacing)
        if laszip_vlr is None:
            self.vlr = lazrs.LazVlr.new_for_compression(point_format, record_length - _RECORD_BYTES[point_format],
                                                         use_variable_size_chunks=True)
            self.laszip = bytes(self.vlr.record_data())
        else:
            self.vlr = lazrs.LazVlr(laszip_vlr)
            self.laszip = bytes(laszip_vlr)
        self.vlrs, self.evlrs, self.template = list(vlrs), list(evlrs), template
        self.gps = [np.inf, -np.inf]
        self.data_offset = 375 + len(self._vlr_block(0, 0))
        fh.seek(0)
        fh.write(b"\0" * (self.data_offset + 8))
        self.pos = self.data_offset + 8
        self.entries: dict[NodeKey, tuple[int, int, int]] = {}
        self.chunks: list[tuple[int, int]] = []
        self.mins = np.full(3, np.inf)
        self.maxs = np.full(3, -np.inf)
        self.by_return = np.zeros(15, dtype=np.int64)

    def _vlr_block(self, hier_off: int, hier_size: int) -> bytes:
        info = _COPC_INFO.pack(*self.center, self.halfsize, self.spacing, hier_off, hier_size,
                               *(self.gps if np.isfinite(self.gps[0]) else (0.0, 0.0)), *([0] * 11))
        out = _vlr_bytes(_COPC_USER, _INFO_ID, b"COPC info", info)
        out += _vlr_bytes(_LASZIP_USER, _LASZIP_ID, b"laszip variable chunks", self.laszip)
        for user, rid, desc, data in self.vlrs:
            out += _vlr_bytes(user, rid, desc, data)
        return out

    def add_chunk(self, key: NodeKey, count: int, chunk: bytes, *, mins=None, maxs=None,
                  by_return=None, gps=None) -> None:
        """Append node ``key``'s compressed ``chunk`` of ``count`` points
        (its statistics, when known, update the header's)."""
        if key in self.entries:
            raise ValueError(f"node {_kt(key)} written twice")
        self.fh.write(chunk)
        self.entries[key] = (self.pos, len(chunk), count)
        self.chunks.append((count, len(chunk)))
        self.pos += len(chunk)
        if mins is not None:
            self.mins = np.minimum(self.mins, mins)
            self.maxs = np.maximum(self.maxs, maxs)
        if by_return is not None:
            self.by_return += by_return
        if gps is not None:
            self.gps = [min(self.gps[0], gps[0]), max(self.gps[1], gps[1])]

    def add_records(self, key: NodeKey, records: np.ndarray) -> None:
        """Compress and append node ``key`` holding ``records``."""
        ints = np.stack([records[c] for c in "XYZ"], axis=1)
        lo = ints.min(axis=0) * self.scale + self.offset
        hi = ints.max(axis=0) * self.scale + self.offset
        ret = np.bincount(records["returns"] & 0x0F, minlength=16)[1:16]
        g = records["gps_time"]
        self.add_chunk(key, len(records), compress_chunk(self.vlr, records), mins=lo, maxs=hi,
                       by_return=ret, gps=(float(g.min()), float(g.max())))

    def finish(self, *, point_count: int | None = None, mins=None, maxs=None, by_return=None) -> None:
        """Write the chunk table, the hierarchy page, the other EVLRs and the
        final header and VLRs."""
        import lazrs
        fh = self.fh
        table_at = self.pos
        lazrs.write_chunk_table(fh, self.chunks, self.vlr)
        fh.flush()
        end = fh.seek(0, os.SEEK_END)
        keys = set(self.entries)
        for k in list(keys):
            while k.depth > 0:
                k = k.parent()
                if k in keys:
                    break
                keys.add(k)
        rows = []
        for k in sorted(keys):
            off, size, count = self.entries.get(k, (0, 0, 0))
            rows.append((k.depth, k.x, k.y, k.z, off, size, count))
        page = np.array(rows, dtype=_ENTRY).tobytes()
        evlr_at = end
        fh.write(_EVLR_HEAD.pack(0, _pad(_COPC_USER, 16), _HIERARCHY_ID, len(page),
                                 _pad(b"EPT hierarchy", 32)))
        fh.write(page)
        for user, rid, desc, data in self.evlrs:
            fh.write(_EVLR_HEAD.pack(0, _pad(user, 16), rid, len(data), _pad(desc, 32)) + data)
        count = sum(c for _, _, c in self.entries.values()) if point_count is None else point_count
        mins = self.mins if mins is None else mins
        maxs = self.maxs if maxs is None else maxs
        if not np.isfinite(mins).all():
            mins = maxs = self.offset.copy()
        by_return = self.by_return if by_return is None else by_return
        t = self.template
        fields = [b"LASF", t.file_source_id if t else 0, (t.global_encoding if t else 0) | 0x10,
                  t.guid if t else b"\0" * 16, 1, 4,
                  t.system_id if t else _pad(b"splatedit", 32), _pad(b"splatedit COPC writer", 32),
                  1, 2026, 375, self.data_offset, 2 + len(self.vlrs), self.point_format | 0x80,
                  self.record_length, 0, 0, 0, 0, 0, 0, *self.scale, *self.offset,
                  maxs[0], mins[0], maxs[1], mins[1], maxs[2], mins[2], 0, evlr_at,
                  1 + len(self.evlrs), count, *[int(v) for v in by_return]]
        fh.seek(0)
        fh.write(_HEADER14.pack(*fields))
        fh.write(self._vlr_block(evlr_at + 60, len(page)))
        fh.write(struct.pack("<q", table_at))
        fh.seek(0, os.SEEK_END)


# --------------------------------------------------------------------------- octree layout

#: the layout's defaults (splatedit.tolerances: COPC_NODE_POINTS, ...)
NODE_POINTS = COPC_NODE_POINTS
LEAF_POINTS = COPC_LEAF_POINTS
FINE_DEPTH = COPC_FINE_DEPTH


class _Octree:
    """The layout of a point set in an octree, from the point counts of the
    cells of level ``fine`` (``codes``: sorted cell codes ``x << 2F | y << F
    | z``, ``counts``).

    Node rule (a random-sampling level of detail, as Potree's 'random'
    sampler and Entwine's): a node whose subtree holds at most
    ``leaf_points`` points (or at level ``fine``) is a leaf and keeps them
    all; above, a node keeps about ``node_points`` of its subtree's points,
    chosen at random.  A point with a uniform random ``u`` goes to the first
    node on its root-to-leaf path with ``u < T(node)``, where ``T(root) =
    node_points / count`` and ``T(node) = T(parent) + node_points /
    count(node)`` (1 at the leaves): of the ``count * (1 - T(parent))``
    points reaching a node it keeps ``node_points`` on average.
    """

    def __init__(self, lo, half: float, fine: int, codes: np.ndarray, counts: np.ndarray,
                 node_points: int = NODE_POINTS, leaf_points: int = LEAF_POINTS):
        self.lo, self.half, self.fine = np.asarray(lo, float), float(half), fine
        F = fine
        fx, fy, fz = codes >> (2 * F), (codes >> F) & ((1 << F) - 1), codes & ((1 << F) - 1)
        self.levels = []     # per depth: (codes, T, alive)
        parent_codes = parent_T = parent_open = None
        for d in range(F + 1):
            s = F - d
            c = ((fx >> s) << (2 * d)) | ((fy >> s) << d) | (fz >> s)
            ucodes, inv = np.unique(c, return_inverse=True)
            cnt = np.bincount(inv, weights=counts, minlength=len(ucodes))
            if d == 0:
                Tp = np.zeros(len(ucodes))
                open_ = np.ones(len(ucodes), bool)
            else:
                ux, uy, uz = ucodes >> (2 * d), (ucodes >> d) & ((1 << d) - 1), ucodes & ((1 << d) - 1)
                pc = ((ux >> 1) << (2 * (d - 1))) | ((uy >> 1) << (d - 1)) | (uz >> 1)
                pi = np.searchsorted(parent_codes, pc)
                Tp = parent_T[pi]
                open_ = parent_open[pi]
            leaf = (cnt <= leaf_points) | (d == F)
            T = np.where(leaf, 1.0, np.minimum(1.0, Tp + node_points / np.maximum(cnt, 1)))
            T = np.where(open_, T, 0.0)          # below a leaf: no node
            self.levels.append((ucodes, T))
            parent_codes, parent_T, parent_open = ucodes, T, open_ & ~leaf & (T < 1.0)
        self.spacing = 2 * self.half / np.sqrt(node_points)

    def cells(self, xyz: np.ndarray) -> np.ndarray:
        """(n, 3) int64 the level-``fine`` cells of ``xyz`` (clamped)."""
        n = 1 << self.fine
        c = np.floor((xyz - self.lo) * (n / (2 * self.half))).astype(np.int64)
        np.clip(c, 0, n - 1, out=c)
        return c

    def fine_codes(self, xyz: np.ndarray) -> np.ndarray:
        c = self.cells(xyz)
        F = self.fine
        return (c[:, 0] << (2 * F)) | (c[:, 1] << F) | c[:, 2]

    def assign(self, fine_codes: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each point's node: (n,) int8 depth and (n,) int64 code at that depth."""
        F = self.fine
        n = len(fine_codes)
        depth = np.full(n, -1, dtype=np.int8)
        code = np.zeros(n, dtype=np.int64)
        fx, fy, fz = fine_codes >> (2 * F), (fine_codes >> F) & ((1 << F) - 1), fine_codes & ((1 << F) - 1)
        todo = np.arange(n)
        for d, (codes, T) in enumerate(self.levels):
            if not len(todo):
                break
            s = F - d
            c = ((fx[todo] >> s) << (2 * d)) | ((fy[todo] >> s) << d) | (fz[todo] >> s)
            i = np.minimum(np.searchsorted(codes, c), len(codes) - 1)
            if np.any(codes[i] != c):
                raise ValueError("a point outside the counted cells")
            take = u[todo] < T[i]
            sel = todo[take]
            depth[sel] = d
            code[sel] = c[take]
            todo = todo[~take]
        if len(todo):
            raise ValueError("points without a node")
        return depth, code

    @staticmethod
    def key_of(depth: int, code: int) -> NodeKey:
        m = (1 << depth) - 1
        return NodeKey(int(depth), int(code >> (2 * depth)), int((code >> depth) & m), int(code & m))


def _count_cells(codes_iter: Iterator[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Sorted unique cell codes and their counts over all arrays of ``codes_iter``."""
    acc_c = np.zeros(0, np.int64)
    acc_n = np.zeros(0, np.int64)
    for codes in codes_iter:
        u, n = np.unique(codes, return_counts=True)
        allc = np.concatenate([acc_c, u])
        alln = np.concatenate([acc_n, n])
        acc_c, inv = np.unique(allc, return_inverse=True)
        acc_n = np.bincount(inv, weights=alln).astype(np.int64)
    return acc_c, acc_n


def _cube(mins, maxs, scale) -> tuple[np.ndarray, float]:
    """Centre and half size of the root cube around the box ``mins..maxs``:
    the box centre, half the longest side plus a grid step (points on the
    far faces stay inside)."""
    mins, maxs = np.asarray(mins, float), np.asarray(maxs, float)
    center = (mins + maxs) / 2
    half = float(np.max(maxs - mins)) / 2 + float(np.max(np.abs(scale)))
    return center, max(half, float(np.max(np.abs(scale))))


def make_records(xyz, scale, offset, colour=None, intensity=None, point_format=None) -> np.ndarray:
    """Point records (format 7 with ``colour``, else 6) of ``xyz`` (file
    units) on the grid ``scale`` / ``offset``; colours as ``c * 257``; one
    return each."""
    fmt = point_format or (7 if colour is not None else 6)
    rec = np.zeros(len(xyz), dtype=record_dtype(fmt, _RECORD_BYTES[fmt]))
    ints = np.rint((np.asarray(xyz, float) - offset) / scale)
    if len(ints) and (ints.min() < -2**31 or ints.max() > 2**31 - 1):
        raise InputError(f"coordinates do not fit LAS's 32-bit integers at scale {list(scale)}")
    for j, c in enumerate("XYZ"):
        rec[c] = ints[:, j]
    rec["returns"] = 0x11
    if intensity is not None:
        rec["intensity"] = intensity
    if colour is not None:
        for j, c in enumerate(("red", "green", "blue")):
            rec[c] = np.asarray(colour[:, j], np.uint16) * 257
    return rec


def _write_layout(fh, records: np.ndarray, tree: _Octree, writer: _Writer, progress=None,
                  stage: str = "writing COPC") -> None:
    """Assign ``records`` (in memory) to the octree ``tree`` and write every
    node through ``writer``."""
    xyz = np.stack([records[c] * writer.scale[j] + writer.offset[j] for j, c in enumerate("XYZ")], axis=1)
    rng = np.random.default_rng(0)
    depth, code = tree.assign(tree.fine_codes(xyz), rng.random(len(records)))
    del xyz
    order = np.lexsort((code, depth))
    depth, code = depth[order], code[order]
    brk = np.flatnonzero((np.diff(depth) != 0) | (np.diff(code) != 0)) + 1
    starts = np.concatenate([[0], brk])
    ends = np.concatenate([brk, [len(order)]])
    for i, (a, b) in enumerate(zip(starts, ends)):
        writer.add_records(tree.key_of(depth[a], code[a]), records[order[a:b]])
        if i % 16 == 0:
            report(progress, stage, b / max(len(order), 1))


def write_copc(dst_path, xyz, colour=None, intensity=None, *, records=None, scale=None, offset=None,
               node_points: int = NODE_POINTS, leaf_points: int = LEAF_POINTS, progress=None) -> WriteReport:
    """Write the points ``xyz`` ((n, 3) float64, file units) as a COPC file
    (in memory; :func:`convert_to_copc` streams large LAS/LAZ).

    Args:
        colour: (n, 3) uint8 (written as 16-bit ``c * 257``, point format 7)
            or None (format 6).
        intensity: (n,) uint16 or None.
        records: instead of ``xyz``/``colour``/``intensity``: the point
            records themselves (format 6/7/8 dtype, :func:`record_dtype`);
            then ``scale`` and ``offset`` are those of the records' grid.
        scale, offset: the LAS grid (default ``LAS_DEFAULT_SCALE`` and the
            box centre rounded to whole units).
        node_points, leaf_points: the layout (see :class:`_Octree`).
    """
    from splatedit.atomic import atomic_open
    from splatedit.tolerances import LAS_DEFAULT_SCALE
    if records is None:
        xyz = np.asarray(xyz, dtype=np.float64)
        if not len(xyz):
            raise InputError("zero points: nothing to write", path=str(dst_path))
        lo, hi = xyz.min(axis=0), xyz.max(axis=0)
        scale = np.full(3, LAS_DEFAULT_SCALE) if scale is None else np.asarray(scale, float)
        offset = np.round((lo + hi) / 2) if offset is None else np.asarray(offset, float)
        records = make_records(xyz, scale, offset, colour, intensity)
    with atomic_open(dst_path, "wb") as fh:
        w = write_records(fh, records, scale, offset, node_points=node_points, leaf_points=leaf_points,
                          progress=progress)
        size = fh.tell()
    return WriteReport(Path(dst_path), len(records), len(w.entries), encoded=len(w.entries), bytes=size)


def write_records(fh, records: np.ndarray, scale, offset, *, node_points: int = NODE_POINTS,
                  leaf_points: int = LEAF_POINTS, vlrs=(), progress=None) -> "_Writer":
    """Write the point ``records`` (in memory) as a COPC file to the open
    binary file ``fh``; returns the finished writer (its ``entries``)."""
    scale, offset = np.asarray(scale, float), np.asarray(offset, float)
    names = records.dtype.names
    fmt = 8 if "nir" in names else 7 if "red" in names else 6
    ints = np.stack([records[c] for c in "XYZ"], axis=1).astype(np.int64)
    lo = ints.min(axis=0) * scale + offset
    hi = ints.max(axis=0) * scale + offset
    center, half = _cube(lo, hi, scale)
    del ints
    tree = _tree_for(records, scale, offset, center, half, node_points, leaf_points)
    w = _Writer(fh, point_format=fmt, record_length=records.dtype.itemsize, scale=scale, offset=offset,
                center=center, halfsize=half, spacing=tree.spacing, vlrs=vlrs)
    _write_layout(fh, records, tree, w, progress)
    w.finish()
    return w


def write_copc_cloud(fh, cloud, path) -> None:
    """Write a :class:`~splatedit.model.cloud.SplatCloud` as COPC to the
    open binary file ``fh`` (the registry's writer): the grid of the LAS/COPC
    file it was read from (its integers back bit for bit), else
    ``LAS_DEFAULT_SCALE`` around its origin; RGB (point format 7) when it has
    colours, intensity, classification and the LAS fields kept in
    ``point_fields`` (returns, GPS time, user data, point source, scan angle)."""
    from splatedit.io.las import quantize
    from splatedit.tolerances import LAS_DEFAULT_SCALE
    q = cloud.quantization
    if q is not None:
        scale, offset = np.array(q.scale, float), np.array(q.offset, float)
    else:
        scale, offset = np.full(3, LAS_DEFAULT_SCALE), np.array(cloud.origin, dtype=np.float64)
    ints = quantize(cloud, scale, offset, path)
    fmt = 7 if cloud.colors is not None else 6
    rec = np.zeros(len(ints), dtype=record_dtype(fmt, _RECORD_BYTES[fmt]))
    for j, c in enumerate("XYZ"):
        rec[c] = ints[:, j]
    del ints
    f = cloud.point_fields or {}
    rn = f.get("return_number", 1)
    nr = f.get("number_of_returns", 1)
    rec["returns"] = (np.asarray(rn, np.uint8) & 0x0F) | ((np.asarray(nr, np.uint8) & 0x0F) << 4)
    for nm in ("gps_time", "user_data", "point_source_id", "scan_angle"):
        if nm in f:
            rec[nm] = f[nm]
    if cloud.intensity is not None:
        rec["intensity"] = cloud.intensity
    if cloud.classification is not None:
        rec["classification"] = cloud.classification
    if cloud.colors is not None:
        for j, c in enumerate(("red", "green", "blue")):
            rec[c] = cloud.colors[:, j].astype(np.uint16) * 257
    write_records(fh, rec, scale, offset)


def _tree_for(records, scale, offset, center, half, node_points, leaf_points, fine=FINE_DEPTH) -> _Octree:
    xyz = np.stack([records[c] * scale[j] + offset[j] for j, c in enumerate("XYZ")], axis=1)
    probe = _Octree(center - half, half, fine, np.zeros(1, np.int64), np.ones(1))
    codes, counts = _count_cells(iter([probe.fine_codes(xyz)]))
    return _Octree(center - half, half, fine, codes, counts, node_points, leaf_points)


# --------------------------------------------------------------------------- streaming rewrite


def _apply_block(src: CopcFile, records: np.ndarray, block: PointBlock) -> np.ndarray:
    """The records of ``block`` after an edit: ``block.records`` with X/Y/Z
    quantized from ``block.xyz`` (only where they changed, so the others keep
    their integers bit for bit), RGB from ``block.colour`` where its high
    byte changed, intensity from ``block.intensity``."""
    rec = (records[block.row] if block.records is None else block.records).copy()
    ints = np.rint((block.xyz - src.offset) / src.scale)
    if len(ints) and (ints.min() < -2**31 or ints.max() > 2**31 - 1):
        raise InputError("an edited point does not fit LAS's 32-bit integers", path=str(src.path))
    for j, c in enumerate("XYZ"):
        col = ints[:, j].astype(np.int64)
        changed = col != rec[c]
        rec[c][changed] = col[changed]
    if block.colour is not None and src.has_colour:
        for j, c in enumerate(("red", "green", "blue")):
            changed = (rec[c] >> 8) != block.colour[:, j]
            rec[c][changed] = block.colour[changed, j].astype(np.uint16) * 257
    if block.intensity is not None:
        rec["intensity"] = block.intensity
    return rec


def _cells_at(src: CopcFile, rec: np.ndarray, depth: int) -> np.ndarray:
    """(n, 3) int64 the cells at ``depth`` of the points ``rec``; raises
    :class:`InputError` for points outside the root cube."""
    xyz = src.positions(rec)
    n = 1 << depth
    f = (xyz - src.bounds[0]) * (n / (2 * src.halfsize))
    c = np.floor(f).astype(np.int64)
    # a point on a cube's far face belongs to the cube (closed cells at the border)
    c = np.where((c == n) & (f <= n), n - 1, c)
    if len(c) and (c.min() < 0 or c.max() >= n):
        bad = int(np.flatnonzero((c < 0).any(axis=1) | (c >= n).any(axis=1))[0])
        raise InputError(f"an edit moved a point to {xyz[bad].tolist()}, outside the octree's root cube "
                         f"{src.bounds.tolist()} (convert the result again to grow the octree)",
                         path=str(src.path))
    return c


def rewrite_copc(src: CopcFile, dst_path, edit: Callable[[CopcNode, PointBlock], PointBlock | None],
                 progress=None, *, only: Iterable[NodeKey] | None = None) -> WriteReport:
    """Write ``src`` to ``dst_path`` node by node with ``edit`` applied.

    ``edit(node, block)`` gets each node (of ``only``, by default every
    node) with its decoded points and returns the edited block (same or
    fewer points: ``block.take(mask)`` deletes; ``xyz``, ``colour`` and
    ``intensity`` may change) or None to leave the node as it is.  Nodes not
    edited (None, or not in ``only``) are copied verbatim: their compressed
    bytes, not decoded.  A point whose new position leaves its node's cube
    moves to the node of the same depth that contains it (decoded and
    re-encoded with the arrivals, or created, with the hierarchy entries
    above it); the header's count, return counts and bounds (the source's
    box grown by the re-encoded points) follow.  Written to a temporary file
    beside ``dst_path`` and renamed (``dst_path`` may be ``src.path``: the
    source is read to the end first).

    Memory: the edited nodes' points (the edit's region), nothing else.

    Raises:
        InputError: an edited point outside the root cube (the octree would
        have to grow: convert the file again) or outside LAS's integers.
    """
    from splatedit.atomic import atomic_open
    keys = list(src.nodes) if only is None else [k for k in only if k in src.nodes]
    keys.sort(key=lambda k: src.nodes[k].offset)
    kept: dict[NodeKey, np.ndarray] = {}
    arrivals: dict[NodeKey, list[np.ndarray]] = {}
    before = np.zeros(15, np.int64)
    moved = 0
    total_pts = max(sum(src.nodes[k].point_count for k in keys), 1)
    done = 0
    report(progress, "editing COPC nodes", 0.0)
    for key in keys:
        node = src.nodes[key]
        _, rec = src.read_records([key])
        block = src.block([key], rec)
        out = edit(node, block)
        done += node.point_count
        report(progress, "editing COPC nodes", done / total_pts)
        if out is None:
            continue
        before += np.bincount(rec["returns"] & 0x0F, minlength=16)[1:16]
        new = _apply_block(src, rec, out)
        cells = _cells_at(src, new, key.depth)
        home = (cells[:, 0] == key.x) & (cells[:, 1] == key.y) & (cells[:, 2] == key.z)
        kept[key] = new[home]
        if not home.all():
            away = ~home
            moved += int(away.sum())
            ac = cells[away]
            ar = new[away]
            uniq, inv = np.unique(ac, axis=0, return_inverse=True)
            inv = inv.reshape(-1)
            for i, (x, y, z) in enumerate(uniq.tolist()):
                arrivals.setdefault(NodeKey(key.depth, x, y, z), []).append(ar[inv == i])
    order = sorted(src.nodes.values(), key=lambda n: n.offset)
    new_keys = sorted(k for k in arrivals if k not in src.nodes)
    total_bytes = max(sum(n.byte_size for n in order), 1)
    rep = WriteReport(Path(dst_path), 0, 0, moved=moved)
    h = src._h
    src_fd = src._fd
    with atomic_open(dst_path, "wb") as fh:
        w = _Writer(fh, point_format=src.point_format, record_length=src.record_length, scale=src.scale,
                    offset=src.offset, center=src.center, halfsize=src.halfsize, spacing=src.spacing,
                    laszip_vlr=src.laszip_vlr, vlrs=src._vlrs, evlrs=src._evlrs, template=h)
        w.gps = list(src.gps_range)
        done = 0
        report(progress, "writing COPC", 0.0)
        for node in order:
            k = node.key
            if k in kept or k in arrivals:
                if k in kept:
                    rec = kept.pop(k)
                else:
                    _, rec = src.read_records([k])
                    before += np.bincount(rec["returns"] & 0x0F, minlength=16)[1:16]
                parts = [rec] + arrivals.pop(k, [])
                rec = np.concatenate(parts) if len(parts) > 1 else rec
                if len(rec):
                    w.add_records(k, rec)
                    rep.encoded += 1
            else:
                w.add_chunk(k, node.point_count,
                            _pread(src_fd, node.byte_size, node.offset, str(src.path), f"node {_kt(k)}"))
                rep.copied += 1
            done += node.byte_size
            report(progress, "writing COPC", done / total_bytes)
        for k in new_keys:
            w.add_records(k, np.concatenate(arrivals.pop(k)))
            rep.created += 1
        # statistics: the source's, with the re-encoded nodes' replaced
        count = sum(c for _, _, c in w.entries.values())
        by_return = np.maximum(np.asarray(h.by_return, np.int64) - before + w.by_return, 0)
        mins = np.minimum(src.point_bounds[0], w.mins)
        maxs = np.maximum(src.point_bounds[1], w.maxs)
        w.finish(point_count=count, mins=mins, maxs=maxs, by_return=by_return)
        rep.bytes = fh.tell()
    rep.point_count = count
    rep.nodes = len(w.entries)
    report(progress, "writing COPC", 1.0)
    return rep


# --------------------------------------------------------------------------- out-of-core build


def build_copc(dst_path, chunks: Callable[[], Iterator[np.ndarray]], *, point_format: int, scale, offset,
               mins, maxs, node_points: int = NODE_POINTS, leaf_points: int = LEAF_POINTS,
               vlrs=(), progress=None, tmp_dir=None, count: int | None = None) -> WriteReport:
    """Write a COPC file from point records streamed in chunks, in bounded
    memory (about three chunks).

    Args:
        chunks: ``chunks()`` yields arrays of records (:func:`record_dtype`
            of ``point_format``, no extra bytes) on the grid ``scale`` /
            ``offset``; it is called twice and must yield the same points.
        mins, maxs: (3,) a box holding every point (file units; the LAS
            header's).
        vlrs: (user, id, description, data) VLRs to keep (a CRS).
        tmp_dir: where the bucketed points are spilled (default: beside
            ``dst_path``; about ``record_length`` bytes a point).
        count: the number of points, when known (for the progress of the
            first pass).

    Passes: (1) count the points per cell of octree level ``FINE_DEPTH``;
    (2) assign each point its node (:class:`_Octree`), sort each chunk by
    node and append it to a spill file; (3) per node, gather its runs from
    the spill file, compress, append to the COPC file.
    """
    from splatedit.atomic import atomic_open
    scale, offset = np.asarray(scale, float), np.asarray(offset, float)
    center, half = _cube(mins, maxs, scale)
    probe = _Octree(center - half, half, FINE_DEPTH, np.zeros(1, np.int64), np.ones(1))
    dt = record_dtype(point_format, _RECORD_BYTES[point_format])

    def xyz_of(rec):
        return np.stack([rec[c] * scale[j] + offset[j] for j, c in enumerate("XYZ")], axis=1)

    n_total = 0
    seen_lo, seen_hi = np.full(3, np.inf), np.full(3, -np.inf)

    def counted():
        nonlocal n_total, seen_lo, seen_hi
        n_total = 0
        for rec in chunks():
            n_total += len(rec)
            xyz = xyz_of(rec)
            if len(xyz):
                seen_lo = np.minimum(seen_lo, xyz.min(axis=0))
                seen_hi = np.maximum(seen_hi, xyz.max(axis=0))
            report(progress, "counting points", n_total / count if count else 0.0)
            yield probe.fine_codes(xyz)

    codes, counts = _count_cells(counted())
    if n_total == 0:
        raise InputError("zero points: nothing to write", path=str(dst_path))
    if np.any(seen_lo < center - half) or np.any(seen_hi > center + half):
        # the box given (a stale LAS header) does not hold the points: count again in theirs
        center, half = _cube(seen_lo, seen_hi, scale)
        probe = _Octree(center - half, half, FINE_DEPTH, np.zeros(1, np.int64), np.ones(1))
        codes, counts = _count_cells(counted())
    report(progress, "counting points", 1.0)
    tree = _Octree(center - half, half, FINE_DEPTH, codes, counts, node_points, leaf_points)
    tmp_dir = Path(dst_path).parent if tmp_dir is None else Path(tmp_dir)
    runs = []
    with tempfile.TemporaryFile(dir=tmp_dir, prefix=".splatedit-copc-spill-") as spill:
        pos = 0
        seen = 0
        for ci, rec in enumerate(chunks()):
            rec = np.asarray(rec, dtype=dt)
            u = np.random.default_rng([0, ci]).random(len(rec))
            depth, code = tree.assign(tree.fine_codes(xyz_of(rec)), u)
            gid = (depth.astype(np.int64) << 40) | code
            order = np.argsort(gid, kind="stable")
            gid = gid[order]
            data = rec[order]
            ug, starts, cnt = np.unique(gid, return_index=True, return_counts=True)
            spill.write(data.tobytes())
            runs.append((pos, ug, starts, cnt))
            pos += data.nbytes
            seen += len(rec)
            report(progress, "sorting points into the octree", seen / n_total)
        spill.flush()
        fd = spill.fileno()
        all_g = np.unique(np.concatenate([r[1] for r in runs]))
        with atomic_open(dst_path, "wb") as fh:
            w = _Writer(fh, point_format=point_format, record_length=dt.itemsize, scale=scale, offset=offset,
                        center=center, halfsize=half, spacing=tree.spacing, vlrs=vlrs)
            for i, g in enumerate(all_g.tolist()):
                parts = []
                for rpos, ug, starts, cnt in runs:
                    j = int(np.searchsorted(ug, g))
                    if j < len(ug) and ug[j] == g:
                        raw = os.pread(fd, int(cnt[j]) * dt.itemsize, rpos + int(starts[j]) * dt.itemsize)
                        parts.append(np.frombuffer(raw, dtype=dt))
                rec = np.concatenate(parts) if len(parts) > 1 else parts[0]
                w.add_records(tree.key_of(g >> 40, g & ((1 << 40) - 1)), rec)
                if i % 8 == 0:
                    report(progress, "writing COPC", (i + 1) / len(all_g))
            w.finish()
            size = fh.tell()
    report(progress, "writing COPC", 1.0)
    return WriteReport(Path(dst_path), n_total, len(w.entries), encoded=len(w.entries), bytes=size)


def las_records(points, point_format: int) -> np.ndarray:
    """Records of COPC point format ``point_format`` (6, 7 or 8) from a
    laspy point record of any LAS point format (same integers; legacy
    formats' 3-bit return fields and scan angle rank converted to 1.4's;
    extra bytes dropped)."""
    names = set(points.point_format.dimension_names)
    rec = np.zeros(len(points), dtype=record_dtype(point_format, _RECORD_BYTES[point_format]))
    for c in "XYZ":
        rec[c] = points[c]
    for nm in ("intensity", "classification", "user_data", "point_source_id", "gps_time"):
        if nm in names:
            rec[nm] = points[nm]
    rn = np.asarray(points["return_number"], np.uint8) if "return_number" in names else 1
    nr = np.asarray(points["number_of_returns"], np.uint8) if "number_of_returns" in names else 1
    rec["returns"] = (np.asarray(rn) & 0x0F) | ((np.asarray(nr) & 0x0F) << 4)
    flags = np.zeros(len(points), np.uint8)
    for bit, nm in ((4, "scanner_channel"), (6, "scan_direction_flag"), (7, "edge_of_flight_line")):
        if nm in names:
            flags |= (np.asarray(points[nm], np.uint8) << bit).astype(np.uint8)
    for bit, nm in ((0, "synthetic"), (1, "key_point"), (2, "withheld"), (3, "overlap")):
        if nm in names:
            flags |= np.asarray(points[nm], np.uint8).astype(np.uint8) << bit
    rec["flags"] = flags
    if "scan_angle" in names:
        rec["scan_angle"] = points["scan_angle"]
    elif "scan_angle_rank" in names:
        rec["scan_angle"] = np.rint(np.asarray(points["scan_angle_rank"], float) / 0.006).astype(np.int16)
    if point_format in (7, 8) and {"red", "green", "blue"} <= names:
        for c in ("red", "green", "blue"):
            rec[c] = points[c]
    if point_format == 8 and "nir" in names:
        rec["nir"] = points["nir"]
    return rec


# --------------------------------------------------------------------------- regions as splat clouds


def file_origin(src: CopcFile) -> np.ndarray:
    """(3,) float64 the origin :func:`splatedit.io.read` gives the whole
    file (:func:`splatedit.io.las.grid_origin` of the header's box): a
    region read out of core has the same local coordinates as the file read
    whole, so edit scripts and the editor's coordinates agree."""
    from splatedit.io.las import grid_origin
    return grid_origin(src.point_bounds[0], src.point_bounds[1], src.scale, src.offset)


def cloud_of_block(src: CopcFile, block: PointBlock, progress=None):
    """A :class:`~splatedit.model.cloud.SplatCloud` of ``block``'s points
    as :func:`splatedit.io.las.read_las` builds one (local coordinates about
    :func:`file_origin`, the integers' exact differences times the scale;
    RGB or grey from intensity; classification; normals and splat sizes
    estimated from the block's own points), with the block's row of each
    splat in ``point_fields['copc_block_row']`` (it follows subsets)."""
    from splatedit.io._build import build_cloud
    from splatedit.io.las import grey_from_intensity
    from splatedit.model.cloud import Quantization
    origin = file_origin(src)
    rec = block.records
    ref = np.round((origin - src.offset) / src.scale).astype(np.int64)
    pos = np.empty((len(rec), 3), dtype=np.float64)
    for j, c in enumerate("XYZ"):
        if np.any(origin != 0):
            pos[:, j] = (rec[c].astype(np.int64) - ref[j]) * src.scale[j]
        else:
            pos[:, j] = rec[c] * src.scale[j] + src.offset[j]
    if block.colour is not None:
        colors = np.full((len(rec), 4), 255, np.uint8)
        colors[:, :3] = block.colour
    else:
        colors = grey_from_intensity(rec["intensity"])
    quant = Quantization(tuple(src.scale.tolist()), tuple(src.offset.tolist()), src.point_format)
    return build_cloud(src.path, pos, colors=colors, progress=progress, origin=origin, already_local=True,
                       intensity=rec["intensity"].copy(), classification=rec["classification"].copy(),
                       quantization=quant,
                       point_fields={"copc_block_row": np.arange(len(rec), dtype=np.int64)})


# --------------------------------------------------------------------------- level of detail


def choose_nodes(src, eye, view_projection, fov_deg: float, size, *, budget: int,
                 refine_px: float) -> list[NodeKey]:
    """The nodes to draw for a camera at ``eye`` ((3,) file units) with the
    world -> clip matrix ``view_projection`` ((4, 4), file units, Vulkan depth
    0..1) and a vertical field of view of ``fov_deg`` degrees, for an image of
    ``size`` (w, h): Potree's rule as the editor applies it
    (:func:`splatedit.model.octree_lod.select_nodes`, one rule for both):
    from the root, the candidate whose point spacing (``src.spacing /
    2**depth``) projects largest at its nearest point is taken while the
    points stay within ``budget``, and its children become candidates while
    that spacing projects above ``refine_px`` pixels; nodes outside the view
    frustum are not refined.  Empty nodes the hierarchy lists (structure
    keys) are walked through, so their children stay reachable.

    Returns:
        list of NodeKey with points (parents before children).
    """
    from splatedit.model.octree_lod import OctreeView, select_nodes
    keyed = {(k.depth, k.x, k.y, k.z): k for k in list(src.nodes) + list(src.structure_keys)}
    nodes = {t: _LodNode(src.nodes[k].point_count if k in src.nodes else 0, src.node_bounds(k))
             for t, k in keyed.items()}
    view = OctreeView(np.asarray(eye, dtype=np.float64), np.asarray(view_projection, dtype=np.float64),
                      math.radians(fov_deg), int(size[1]))
    choice = select_nodes(nodes, float(src.spacing), view, budget=budget, min_px=refine_px)
    return [keyed[t] for t in choice.keys if keyed[t] in src.nodes]


@dataclass(frozen=True)
class _LodNode:
    """A node as :func:`~splatedit.model.octree_lod.select_nodes` reads it."""
    point_count: int
    bounds: np.ndarray
