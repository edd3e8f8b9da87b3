"""The lean reading of `splatedit info` (splatedit.io.read_summary): a binary
splat PLY read keeping only centres and radii gives what the full reader
gives, and a file the full reader refuses is refused with its message."""

from __future__ import annotations

import json

import numpy as np
import pytest

from splatedit.errors import InputError
from splatedit.io import read, read_summary, write
from splatedit.model.cloud import SplatCloud
from tests.io._plyutil import make_ply


def _scan(n=20_000, seed=3):
    """A georeferenced wavy tile of splats with colours and intensities."""
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0, 50, size=(n, 2))
    world = np.column_stack([xy[:, 0] + 512_345.0, xy[:, 1] + 5_123_456.0,
                             300 + np.sin(xy[:, 0] / 5)])
    t = rng.normal(size=(n, 3))
    u = np.cross(t, [0.0, 0.0, 1.0])
    u *= (0.05 * rng.uniform(0.5, 1.5, n) / np.linalg.norm(u, axis=1))[:, None]
    v = np.cross([0.0, 0.0, 1.0], u) * rng.uniform(0.3, 1.0, n)[:, None]
    origin = np.round(world.mean(0))
    colors = rng.integers(0, 256, size=(n, 4)).astype(np.uint8)
    return SplatCloud(world - origin, u, v, colors, origin=origin,
                      intensity=rng.integers(0, 65535, n).astype(np.uint16))


def test_lean_summary_equals_the_full_read(tmp_path):
    path = tmp_path / "scan.ply"
    write(path, _scan())
    lean = read_summary(path, lean_above=0)
    full = read(path)
    assert lean.cloud is None and lean.n == full.n
    assert np.array_equal(lean.origin, full.origin) and full.origin.any()
    assert np.array_equal(lean.positions, full.positions)
    assert np.array_equal(lean.radii, full.radii)
    for a, b in zip(lean.bounds(), full.bounds()):
        assert np.array_equal(a, b)
    assert (lean.colors, lean.intensity, lean.classification) == (True, True, False)
    rows = np.arange(0, full.n, 97)
    assert np.allclose(lean.normals_at(rows), full.normals_at(rows), rtol=0, atol=1e-12)
    # below the limit (or for another format) the whole cloud is read
    assert read_summary(path, lean_above=full.n).cloud is not None


@pytest.mark.parametrize("bad", ["nan", "parallel", "short"])
def test_lean_summary_refuses_what_the_reader_refuses(tmp_path, bad):
    c = _scan(2000)
    u, v = c.u.copy(), c.v.copy()
    row = 1234
    if bad == "nan":
        v[row, 1] = np.nan
    elif bad == "parallel":
        v[row] = 2.0 * u[row]
    else:
        u[row] *= 1e-12
    path = make_ply(tmp_path / f"{bad}.ply", c.world_positions(), fdtype="f8", axes=np.hstack([u, v]))
    with pytest.raises(InputError) as full:
        read(path)
    with pytest.raises(InputError) as lean:
        read_summary(path, lean_above=0)
    assert str(lean.value) == str(full.value) and f"row {row}" in str(full.value)


def test_info_prints_the_same_through_the_lean_and_the_full_read(tmp_path, monkeypatch, capsys):
    from splatedit import tolerances
    from splatedit.cli import main
    from splatedit.io import _plysummary
    path = tmp_path / "scan.ply"
    write(path, _scan())
    monkeypatch.setattr(tolerances, "INFO_EXACT_MAX_POINTS", 1000)
    outs = []
    for lean in (True, False):
        if not lean:
            monkeypatch.setattr(_plysummary, "read_ply_summary", lambda *a, **k: None)
        assert main(["-q", "info", "--json", str(path)]) == 0
        outs.append(json.loads(capsys.readouterr().out))
    assert outs[0] == outs[1]
    assert "spacing" in outs[0]["estimated"] and outs[0]["colors"] and outs[0]["intensity"]


def _normals_radius_file(tmp_path, name="nr.ply", n=20_000, fdtype="f4", zero_normal_row=None,
                         bad_radius_row=None):
    c = _scan(n)
    nrm = np.cross(c.u, c.v)
    radius = np.linalg.norm(c.u, axis=1)
    if zero_normal_row is not None:
        nrm[zero_normal_row] = 0.0
    if bad_radius_row is not None:
        radius[bad_radius_row] = -1.0
    return make_ply(tmp_path / name, c.world_positions(), fdtype=fdtype, normals=nrm, radius=radius,
                    colors=c.colors)


@pytest.mark.parametrize("fdtype", ["f4", "f8"])
def test_lean_summary_of_a_normals_and_radius_file_equals_the_full_read(tmp_path, fdtype):
    """Files with normals and a radius per point (scanner pipelines, Open3D)
    take the lean path too: the file's radii, no estimation."""
    path = _normals_radius_file(tmp_path, fdtype=fdtype)
    lean = read_summary(path, lean_above=0)
    full = read(path)
    assert lean.cloud is None and lean.n == full.n
    assert np.array_equal(lean.origin, full.origin)
    assert np.array_equal(lean.positions, full.positions)
    np.testing.assert_allclose(lean.radii, full.radii, rtol=1e-12)
    rows = np.arange(0, full.n, 97)
    assert np.allclose(lean.normals_at(rows), full.normals_at(rows), rtol=0, atol=1e-6)


def test_a_normals_and_radius_file_with_a_zero_normal_or_bad_radius_takes_the_full_read(tmp_path):
    path = _normals_radius_file(tmp_path, "zero.ply", n=3000, zero_normal_row=17)
    assert read_summary(path, lean_above=0).cloud is not None        # the full reader fills the normal
    path = _normals_radius_file(tmp_path, "neg.ply", n=3000, bad_radius_row=1234)
    with pytest.raises(InputError, match="row 1234"):
        read_summary(path, lean_above=0)


def test_a_normals_and_radius_file_too_small_to_measure_is_refused_by_the_lean_read_too(tmp_path):
    """The lean pass of a normals + radius file makes the full reader's extent
    check (a model under MIN_EXTENT_ABS across): the same one-line error."""
    rng = np.random.default_rng(4)
    pts = rng.normal(size=(500, 3)) * 1e-60
    nrm = rng.normal(size=(500, 3))
    path = make_ply(tmp_path / "tiny.ply", pts, fdtype="f8", normals=nrm, radius=np.full(500, 1e-61))
    with pytest.raises(InputError) as full:
        read(path)
    with pytest.raises(InputError) as lean:
        read_summary(path, lean_above=0)
    assert str(lean.value) == str(full.value) and "across" in str(full.value)
