"""Issue 12, property-based: generated PLY files and edit scripts against the
command-line contract.  Every run ends in exit 0 with a readable result, or
exit 2 with exactly one ``splatedit: error:`` line naming the file; never a
traceback (an exception out of ``main`` fails the test), within a deadline."""

from __future__ import annotations

import copy
import json
import struct

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from splatedit.cli import main
from splatedit.io import read

SETTINGS = settings(max_examples=40, deadline=3000, derandomize=True,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])

# --------------------------------------------------------------- PLY files
PROPS = ["x", "y", "z", "x", "nx", "ny", "nz", "radius", "red", "green", "blue", "alpha", "ux", "vz", "q"]
TYPES = ["float", "double", "uchar", "int", "short", "uint", "char"]
TOKENS = st.one_of(
    st.integers(-300, 300).map(str),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.sampled_from(["1e155", "-1e300", "1e-320", "nan", "inf", "0", "255", "256", "x", "", "1,5",
                     "9" * 40, "0x10", "+.5", "1e400"]))


@st.composite
def ply_files(draw):
    fmt = draw(st.sampled_from(["ascii", "ascii", "binary_little_endian", "binary_big_endian"]))
    if draw(st.booleans()):    # a plausible file: most of these read
        nrows = draw(st.integers(1, 40))
        pts = draw(st.lists(st.tuples(*[st.floats(-1e3, 1e3) | st.sampled_from([0.0, 1e14, 1e-300])] * 3),
                            min_size=nrows, max_size=nrows))
        extra = draw(st.sampled_from([0, 0, 1, -1]))
        body = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in pts)
        return (f"ply\nformat ascii 1.0\nelement vertex {nrows + extra}\nproperty double x\n"
                f"property double y\nproperty double z\nend_header\n{body}").encode()
    props = draw(st.lists(st.sampled_from(PROPS), min_size=0, max_size=7))
    if draw(st.booleans()):
        props = ["x", "y", "z"] + props
    types = [draw(st.sampled_from(TYPES)) for _ in props]
    nrows = draw(st.integers(0, 12))
    declared = draw(st.one_of(st.just(nrows), st.integers(0, 14), st.sampled_from([400_000_000, 2**31])))
    faces = draw(st.sampled_from([None, None, 1, 2, 10**9]))
    head = [b"ply", f"format {fmt} 1.0".encode(), f"element vertex {declared}".encode()]
    head += [f"property {t} {p}".encode() for t, p in zip(types, props)]
    if faces is not None:
        head += [f"element face {faces}".encode(), b"property list uchar int vertex_indices"]
    head.append(b"end_header")
    head = b"\n".join(head) + b"\n"
    if fmt == "ascii":
        rows = [" ".join(draw(st.lists(TOKENS, min_size=max(0, len(props) - 1), max_size=len(props) + 1)))
                for _ in range(nrows)]
        if faces is not None:
            rows += [" ".join(draw(st.lists(TOKENS, min_size=1, max_size=5))) for _ in range(min(faces, 3))]
        body = ("\n".join(rows) + "\n").encode()
    else:
        coords = draw(st.lists(st.floats(allow_nan=True, allow_infinity=True, width=32),
                               min_size=0, max_size=3 * nrows))
        order = "<" if fmt == "binary_little_endian" else ">"
        body = struct.pack(order + "f" * len(coords), *coords) + draw(st.binary(max_size=40))
    return head + body


def _check_contract(code: int, err: str, path) -> None:
    assert "Traceback" not in err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert all(ln.startswith(("splatedit: error: ", "splatedit: warning: ")) for ln in lines), err
    if code == 0:
        assert not any(ln.startswith("splatedit: error: ") for ln in lines), err
    else:
        assert code == 2, (code, err)
        errors = [ln for ln in lines if ln.startswith("splatedit: error: ")]
        assert len(errors) == 1 and str(path) in errors[0], err


@SETTINGS
@given(data=ply_files())
def test_generated_ply_files_keep_the_contract(tmp_path_factory, capsys, data):
    d = tmp_path_factory.mktemp("ply")
    path, out = d / "in.ply", d / "out.ply"
    path.write_bytes(data)
    code = main(["-q", "convert", str(path), str(out)])
    captured = capsys.readouterr()
    event(f"exit {code}")
    _check_contract(code, captured.err, path)
    if code == 0:
        back = read(out)           # whatever was written passes the reader's own checks
        assert back.n > 0 and np.isfinite(back.normals).all()
    else:
        assert not out.exists()


# ---------------------------------------------------------- OFF and XYZ text
@st.composite
def off_files(draw):
    kw = draw(st.sampled_from(["OFF", "COFF", "NOFF", "CNOFF", "off", ""]))
    nv, nf = draw(st.integers(0, 8)), draw(st.integers(0, 4))
    counts = draw(st.sampled_from([f"{nv} {nf} 0", f"{nv} {nf} 0", f"{nv} {nf}", "1e9 1 0", "inf 1 0", "-1 0 0",
                                   f"{nv} 99999999999 0"]))
    rows = [" ".join(draw(st.lists(TOKENS, min_size=0, max_size=8))) for _ in range(draw(st.integers(0, 12)))]
    # distinct, non-collinear vertices with a generated height
    good = [f"{i} {(i * i) % 7} {draw(st.floats(-5, 5))!r}" for i in range(nv)]
    index = st.integers(0, max(nv - 1, 0)) | st.sampled_from([-1, nv, 10 ** 30])
    fl = [f"3 {draw(index)} {draw(index)} {draw(index)}" for _ in range(nf)]
    body = draw(st.sampled_from([rows, good + fl, good + fl, good + rows]))
    return (kw + "\n" + counts + "\n" + "\n".join(body) + "\n").encode()

