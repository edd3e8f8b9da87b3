"""COPC files (splatedit.io.copc): written and read by region and level
(checked against laspy's CopcReader), rewritten node by node (untouched
nodes byte for byte, moved points re-homed), built out of core, converted
and cached."""

from __future__ import annotations

import os

import numpy as np
import pytest

from splatedit.errors import InputError
from splatedit.io.copc import (CopcFile, NodeKey, build_copc, make_records, record_dtype, rewrite_copc,
                               write_copc)
from splatedit.io.copc_convert import cached_copc, convert_to_copc

laspy = pytest.importorskip("laspy")

SCALE = np.array([0.001, 0.001, 0.001])
OFFSET = np.array([500_000.0, 5_000_000.0, 0.0])
#: small nodes, so that 40k points make a tree of 3-4 levels
LAYOUT = dict(node_points=1500, leaf_points=4000)


def _records(n=40_000, seed=0):
    """Format-7 records of a wavy 60 x 60 m terrain with unique GPS times."""
    r = np.random.default_rng(seed)
    xy = r.random((n, 2)) * 60
    z = 10 + 2 * np.sin(xy[:, 0] / 5) * np.cos(xy[:, 1] / 7) + r.normal(0, 0.02, n)
    xyz = np.column_stack([xy, z]) + OFFSET + [3, 4, 0]
    rec = make_records(xyz, SCALE, OFFSET, colour=r.integers(0, 256, (n, 3), dtype=np.uint8),
                       intensity=r.integers(0, 65536, n).astype(np.uint16))
    rec["gps_time"] = np.arange(n) * 1e-3
    rec["classification"] = 2
    return rec


@pytest.fixture(scope="module")
def copc_path(tmp_path_factory):
    rec = _records()
    p = tmp_path_factory.mktemp("copc") / "terrain.copc.laz"
    write_copc(p, None, records=rec, scale=SCALE, offset=OFFSET, **LAYOUT)
    return p, rec


def _ints(points) -> np.ndarray:
    """(n, 4) int64 X, Y, Z and GPS time (in ms) sorted by GPS time."""
    a = np.column_stack([np.asarray(points["X"]), np.asarray(points["Y"]), np.asarray(points["Z"]),
                         np.rint(np.asarray(points["gps_time"]) * 1e3)]).astype(np.int64)
    return a[np.argsort(a[:, 3])]


def test_write_then_read_by_region_and_level_gives_the_source_integers_like_laspy(copc_path):
    path, rec = copc_path
    f = CopcFile.open(path)
    assert f.point_count == len(rec) and f.max_depth >= 2 and f.has_colour
    every = f.read(f.nodes)
    assert np.array_equal(_ints(every.records), _ints(rec))              # bit-exact integers
    assert np.allclose(every.xyz, f.positions(every.records))
    with laspy.CopcReader.open(str(path)) as rd:
        assert np.array_equal(_ints(rd.query()), _ints(rec))
        for level in range(f.max_depth + 1):
            ours = f.read([n.key for n in f.select() if n.key.depth == level])
            assert np.array_equal(_ints(ours.records), _ints(rd.query(level=level))), level
        lo = OFFSET + [20, 10, 0]
        hi = OFFSET + [35, 30, 20]
        ours = f.read(f.select(np.stack([lo, hi]), max_depth=2))
        inside = np.all((ours.xyz >= lo) & (ours.xyz <= hi), axis=1)
        theirs = rd.query(bounds=laspy.copc.Bounds(mins=lo, maxs=hi), level=range(0, 3))
        assert inside.sum() == len(theirs) > 0
        assert np.array_equal(_ints(ours.records[inside]), _ints(theirs))


def test_every_point_lies_in_its_node_cube_and_colours_are_the_high_byte(copc_path):
    path, rec = copc_path
    f = CopcFile.open(path)
    b = f.read(f.nodes)
    for i, k in enumerate(b.keys):
        m = b.node == i
        cube = f.node_bounds(k)
        assert np.all(b.xyz[m] >= cube[0]) and np.all(b.xyz[m] <= cube[1])
        assert np.array_equal(b.row[m], np.arange(m.sum()))
    assert np.array_equal(b.colour[:, 0], (b.records["red"] >> 8).astype(np.uint8))
    assert np.array_equal(b.intensity, b.records["intensity"])


