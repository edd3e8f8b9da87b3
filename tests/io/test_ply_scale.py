"""Binary PLY at scale: the chunked reader equals plyfile's, names absolute
rows, stays within 1.5x the arrays it keeps; far coordinates are rebased."""

from __future__ import annotations

import tracemalloc

import numpy as np
import plyfile
import pytest

from splatedit.errors import InputError
from splatedit.io import read, write
from splatedit.io import _plybinary as plymod
from tests.io._plyutil import make_ply


def _sphere_splats(n, seed=0):
    rng = np.random.default_rng(seed)
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    a = np.where(np.abs(p[:, [0]]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    t1 = np.cross(p, a)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(p, t1)
    s = 2 * np.sqrt(4 * np.pi / n)
    return p, np.hstack([s * t1, s * t2])


@pytest.mark.parametrize("order", ["<", ">"])
def test_chunked_binary_read_equals_plyfile_across_chunks(tmp_path, monkeypatch, order):
    p, axes = _sphere_splats(5000)
    colors = np.random.default_rng(1).integers(0, 256, size=(5000, 4)).astype(np.uint8)
    path = make_ply(tmp_path / "s.ply", p, fdtype="f8", byte_order=order, axes=axes, colors=colors)
    monkeypatch.setattr(plymod, "PLY_READ_CHUNK_BYTES", 7 * 1000)   # many chunks, a ragged last one
    c = read(path)
    ref = plyfile.PlyData.read(str(path))["vertex"].data
    assert np.array_equal(c.positions, np.column_stack([ref[k] for k in "xyz"]).astype(np.float64))
    assert np.array_equal(c.u, np.column_stack([ref[k] for k in ("ux", "uy", "uz")]).astype(np.float64))
    assert np.array_equal(c.v, np.column_stack([ref[k] for k in ("vx", "vy", "vz")]).astype(np.float64))
    assert np.array_equal(c.colors, colors)


def test_nan_in_a_later_chunk_names_the_absolute_row(tmp_path, monkeypatch):
    p, axes = _sphere_splats(3000)
    axes[2345, 4] = np.nan
    path = make_ply(tmp_path / "n.ply", p, fdtype="f8", axes=axes)
    monkeypatch.setattr(plymod, "PLY_READ_CHUNK_BYTES", 1000 * 72)
    with pytest.raises(InputError) as info:
        read(path)
    msg = str(info.value)
    assert "row 2345" in msg and "property 'vy'" in msg and "NaN" in msg


def test_truncated_body_names_the_first_missing_row(tmp_path, monkeypatch):
    p, axes = _sphere_splats(3000)
    path = make_ply(tmp_path / "t.ply", p, fdtype="f8", axes=axes)
    data = path.read_bytes()
    path.write_bytes(data[:-72 * 500 - 10])       # the last 500 rows and part of one more
    monkeypatch.setattr(plymod, "PLY_READ_CHUNK_BYTES", 1000 * 72)
    with pytest.raises(InputError) as info:
        read(path)
    assert "row 2499" in str(info.value) and "early end-of-file" in str(info.value)


def test_peak_memory_of_a_read_is_at_most_1_5x_the_arrays_kept(tmp_path):
    from splatedit.bench.io import write_sphere_ply
    path = tmp_path / "big.ply"
    write_sphere_ply(path, 400_000)
    tracemalloc.start()
    try:
        c = read(path)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    kept = c.positions.nbytes + c.u.nbytes + c.v.nbytes
    assert peak <= 1.5 * kept, (peak / kept)


def test_utm_coordinates_are_rebased_and_written_back_bit_exactly(tmp_path):
    p, axes = _sphere_splats(2000)
    world = p * 50 + np.array([512_345.678, 5_123_456.789, 312.5])
    world = np.round(world, 3)
    path = make_ply(tmp_path / "utm.ply", world, fdtype="f8", axes=axes * 50)
    c = read(path)
    assert np.abs(c.origin).max() > 5e6 and np.abs(c.positions).max() < 100
    # float32 (the GPU's precision) of the local coordinates keeps sub-mm steps
    assert np.abs(c.positions.astype(np.float32) - c.positions).max() < 1e-5
    assert np.array_equal(c.world_positions(), world)
    write(tmp_path / "out.ply", c)
    back = plyfile.PlyData.read(str(tmp_path / "out.ply"))["vertex"].data
    assert np.array_equal(np.column_stack([back[k] for k in "xyz"]), world)


def test_subset_and_replace_keep_the_origin_and_scan_attributes(tmp_path):
    p, axes = _sphere_splats(500)
    world = p * 10 + np.array([600_000.0, 4_000_000.0, 0.0])
    c = read(make_ply(tmp_path / "o.ply", world, fdtype="f8", axes=axes * 10))
    c.intensity = np.arange(500, dtype=np.uint16)
    s = c.subset(np.arange(0, 500, 2))
    assert np.array_equal(s.origin, c.origin) and np.array_equal(s.intensity, c.intensity[::2])
    r = c.replace(positions=c.positions + 1.0)
    assert np.array_equal(r.origin, c.origin) and r.intensity is c.intensity


@pytest.mark.parametrize("binary", [True, False])
def test_ply_keeps_intensity_and_classification(tmp_path, binary):
    p, axes = _sphere_splats(300)
    c = read(make_ply(tmp_path / "i.ply", p, fdtype="f8", axes=axes))
    c.intensity = (np.arange(300) * 200).astype(np.uint16)
    c.classification = (np.arange(300) % 19).astype(np.uint8)
    write(tmp_path / "o.ply", c, binary=binary)
    back = read(tmp_path / "o.ply")
    assert np.array_equal(back.intensity, c.intensity)
    assert np.array_equal(back.classification, c.classification)
    assert back.colors is None


def test_bench_io_quick_compares_readers_in_one_run_and_las_is_exact():
    from splatedit.bench.io import bench_io
    lines = list(bench_io(quick=True))
    reads = {ln["reader"]: ln for ln in lines if ln["case"] == "ply_read"}
    assert set(reads) == {"splatedit", "plyfile", "open3d"}
    ours = reads["splatedit"]
    assert ours["n"] == ours["splats"] == 200_000 and ours["seconds"] > 0
    assert ours["peak_over_kept"] <= 1.5        # the memory bound, measured in a fresh process
    las = [ln for ln in lines if ln["case"] in ("las_read", "laz_read")]
    assert len(las) == 2 and all(ln["mm_exact"] for ln in las)