@st.composite
def xyz_files(draw):
    ncol = draw(st.sampled_from([3, 3, 6, 2, 4, 7]))
    rows = draw(st.integers(0, 30))
    if draw(st.integers(0, 3)) > 0:      # mostly plausible numbers: most of these read
        body = "\n".join(" ".join(repr(draw(st.floats(-1e3, 1e3) | st.sampled_from([0.0, 1e14, 1e-300, 5.0])))
                                  for _ in range(ncol)) for _ in range(rows))
    else:
        body = "\n".join(" ".join(draw(st.lists(TOKENS, min_size=1, max_size=7))) for _ in range(rows))
    return body.encode()


@SETTINGS
@given(content=off_files(), command=st.sampled_from(["info", "convert"]))
def test_generated_off_files_keep_the_contract(tmp_path_factory, capsys, content, command):
    _text_file_contract(tmp_path_factory, capsys, content, ".off", command)


@SETTINGS
@given(content=xyz_files(), command=st.sampled_from(["info", "convert"]))
def test_generated_xyz_files_keep_the_contract(tmp_path_factory, capsys, content, command):
    _text_file_contract(tmp_path_factory, capsys, content, ".xyz", command)


def _text_file_contract(tmp_path_factory, capsys, content: bytes, ext: str, command: str) -> None:
    d = tmp_path_factory.mktemp("text")
    path, out = d / f"in{ext}", d / "out.ply"
    path.write_bytes(content)
    argv = ["info", str(path), "--json"] if command == "info" else ["convert", str(path), str(out)]
    code = main(["-q", *argv])
    captured = capsys.readouterr()
    event(f"{ext} exit {code}")
    _check_contract(code, captured.err, path)
    if code == 0 and command == "info":
        assert json.loads(captured.out)["splats"] > 0
    if code == 0 and command == "convert":
        assert read(out).n > 0


# ------------------------------------------------------------- edit scripts
TEMPLATE = {"version": 1, "solver": {"method": "auto"}, "edits": [
    {"support": {"sphere": {"center": [0, 0, 1], "radius": 0.6}},
     "handle": {"sphere": {"center": [0, 0, 1], "radius": 0.2}},
     "transform": {"translate": [0, 0, 0.1], "rotate": {"axis": [0, 0, 1], "degrees": 10},
                   "scale": 1.1}},
    {"support": {"box": {"min": [-1, -1, 0], "max": [1, 1, 1.1]}},
     "curves": [{"points": [[-0.3, 0, 0.95], [0.3, 0, 0.95]], "move": [[0, 0, 0.05], [0, 0, 0.05]],
                 "samples": 12}]}]}

VALUES = st.one_of(
    st.integers(min_value=-(10 ** 30), max_value=10 ** 30), st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([10 ** 400, -1, 0, 2, 10_000_000, 1e9, 1e300, "up", None, True, [], {}, [1e308, 1e308, 0],
                     [0, 0, 0], [1, 2], [[0, 0, 0]] * 3, {"sphere": {}}]),
    st.lists(st.floats(-2, 2), min_size=3, max_size=3))


def _paths(doc, prefix=()):
    """Every key path of ``doc`` (dicts and lists)."""
    out = [prefix]
    if isinstance(doc, dict):
        for k, v in doc.items():
            out += _paths(v, prefix + (k,))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            out += _paths(v, prefix + (i,))
    return out


PATHS = _paths(TEMPLATE)[1:]


@st.composite
def scripts(draw):
    doc = copy.deepcopy(TEMPLATE)
    for _ in range(draw(st.integers(0, 3))):
        path = draw(st.sampled_from(PATHS))
        node = doc
        try:
            for k in path[:-1]:
                node = node[k]
            node[path[-1]] = draw(VALUES)
        except (KeyError, IndexError, TypeError):
            pass        # an earlier mutation replaced a parent
    text = json.dumps(doc, allow_nan=True)
    if draw(st.integers(0, 9)) == 0:
        text = text[:draw(st.integers(0, len(text)))]        # truncated JSON
    return text.encode()


@pytest.fixture(scope="module")
def sphere_ply(tmp_path_factory):
    from splatedit.io import write
    from splatedit.model.estimate import estimate_splats
    rng = np.random.default_rng(5)
    p = rng.normal(size=(600, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    path = tmp_path_factory.mktemp("sphere") / "sphere.ply"
    write(path, estimate_splats(p, normals=p))
    return path


@SETTINGS
@given(data=scripts())
def test_generated_edit_scripts_keep_the_contract(tmp_path_factory, capsys, sphere_ply, data):
    d = tmp_path_factory.mktemp("edit")
    script, out = d / "edit.json", d / "out.ply"
    script.write_bytes(data)
    code = main(["-q", "deform", str(sphere_ply), "--edit", str(script), "-o", str(out)])
    captured = capsys.readouterr()
    event(f"exit {code}")
    _check_contract(code, captured.err, script)
    if code == 0:
        assert read(out).n == 600
    else:
        assert not out.exists()