def test_rewrite_without_edit_copies_every_node_byte_for_byte(copc_path, tmp_path):
    path, _ = copc_path
    f = CopcFile.open(path)
    rep = rewrite_copc(f, tmp_path / "same.copc.laz", lambda node, block: None)
    assert rep.copied == len(f.nodes) and rep.encoded == 0
    g = CopcFile.open(tmp_path / "same.copc.laz")
    assert set(g.nodes) == set(f.nodes)
    for k in f.nodes:
        assert g.read_compressed(k) == f.read_compressed(k)
    assert (tmp_path / "same.copc.laz").read_bytes() == path.read_bytes()


def test_edit_moving_points_across_node_borders_keeps_a_valid_copc(copc_path, tmp_path):
    path, rec = copc_path
    f = CopcFile.open(path)
    deep = max(f.nodes, key=lambda k: (k.depth, f.nodes[k].point_count))
    shift = 2 * f.halfsize / (1 << deep.depth)          # one cell of that depth along x

    def edit(node, block):
        if node.key != deep:
            return None
        block.xyz[: len(block) // 2, 0] += shift * 0.7
        block.xyz[len(block) // 2:, 1] -= shift * 0.3
        return block.take(np.arange(len(block)) % 10 != 0)         # and drop every 10th point

    out = tmp_path / "moved.copc.laz"
    rep = rewrite_copc(f, out, edit, only=[deep])
    g = CopcFile.open(out)
    dropped = (f.nodes[deep].point_count + 9) // 10
    assert g.point_count == rep.point_count == len(rec) - dropped
    assert rep.moved > 0 and rep.copied >= len(f.nodes) - 3
    b = g.read(g.nodes)
    for i, k in enumerate(b.keys):
        m = b.node == i
        cube = g.node_bounds(k)
        assert np.all(b.xyz[m] >= cube[0] - 1e-9) and np.all(b.xyz[m] <= cube[1] + 1e-9), k
    for k in g.nodes:                                   # every node's ancestors are listed
        while k.depth:
            k = k.parent()
            assert k in g.nodes or k in g.structure_keys
    with laspy.CopcReader.open(str(out)) as rd:
        assert np.array_equal(_ints(rd.query()), _ints(b.records))
    las = laspy.read(str(out))
    assert len(las.points) == g.point_count
    assert np.isclose(las.header.maxs[0], max(b.xyz[:, 0].max(), f.point_bounds[1][0]))
    # the nodes that neither were edited nor received points are the source's bytes
    same = [k for k in f.nodes if k != deep and k in g.nodes and g.nodes[k].point_count == f.nodes[k].point_count]
    assert len(same) >= len(f.nodes) - 3
    assert all(g.read_compressed(k) == f.read_compressed(k) for k in same)
    assert rep.created + rep.encoded >= 2                 # the edited node and where its points went


def test_edit_outside_the_root_cube_is_refused_naming_the_file(copc_path, tmp_path):
    path, _ = copc_path
    f = CopcFile.open(path)
    k = next(iter(f.nodes))

    def edit(node, block):
        block.xyz[0, 0] += 10 * f.halfsize
        return block

    with pytest.raises(InputError, match="outside the octree's root cube") as exc:
        rewrite_copc(f, tmp_path / "x.copc.laz", edit, only=[k])
    assert str(path) in str(exc.value)
    assert not (tmp_path / "x.copc.laz").exists()


def test_out_of_core_build_in_chunks_holds_the_same_points_as_a_write_in_memory(tmp_path):
    rec = _records(30_000, seed=3)
    xyz = np.column_stack([rec[c] * SCALE[j] + OFFSET[j] for j, c in enumerate("XYZ")])
    rep = build_copc(tmp_path / "chunked.copc.laz", lambda: iter(np.array_split(rec, 7)), point_format=7,
                     scale=SCALE, offset=OFFSET, mins=xyz.min(0), maxs=xyz.max(0), **LAYOUT)
    assert rep.point_count == len(rec)
    f = CopcFile.open(tmp_path / "chunked.copc.laz")
    assert f.max_depth >= 1 and len(f.nodes) > 5
    assert np.array_equal(_ints(f.read(f.nodes).records), _ints(rec))
    # a box too small for the points (a stale LAS header) is grown, not clamped into
    build_copc(tmp_path / "stale.copc.laz", lambda: iter(np.array_split(rec, 3)), point_format=7,
               scale=SCALE, offset=OFFSET, mins=xyz.min(0) + 10, maxs=xyz.max(0) - 10, **LAYOUT)
    g = CopcFile.open(tmp_path / "stale.copc.laz")
    b = g.read(g.nodes)
    for i, k in enumerate(b.keys):
        cube = g.node_bounds(k)
        assert np.all(b.xyz[b.node == i] >= cube[0]) and np.all(b.xyz[b.node == i] <= cube[1])


def test_convert_las_to_copc_streams_keeping_integers_returns_and_classes(tmp_path):
    rec = _records(25_000, seed=5)
    hdr = laspy.LasHeader(point_format=3, version="1.2")
    hdr.scales, hdr.offsets = SCALE, OFFSET
    las = laspy.LasData(hdr)
    las.X, las.Y, las.Z = rec["X"], rec["Y"], rec["Z"]
    las.intensity = rec["intensity"]
    las.classification = np.arange(len(rec)) % 7
    las.return_number = 1 + np.arange(len(rec)) % 3
    las.number_of_returns = np.full(len(rec), 3)
    las.gps_time = rec["gps_time"]
    las.red, las.green, las.blue = rec["red"], rec["green"], rec["blue"]
    las.write(str(tmp_path / "src.las"))
    rep = convert_to_copc(tmp_path / "src.las", tmp_path / "out.copc.laz", chunk_points=6000, **LAYOUT)
    assert rep.point_count == len(rec)
    got = laspy.read(str(tmp_path / "out.copc.laz"))
    assert got.header.point_format.id == 7
    src = laspy.read(str(tmp_path / "src.las"))

    def table(l):
        a = np.column_stack([l.X, l.Y, l.Z, l.classification, l.return_number, l.number_of_returns, l.red,
                             np.rint(np.asarray(l.gps_time) * 1e3)]).astype(np.int64)
        return a[np.argsort(a[:, -1])]
    assert np.array_equal(table(got), table(src))


def test_convert_ply_to_copc_and_back_through_the_registry(tmp_path):
    from splatedit.data import default_model_path
    from splatedit.io import convert, read
    from splatedit.io.formats import format_of
    assert format_of("A.COPC.LAZ").name.startswith("COPC") and format_of("a.laz").name == "LAS/LAZ"
    src = read(default_model_path())
    convert(default_model_path(), tmp_path / "bunny.copc.laz")
    assert CopcFile.open(tmp_path / "bunny.copc.laz").point_count == src.n
    back = convert(tmp_path / "bunny.copc.laz", tmp_path / "bunny.ply")
    world = src.positions + src.origin
    got = back.positions + back.origin
    # order follows the octree; the grid is LAS_DEFAULT_SCALE
    key = lambda a: a[np.lexsort(np.round(a / 0.001).T.astype(np.int64))]      # noqa: E731
    assert np.abs(key(got) - key(world)).max() <= 0.0005 + 1e-12


def test_cached_copc_converts_once_and_again_when_the_source_changes(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    rec = _records(3000, seed=7)
    hdr = laspy.LasHeader(point_format=7, version="1.4")
    hdr.scales, hdr.offsets = SCALE, OFFSET
    las = laspy.LasData(hdr)
    las.X, las.Y, las.Z = rec["X"], rec["Y"], rec["Z"]
    las.write(str(tmp_path / "scan.laz"))
    first = cached_copc(tmp_path / "scan.laz")
    assert first.parent == tmp_path / "cache" / "splatedit" / "copc" and first.name.endswith(".copc.laz")
    stamp = first.stat().st_mtime_ns
    assert cached_copc(tmp_path / "scan.laz") == first and first.stat().st_mtime_ns == stamp
    las.X = rec["X"] + 1
    las.write(str(tmp_path / "scan.laz"))
    os.utime(tmp_path / "scan.laz", ns=(stamp + 10**9, stamp + 10**9))
    assert cached_copc(tmp_path / "scan.laz") != first
    copc = tmp_path / "cache" / "splatedit" / "copc"
    assert len(list(copc.glob("*.copc.laz"))) == 2
    assert cached_copc(first) == first                       # a COPC file is its own cache


def test_record_dtype_matches_laspy_point_formats():
    for fmt in (6, 7, 8):
        assert record_dtype(fmt, laspy.PointFormat(fmt).size).itemsize == laspy.PointFormat(fmt).size
    assert record_dtype(6, 33)["extra"].shape == (3,)
    assert NodeKey(2, 3, 1, 0).parent() == NodeKey(1, 1, 0, 0)
    assert NodeKey(1, 1, 0, 0) in [c.parent() for c in NodeKey(1, 1, 0, 0).children()]


#: a COPC hierarchy entry (the specification's layout)
ENTRY = np.dtype([("d", "<i4"), ("x", "<i4"), ("y", "<i4"), ("z", "<i4"), ("offset", "<u8"),
                  ("byte_size", "<i4"), ("point_count", "<i4")])


def _split_hierarchy(src, dst):
    """``src`` with its one hierarchy page split as other writers (PDAL,
    untwine) lay it out: a root page with the root and one -1 entry per
    depth-1 node pointing at a child page with that node and its subtree."""
    import struct
    data = bytearray(src.read_bytes())
    root_off, root_size = struct.unpack_from("<QQ", data, 375 + 54 + 40)
    e = np.frombuffer(bytes(data[root_off:root_off + root_size]), dtype=ENTRY)
    assert root_off - 60 + 60 + root_size == len(data)          # the page is the file's last EVLR
    d1 = e[e["d"] == 1]
    root = [e[e["d"] == 0]]
    body = root_off + (1 + len(d1)) * 32
    children = []
    for k in d1:
        sub = e[(e["d"] >= 1) & ((e["x"] >> (e["d"] - 1)) == k["x"]) & ((e["y"] >> (e["d"] - 1)) == k["y"])
                & ((e["z"] >> (e["d"] - 1)) == k["z"])]
        ptr = k.copy()
        ptr["offset"], ptr["byte_size"], ptr["point_count"] = body, len(sub) * 32, -1
        root.append(np.array([ptr], dtype=ENTRY))
        children.append(sub)
        body += len(sub) * 32
    pages = np.concatenate(root).tobytes() + b"".join(c.tobytes() for c in children)
    out = data[:root_off] + pages
    struct.pack_into("<QQ", out, 375 + 54 + 40, root_off, (1 + len(d1)) * 32)
    struct.pack_into("<Q", out, root_off - 60 + 20, len(pages))       # the EVLR's record length
    dst.write_bytes(bytes(out))


def test_a_hierarchy_in_several_pages_reads_like_one(copc_path, tmp_path):
    path, rec = copc_path
    split = tmp_path / "paged.copc.laz"
    _split_hierarchy(path, split)
    f, g = CopcFile.open(path), CopcFile.open(split)
    assert {k: (n.offset, n.point_count) for k, n in f.nodes.items()} == \
        {k: (n.offset, n.point_count) for k, n in g.nodes.items()}
    with laspy.CopcReader.open(str(split)) as rd:
        assert len(rd.root_page.entries) < len(f.nodes)             # laspy must follow the child pages
        assert np.array_equal(_ints(rd.query()), _ints(rec))
    lo, hi = OFFSET + [10, 10, 0], OFFSET + [30, 30, 20]
    assert np.array_equal(_ints(g.read(g.select(np.stack([lo, hi]))).records),
                          _ints(f.read(f.select(np.stack([lo, hi]))).records))
