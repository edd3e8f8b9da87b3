"""Bit-exact round trips through our PLY writer for every input variant."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from splatedit.io import read, write
from tests.io._plyutil import grid_mesh, make_ply


def sphere(n, seed=0):
    rng = np.random.default_rng(seed)
    p = rng.normal(size=(n, 3))
    return p / np.linalg.norm(p, axis=1, keepdims=True)


def assert_same(a, b):
    for name in ("positions", "u", "v", "colors", "faces"):
        x, y = getattr(a, name), getattr(b, name)
        if x is None or y is None:
            assert x is None and y is None, name
            continue
        assert x.dtype == y.dtype and x.shape == y.shape, name
        assert x.tobytes() == y.tobytes(), f"{name} differs bitwise"


def roundtrip(tmp_path, src, tag=""):
    first = read(src)
    out_bin = write(tmp_path / f"out{tag}.ply", first)
    out_txt = write(tmp_path / f"out{tag}_ascii.ply", first, binary=False)
    for out in (out_bin, out_txt):
        again = read(out)
        assert_same(first, again)
    return first


VARIANTS = list(itertools.product([False, True], ["<", ">"], ["f4", "f8"]))


@pytest.mark.parametrize("text,order,fdtype", VARIANTS)
def test_point_cloud_with_normals_roundtrips_bitwise(tmp_path, text, order, fdtype):
    p = sphere(300)
    src = make_ply(tmp_path / "in.ply", p, text=text, byte_order=order, fdtype=fdtype, normals=p)
    c = roundtrip(tmp_path, src)
    assert np.array_equal(c.positions, p.astype(fdtype).astype(np.float64))
    assert np.all(np.einsum("ij,ij->i", c.normals, p) > 0.999)


@pytest.mark.parametrize("text,order,fdtype", VARIANTS)
def test_colours_uchar_and_float_roundtrip_bitwise(tmp_path, text, order, fdtype):
    rng = np.random.default_rng(1)
    p = sphere(200)
    cols = rng.integers(0, 256, size=(200, 4)).astype(np.uint8)
    src = make_ply(tmp_path / "u.ply", p, text=text, byte_order=order, fdtype=fdtype, normals=p,
                   colors=cols)
    c = roundtrip(tmp_path, src, "u")
    assert np.array_equal(c.colors, cols)
    fcols = rng.random((200, 3)).astype(fdtype)
    src = make_ply(tmp_path / "f.ply", p, text=text, byte_order=order, fdtype=fdtype, normals=p,
                   colors=fcols, color_dtype=fdtype)
    c = roundtrip(tmp_path, src, "f")
    assert np.array_equal(c.colors[:, :3], np.rint(fcols.astype(np.float64) * 255).astype(np.uint8))
    assert np.all(c.colors[:, 3] == 255)


@pytest.mark.parametrize("text,order", [(False, "<"), (True, "<"), (False, ">")])
def test_radius_and_normals_give_splats_of_that_radius(tmp_path, text, order):
    p = sphere(150)
    r = np.linspace(0.05, 0.1, 150)
    src = make_ply(tmp_path / "r.ply", p, text=text, byte_order=order, fdtype="f8", normals=p,
                   radius=r)
    c = roundtrip(tmp_path, src)
    assert np.allclose(np.linalg.norm(c.u, axis=1), r, rtol=1e-12)
    assert np.allclose(np.linalg.norm(c.v, axis=1), r, rtol=1e-12)


@pytest.mark.parametrize("text,order,fdtype", VARIANTS)
def test_mesh_with_polygons_roundtrips_bitwise_with_fan_triangles(tmp_path, text, order, fdtype):
    verts, quads = grid_mesh()
    src = make_ply(tmp_path / "m.ply", verts, text=text, byte_order=order, fdtype=fdtype,
                   faces=quads)
    c = roundtrip(tmp_path, src)
    q = np.asarray(quads)
    expect = np.stack([q[:, [0, 1, 2]], q[:, [0, 2, 3]]], axis=1).reshape(-1, 3)
    assert np.array_equal(c.faces, expect)


def test_triangle_mesh_binary_uses_fast_path_and_roundtrips(tmp_path):
    verts, quads = grid_mesh()
    tris = [[a, b, c] for a, b, c, d in quads] + [[a, c, d] for a, b, c, d in quads]
    src = make_ply(tmp_path / "t.ply", verts, fdtype="f8", faces=tris)
    c = roundtrip(tmp_path, src)
    assert np.array_equal(c.faces, np.asarray(tris))


def test_our_axes_are_used_as_stored(tmp_path):
    p = sphere(100)
    u = np.cross(p, [0.0, 0.0, 1.0]) + np.cross(p, [1.0, 0, 0]) * 1e-3
    v = np.cross(p, u)
    axes = np.hstack([u * 0.03, v * 0.02])
    src = make_ply(tmp_path / "a.ply", p, fdtype="f8", axes=axes)
    c = roundtrip(tmp_path, src)
    assert np.array_equal(c.u, axes[:, :3]) and np.array_equal(c.v, axes[:, 3:])


def test_estimated_splats_roundtrip_bitwise(tmp_path):
    src = make_ply(tmp_path / "bare.ply", sphere(400), fdtype="f8")
    roundtrip(tmp_path, src)


def test_unknown_extra_properties_and_elements_are_ignored(tmp_path):
    p = sphere(50)
    extra = {"intensity": np.arange(50, dtype=np.float32), "label": np.arange(50, dtype=np.int32),
             "segment_index": np.ones(50, dtype=np.uint16)}
    src = make_ply(tmp_path / "x.ply", p, normals=p, extra=extra)
    c = read(src)
    assert c.n == 50 and c.colors is None


def test_writer_output_is_binary_little_endian_double(tmp_path):
    c = read(make_ply(tmp_path / "in.ply", sphere(20), normals=sphere(20)))
    out = write(tmp_path / "o.ply", c)
    head = out.read_bytes().split(b"end_header")[0].decode()
    assert "format binary_little_endian 1.0" in head
    for prop in ("double x", "double ux", "double vz", "float nx"):
        assert f"property {prop}\n" in head


@pytest.mark.parametrize("colors", [False, True])
def test_vectorised_ascii_reader_equals_plyfile_reader(tmp_path, monkeypatch, colors):
    import splatedit.io.ply as ply
    verts, quads = grid_mesh()
    rng = np.random.default_rng(2)
    cols = rng.integers(0, 256, size=(len(verts), 3)).astype(np.uint8) if colors else None
    src = make_ply(tmp_path / "a.ply", verts, text=True, fdtype="f4", colors=cols, faces=quads)
    assert ply._read_ascii_fast(src, None) is not None
    fast = read(src)
    monkeypatch.setattr(ply, "_read_ascii_fast", lambda *a: None)
    assert_same(fast, read(src))


def test_the_up_axis_written_into_a_ply_header_is_what_the_reader_detects(tmp_path):
    """The editor saves the up axis it shows (U, or detected) as
    ``comment up_axis ...``: the saved file opens standing the same way."""
    from splatedit.data import default_model_path
    from splatedit.io import read, write
    from splatedit.model.orientation import UpSource, detect_cloud_up_axis, header_up_hint
    cloud = read(default_model_path())
    for label in ("+Z", "-X"):
        out = write(tmp_path / f"up{label[1]}.ply", cloud, up_axis=label)
        hint = header_up_hint(out)
        assert hint.label == label and hint.source is UpSource.FILE_HEADER
        up = detect_cloud_up_axis(read(out), out)
        assert up.label == label
    plain = write(tmp_path / "plain.ply", cloud)
    assert header_up_hint(plain) is None
    import pytest
    with pytest.raises(ValueError):
        write(tmp_path / "bad.ply", cloud, up_axis="Z-up")
