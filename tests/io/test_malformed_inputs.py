"""Every kind of bad input is an InputError naming the file and the place."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.errors import InputError, InputWarning
from splatedit.io import read
from tests.io._plyutil import make_ply

P = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.1], [0.5, 0.5, 0.3]])
N = np.tile([0.0, 0.0, 1.0], (5, 1))


def ascii_ply(body_lines, header_props="property float x\nproperty float y\nproperty float z\n",
              count=None, extra_elements=""):
    count = len(body_lines) if count is None else count
    head = f"ply\nformat ascii 1.0\nelement vertex {count}\n{header_props}{extra_elements}end_header\n"
    return (head + "".join(line + "\n" for line in body_lines)).encode()


XYZ_OK = ["0 0 0", "1 0 0", "0 1 0", "1 1 0.1"]


def truncated_binary(tmp_path):
    path = make_ply(tmp_path / "t.ply", P, fdtype="f8", normals=N)
    data = path.read_bytes()
    path.write_bytes(data[:-20])
    return path


def nan_binary(tmp_path):
    q = P.copy()
    q[3, 1] = np.nan
    return make_ply(tmp_path / "nan.ply", q, fdtype="f8")


def mesh_bad_index(tmp_path):
    return make_ply(tmp_path / "mesh.ply", P, faces=[[0, 1, 2], [1, 3, 7]])


def dup_binary(tmp_path):
    path = make_ply(tmp_path / "dupb.ply", P, fdtype="f8", normals=N)
    data = path.read_bytes()
    head, body = data.split(b"end_header\n", 1)
    head = head.replace(b"property double z\n", b"property double z\nproperty double x\n", 1)
    # one more double per row: rebuild the body with 7 columns
    rows = np.frombuffer(body, dtype="<f8").reshape(len(P), 6)
    path.write_bytes(head + b"end_header\n" + np.column_stack([rows[:, :3], rows[:, :1], rows[:, 3:]]).astype("<f8").tobytes())
    return path


CASES = [
    # (id, file name, content bytes or builder, expected substrings)
    ("truncated binary ply", "t.ply", truncated_binary, ["early end-of-file", "truncated"]),
    ("vertex count too large", "c.ply", ascii_ply(["0 0 0", "1 0 0", "0 1 0"], count=5),
     ["element 'vertex'", "row 3", "early end-of-file"]),
    ("nan in binary ply", "nan.ply", nan_binary, ["row 3", "property 'y'", "NaN"]),
    ("inf in ascii ply", "inf.ply", ascii_ply(["0 0 0", "1 inf 0", "0 1 0"]),
     ["row 1", "property 'y'", "infinite"]),
    ("missing z", "noz.ply", ascii_ply(["0 0", "1 0"], "property float x\nproperty float y\n"),
     ["missing property 'z'"]),
    ("empty ply", "empty.ply", b"", ["expected 'ply'"]),
    ("not a ply", "junk.ply", b"hello world\n", ["expected 'ply'"]),
    ("zero vertices ply", "zero.ply", ascii_ply([]), ["zero vertices"]),
    ("malformed ascii ply token", "tok.ply", ascii_ply(["0 0 0", "1 x 0"]),
     ["row 1", "property 'y'", "malformed input"]),
    ("face index out of range ply", "mesh.ply", mesh_bad_index,
     ["element 'face'", "row 1", "out of range"]),
    ("empty xyz", "empty.xyz", b"", ["empty file"]),
    ("only comments xyz", "c.xyz", b"# nothing\n\n   \n", ["empty file"]),
    ("bad xyz token", "tok.xyz", ("\n".join(XYZ_OK[:2] + ["1 abc 3"] + XYZ_OK[2:]) + "\n").encode(),
     ["line 3", "row", "not a number: 'abc'"]),
    ("bad xyz token after comments", "tok2.xyz",
     ("# header\n\n" + "\n".join(XYZ_OK) + "\n0 0 1,5\n").encode(), ["line 7", "'1,5'"]),
    ("wrong column count xyz", "col.xyz", ("\n".join(XYZ_OK[:3] + ["1 2"]) + "\n").encode(),
     ["wrong column count", "line 4", "row 3"]),
    ("four columns xyz", "c4.xyz", b"1 2 3 4\n", ["expected 3 columns", "got 4"]),
    ("nan xyz", "nan.xyz", b"0 0 0\n1 1 nan\n0 1 0\n", ["row 1", "property 'z'", "NaN", "line 2"]),
    ("inf normal xyz", "inf.xyz", b"0 0 0 0 0 1\n1 1 0 0 -inf 1\n0 1 0 0 0 1\n",
     ["row 1", "property 'ny'", "infinite"]),
    ("empty off", "e.off", b"", ["empty file"]),
    ("not off", "x.off", b"PLY\n1 2 3\n", ["not an OFF file"]),
    ("off counts too large", "n.off", b"OFF\n5 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", ["truncated"]),
    ("off counts too small", "s.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n",
     ["after the last face", "line 7"]),
    ("off bad counts line", "b.off", b"OFF\n3 x 0\n0 0 0\n", ["counts must be integers"]),
    ("off missing counts", "m.off", b"OFF\n", ["before the counts"]),
    ("off zero vertices", "z.off", b"OFF\n0 0 0\n", ["zero vertices"]),
    ("off face index out of range", "f.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
     ["element 'face'", "row 0", "out of range", "line 6"]),
    ("off short face", "g.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", [">= 3"]),
    ("off vertex with 2 numbers", "v.off", b"OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n",
     ["vertex line has 2 numbers", "line 4"]),
    ("off nan vertex", "nan.off", b"OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n",
     ["row 1", "property 'y'", "NaN"]),
    # issue 12 class 1: tracebacks from files
    ("duplicated property ascii ply", "dup.ply",
     ascii_ply(["0 0 0 0", "1 1 0 0", "0 0 1 0"],
               "property float x\nproperty float x\nproperty float y\nproperty float z\n"),
     ["header", "property 'x'", "declared twice"]),
    ("duplicated property binary ply", "dupb.ply", lambda tmp: dup_binary(tmp), ["declared twice", "'x'"]),
    ("coordinates near 1e155 xyz", "big.xyz", b"0 0 0\n1e155 0 0\n0 1e155 0\n0 0 1e155\n",
     ["row 1", "property 'x'", "1e+155", "supported magnitude", "line 2"]),
    ("coordinates near 1e155 ply", "big.ply", ascii_ply(["0 0 0", "1 0 0", "0 -1e155 0", "0 0 1"]),
     ["row 2", "property 'y'", "-1e+155", "does not fit the declared type float"]),
    ("coordinates near 1e155 double ply", "bigd.ply",
     ascii_ply(["0 0 0", "1 0 0", "0 -1e155 0", "0 0 1"],
               "property double x\nproperty double y\nproperty double z\n"),
     ["row 2", "property 'y'", "-1e+155", "supported magnitude"]),
    ("off face vertex count inf", "inf.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\ninf 0 1 2\n",
     ["element 'face'", "row 0", "got inf", "line 6"]),
    ("off face vertex count nan", "nan.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\nnan 0 1 2\n",
     ["element 'face'", "row 0", "got nan"]),
    # issue 12 class 2: values a written file could not hold
    ("radius 1e160 ply", "r.ply", ascii_ply(["0 0 0 0 0 1 1e160", "1 0 0 0 0 1 1", "0 1 0 0 0 1 1"],
                                            "property float x\nproperty float y\nproperty float z\n"
                                            "property float nx\nproperty float ny\nproperty float nz\n"
                                            "property double radius\n"),
     ["row 0", "property 'radius'", "1e+160", "supported magnitude"]),
    # issue 12 class 11: face indices beyond int64 are reported as read
    ("off face index 1e300", "i.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 1e300\n",
     ["element 'face'", "row 0", "vertex index 1e+300 out of range", "line 6"]),
    ("ply face index 1e300", "i.ply",
     ascii_ply(["0 0 0", "1 0 0", "0 1 0"], extra_elements="element face 1\n"
               "property list uchar float vertex_indices\n") + b"3 0 1 1e300\n",
     ["element 'face'", "row 0", "vertex index 1e+300 out of range"]),
    ("unknown extension", "model.stl", b"solid x\n", ["unsupported file extension", ".ply", ".off"]),
    ("missing file", None, None, ["cannot read file"]),
]


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_malformed_input_raises_input_error_with_message(tmp_path, case):
    _, name, content, expected = case
    if name is None:
        path = tmp_path / "does_not_exist.xyz"
    elif callable(content):
        path = content(tmp_path)
    else:
        path = tmp_path / name
        path.write_bytes(content)
    with pytest.raises(InputError) as info:
        read(path)
    msg = str(info.value)
    assert path.name in msg
    for sub in expected:
        assert sub in msg, f"{sub!r} not in {msg!r}"


def test_xyz_error_reports_line_attribute(tmp_path):
    path = tmp_path / "a.xyz"
    path.write_bytes(b"# c\n0 0 0\n\n1 2\n")
    with pytest.raises(InputError) as info:
        read(path)
    assert info.value.line == 4 and info.value.row == 1


@pytest.mark.parametrize("damage", ["nan position", "huge axis", "nan axis"])
def test_write_refuses_a_cloud_its_own_reader_would_reject(tmp_path, damage):
    """Issue 12 class 2: every written file passes the reader's validation, so a
    cloud damaged in place after construction is refused before writing."""
    from splatedit.data import default_model_path
    from splatedit.io import write
    cloud = read(default_model_path())
    if damage == "nan position":
        cloud.positions[7, 1] = np.nan
    elif damage == "huge axis":
        cloud.u[7] *= 1e160
    else:
        cloud.v[7, 0] = np.nan
    out = tmp_path / "out.ply"
    with pytest.raises(InputError) as info:
        write(out, cloud)
    assert "row 7" in str(info.value)
    assert not out.exists() and not list(tmp_path.iterdir())


def test_written_file_with_largest_accepted_values_reads_back(tmp_path):
    """Values at the magnitude limit survive a write/read round trip exactly."""
    from splatedit.io import write
    from splatedit.tolerances import MAX_COORDINATE_ABS
    q = P * MAX_COORDINATE_ABS
    cloud = read(make_ply(tmp_path / "in.ply", q, fdtype="f8", normals=N, radius=np.full(5, 0.3 * MAX_COORDINATE_ABS)))
    write(tmp_path / "out.ply", cloud)
    back = read(tmp_path / "out.ply")
    assert np.array_equal(back.positions, cloud.positions) and np.isfinite(back.normals).all()



@pytest.mark.parametrize("kind", ["ascii fast path", "ascii via plyfile", "binary with faces"])
def test_data_after_the_declared_rows_warns_with_file_and_amount(tmp_path, kind):
    """Issue 12 class 3: trailing rows are not dropped silently."""
    from splatedit.errors import InputWarning
    if kind == "ascii fast path":
        path = tmp_path / "a.ply"
        path.write_bytes(ascii_ply(XYZ_OK + ["0 0 1", "1 0 1"], count=4))
        expect = "2 data line(s) from line 12"
    elif kind == "ascii via plyfile":       # a list property: plyfile reads it
        path = tmp_path / "b.ply"
        path.write_bytes(ascii_ply([r + " 1 7" for r in XYZ_OK + ["0 0 1"]], count=4,
                                   header_props="property float x\nproperty float y\nproperty float z\n"
                                                "property list uchar int tag\n"))
        expect = "1 data line(s) from line 13"
    else:
        path = make_ply(tmp_path / "c.ply", P, fdtype="f8", normals=N, faces=[[0, 1, 2], [1, 3, 4, 2]])
        with open(path, "ab") as fh:
            fh.write(b"\0" * 17)
        expect = "17 byte(s)"
    with pytest.warns(InputWarning) as record:
        cloud = read(path)
    assert cloud.n in (4, 5)
    msg = str(record[0].message)
    assert str(path) in msg and expect in msg, msg


def test_exact_files_do_not_warn(tmp_path):
    import warnings
    path = make_ply(tmp_path / "c.ply", P, fdtype="f8", normals=N, faces=[[0, 1, 2], [1, 3, 4, 2]])
    q = tmp_path / "a.ply"
    q.write_bytes(ascii_ply(XYZ_OK))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read(path)
        read(q)


# ------------------------------------------ issue 21: scanner formats and Gaussians
def _las(tmp_path, name, *, edits=(), append=b"", cut=None, n=40):
    """A small LAS file (format 3, scale 0.01) with header fields overwritten:
    ``edits`` = (offset, struct format, value)."""
    import struct
    import laspy
    h = laspy.LasHeader(point_format=3, version="1.2")
    h.scales, h.offsets = [0.01] * 3, [0.0] * 3
    las = laspy.LasData(h)
    rng = np.random.default_rng(1)
    for d in "XYZ":
        las[d] = rng.integers(0, 1000, n)
    path = tmp_path / name
    las.write(str(path))
    data = bytearray(path.read_bytes())
    for off, fmt, value in edits:
        struct.pack_into("<" + fmt, data, off, value)
    path.write_bytes(bytes(data[:cut] if cut is not None else data) + append)
    return path


def _laz_chunks(tmp_path, chunks, table=None):
    """A LAZ file whose chunk table (its offset: the first 8 bytes of the
    point data) declares ``chunks`` chunks, or whose offset is ``table``."""
    import struct
    path = _las(tmp_path, "c.laz")
    data = bytearray(path.read_bytes())
    start = struct.unpack_from("<I", data, 96)[0]
    if table is not None:
        struct.pack_into("<q", data, start, table)
    else:
        at = struct.unpack_from("<q", data, start)[0]
        struct.pack_into("<I", data, at + 4, chunks)
    path.write_bytes(bytes(data))
    return path


def _las14_evlr(tmp_path, length):
    """A LAS 1.4 file with one extended variable-length record declaring ``length`` bytes."""
    import struct
    import laspy
    h = laspy.LasHeader(point_format=6, version="1.4")
    h.scales, h.offsets = [0.01] * 3, [0.0] * 3
    las = laspy.LasData(h)
    for d in "XYZ":
        las[d] = np.arange(40) * (3 if d == "X" else 1)
    path = tmp_path / "e.las"
    las.write(str(path))
    data = bytearray(path.read_bytes())
    size = len(data)
    data += struct.pack("<H16sHQ32s", 0, b"user", 1, length, b"hostile")
    struct.pack_into("<QI", data, 235, size, 1)
    path.write_bytes(bytes(data))
    return path


def _put(tmp_path, name, data):
    """Write ``data`` (bytes or str) to ``tmp_path / name``; returns the path."""
    path = tmp_path / name
    (path.write_bytes if isinstance(data, bytes) else path.write_text)(data)
    return path


def _pcd(head_fields="x y z", size="4 4 4", typ="F F F", count="1 1 1", points="3",
         data="ascii", body="0 0 0\n1 0 0\n0 1 0\n"):
    return (f"VERSION 0.7\nFIELDS {head_fields}\nSIZE {size}\nTYPE {typ}\nCOUNT {count}\nWIDTH 3\n"
            f"HEIGHT 1\nPOINTS {points}\nDATA {data}\n{body}").encode()


def _gaussians(tmp_path, name, column, row, value):
    import plyfile
    from splatedit.data import gaussian_scene_path
    v = plyfile.PlyData.read(str(gaussian_scene_path()))["vertex"].data.copy()
    if row is None:
        v[column] += value
    else:
        v[column][row] = value
    path = tmp_path / name
    plyfile.PlyData([plyfile.PlyElement.describe(v, "vertex")]).write(str(path))
    return path


NAN, INF = float("nan"), float("inf")
SCANNER_CASES = [
    # (id, builder(tmp_path) -> path, expected substrings); class 1 of issue 21
    ("las scale nan", lambda t: _las(t, "s.las", edits=[(131, "d", NAN)]), ["header: x scale is nan"]),
    ("las scale inf", lambda t: _las(t, "s.las", edits=[(147, "d", INF)]), ["z scale is inf"]),
    ("las scale 1e300", lambda t: _las(t, "s.las", edits=[(139, "d", 1e300)]),
     ["y scale 1e+300", "supported magnitude"]),
    ("las offset nan", lambda t: _las(t, "o.las", edits=[(155, "d", NAN)]), ["x offset is nan"]),
    ("las offset 1e300", lambda t: _las(t, "o.las", edits=[(171, "d", -1e300)]),
     ["z offset -1e+300", "supported magnitude"]),
    ("las coordinates beyond 1e15", lambda t: _las(t, "c.las", edits=[(131, "d", 1e13)]),
     ["x coordinate", "supported magnitude"]),
    # class 3: degenerate scale
    ("las scale 0", lambda t: _las(t, "z.las", edits=[(139, "d", 0.0)]), ["y scale 0 is degenerate"]),
    # class 4: lying counts
    ("las count above the records", lambda t: _las(t, "n.las", edits=[(107, "I", 5000)]),
     ["early end-of-file", "5000 points", "40 point records"]),
    ("laz count above the records", lambda t: _las(t, "n.laz", edits=[(107, "I", 5000)]),
     ["not a readable LAS/LAZ file"]),
    # class 2: header-driven allocations bounded by the file size
    ("las 4e9 points", lambda t: _las(t, "b.las", edits=[(107, "I", 2**32 - 1)]), ["early end-of-file"]),
    ("laz 4e9 points", lambda t: _las(t, "b.laz", edits=[(107, "I", 2**32 - 1)]),
     ["cannot be compressed into"]),
    ("laz chunk table count damaged", lambda t: _laz_chunks(t, 10**9), ["chunk table declares 1000000000"]),
    ("laz chunk table offset damaged", lambda t: _laz_chunks(t, None, table=10**9), ["chunk table offset"]),
    ("laz chunk size damaged", lambda t: _las(t, "k.laz", edits=[(227 + 54 + 12, "I", 534070706)]),
     ["534070706 points per chunk"]),
    ("las 1.4 extended record of 2**40 bytes", lambda t: _las14_evlr(t, 2**40),
     ["extended variable-length record 0", "1099511627776 bytes"]),
    ("las 1e9 variable-length records", lambda t: _las(t, "v.las", edits=[(100, "I", 10**9)]),
     ["variable-length records do not fit"]),
    ("las point data offset past the end", lambda t: _las(t, "p.las", edits=[(96, "I", 10**8)]),
     ["point data offset 100000000"]),
    ("las record length below the format", lambda t: _las(t, "r.las", edits=[(105, "H", 4)]),
     ["record length 4"]),
    ("las truncated header", lambda t: _las(t, "h.las", cut=100), ["truncated LAS header"]),
    ("lasf and random bytes", lambda t: _put(t, "x.las", b"LASF" + bytes(range(256)) * 2), ["header"]),
    ("pcd COUNT 3 for x", lambda t: _put(t, "c.pcd", _pcd(count="3 1 1")),
     ["field 'x' has COUNT 3 (must be 1)"]),
    ("pcd huge COUNT", lambda t: _put(t, "h.pcd",
        _pcd("x y z label", "4 4 4 4", "F F F U", "1 1 1 99999999999")),
     ["a row of", "cannot fit"]),
    ("pcd duplicate FIELDS", lambda t: _put(t, "d.pcd",
        _pcd("x y z x", "4 4 4 4", "F F F F", "1 1 1 1", body="0 0 0 0\n1 0 0 0\n0 1 0 0\n")),
     ["field 'x' is listed twice"]),
    ("pcd negative POINTS", lambda t: _put(t, "n.pcd", _pcd(points="-3")),
     ["POINTS -3 is negative"]),
    ("pcd POINTS 0", lambda t: _put(t, "z.pcd", _pcd(points="0", body="")),
     ["zero points"]),
    ("pcd int field overflow", lambda t: _put(t, "i.pcd",
        _pcd(typ="F F I", size="4 4 2", body="0 0 0\n1 0 1e30\n0 1 0\n")),
     ["row 1", "property 'z'", "does not fit the declared type int16"]),
    ("pcd binary POINTS above the data", lambda t: _put(t, "b.pcd",
        _pcd(points="9", data="binary", body="") + np.zeros((3, 3), "<f4").tobytes()),
     ["early end-of-file", "POINTS says 9", "3 rows"]),
    # class 6 / 8: Gaussian scenes name their own properties, one validation for every command
    ("gaussian scene at 1e20", lambda t: _gaussians(t, "far.ply", "x", None, 1e20),
     ["row 0", "property 'x'", "supported magnitude"]),
    ("gaussian huge log-scale", lambda t: _gaussians(t, "s.ply", "scale_1", 7, 60.0),
     ["row 7", "property 'scale_1'", "log-scale 60"]),
    # class 3: a model 1e-300 across
    ("xyz 1e-300 across", lambda t: _put(t, "t.xyz",
        "".join(f"{x}e-300 {y}e-300 {(x + y) % 3}e-300\n" for x in range(5) for y in range(5))),
     ["across", "smallest supported extent"]),
]


@pytest.mark.parametrize("build,expected", [c[1:] for c in SCANNER_CASES], ids=[c[0] for c in SCANNER_CASES])
def test_hostile_scanner_files_raise_one_input_error_naming_the_cause(tmp_path, build, expected):
    """Issue 21 classes 1-4, 6, 8: every reader validates what it reads (finite,
    non-degenerate scales, counts against the file size, field lists) before
    the library or numpy sees it."""
    import warnings
    path = build(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", InputWarning)
        with pytest.raises(InputError) as info:
            read(path)
    msg = str(info.value)
    assert path.name in msg and "\n" not in msg
    for sub in expected:
        assert sub in msg, f"{sub!r} not in {msg!r}"


SCANNER_WARNINGS = [
    # (id, builder, expected substrings of the one warning, points read); class 4
    ("las records after the count", lambda t: _las(t, "m.las", edits=[(107, "I", 25)]),
     ["15 point record(s) after the 25"], 25),
    ("pcd ascii rows after POINTS", lambda t: _put(t, "a.pcd", _pcd(points="2")),
     ["1 data line(s) from line 12", "after the 2 points"], 2),
    ("pcd binary bytes after POINTS", lambda t: _put(t, "b.pcd",
        _pcd(points="2", data="binary", body="") + np.eye(3, dtype="<f4").tobytes()),
     ["12 byte(s) after the 2 points"], 2),
]


@pytest.mark.parametrize("build,expected,n", [c[1:] for c in SCANNER_WARNINGS],
                         ids=[c[0] for c in SCANNER_WARNINGS])
def test_scanner_data_beyond_the_declared_count_warns_like_ply(tmp_path, build, expected, n):
    path = build(tmp_path)
    with pytest.warns(InputWarning) as record:
        cloud = read(path)
    assert cloud.n == n
    msg = str(record[0].message)
    assert str(path) in msg, msg
    for sub in expected:
        assert sub in msg, f"{sub!r} not in {msg!r}"
