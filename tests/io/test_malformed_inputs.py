"""Every kind of bad input is an InputError naming the file and the place."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.errors import InputError
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
