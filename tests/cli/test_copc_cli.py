"""COPC files through the commands, out of core: ``deform`` reads only the
script's region and equals the same edit in memory; ``info`` reads header
and hierarchy only; ``render`` chooses nodes by level; damaged files give one
error line naming the file (exit 2)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from splatedit.io.copc import CopcFile, file_origin, make_records, write_copc

laspy = pytest.importorskip("laspy")

SCALE = np.array([0.001, 0.001, 0.001])
OFFSET = np.array([500_000.0, 5_000_000.0, 0.0])


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "splatedit.cli", "-q", *map(str, args)],
                          capture_output=True, text=True, timeout=120)


@pytest.fixture(scope="module")
def scan(tmp_path_factory):
    """A 60 x 60 m wavy terrain of 40k points (unique GPS times) as COPC, and
    a sphere edit (local coordinates) lifting a spot in its middle."""
    r = np.random.default_rng(11)
    n = 40_000
    xy = r.random((n, 2)) * 60
    z = 10 + 2 * np.sin(xy[:, 0] / 5) * np.cos(xy[:, 1] / 7) + r.normal(0, 0.01, n)
    rec = make_records(np.column_stack([xy, z]) + OFFSET, SCALE, OFFSET,
                       colour=r.integers(0, 256, (n, 3), dtype=np.uint8))
    rec["gps_time"] = np.arange(n) * 1e-3
    d = tmp_path_factory.mktemp("copccli")
    path = d / "terrain.copc.laz"
    write_copc(path, None, records=rec, scale=SCALE, offset=OFFSET, node_points=1500, leaf_points=4000)
    with CopcFile.open(path) as f:
        origin = file_origin(f)
    c = np.array([30.0, 30.0, 0.0]) + OFFSET - origin
    c[2] = 10 + 2 * np.sin(30 / 5) * np.cos(30 / 7)
    script = {"version": 1, "edits": [{"support": {"sphere": {"center": c.tolist(), "radius": 6.0}},
                                        "handle": {"sphere": {"center": c.tolist(), "radius": 1.5}},
                                        "transform": {"translate": [0.3, 0.0, 1.2]}}]}
    (d / "lift.json").write_text(json.dumps(script))
    return path, d / "lift.json", c, origin


def _table(path):
    las = laspy.read(str(path))
    a = np.column_stack([las.X, las.Y, las.Z, np.rint(np.asarray(las.gps_time) * 1e3)]).astype(np.int64)
    return a[np.argsort(a[:, 3])]


def test_deform_out_of_core_equals_the_edit_in_memory(scan, tmp_path):
    path, script, centre, origin = scan
    res = run_cli("deform", path, "--edit", script, "-o", tmp_path / "ooc.copc.laz")
    assert res.returncode == 0, res.stderr
    assert "copied" in res.stdout and "re-encoded" in res.stdout
    res = run_cli("deform", path, "--edit", script, "-o", tmp_path / "mem.laz")
    assert res.returncode == 0, res.stderr
    src, ooc, mem = _table(path), _table(tmp_path / "ooc.copc.laz"), _table(tmp_path / "mem.laz")
    assert np.array_equal(src[:, 3], ooc[:, 3]) and np.array_equal(src[:, 3], mem[:, 3])
    moved = np.any(ooc != src, axis=1)
    assert moved.sum() > 500
    world = src[:, :3] * SCALE + OFFSET - origin
    in_support = np.linalg.norm(world - centre, axis=1) <= 6.0
    assert not (moved & ~in_support).any()                       # only the support moved
    assert np.array_equal(ooc[~in_support], src[~in_support])    # bit-identical elsewhere
    assert np.abs(ooc - mem).max() <= 1                          # one millimetre step at most in the support
    # before quantization: the region's deformation equals the whole model's to 1e-6 of the diagonal
    from splatedit.commands.outofcore import edit_region
    from splatedit.io import read
    from splatedit.io.copc import cloud_of_block
    from splatedit.script import load_script, run_script
    s = load_script(script)
    whole = read(path)
    out_whole, _ = run_script(whole, s)
    with CopcFile.open(path) as f:
        block = f.read(f.select(edit_region(s, str(script)) + origin))
        region = cloud_of_block(f, block)
    out_region, _ = run_script(region, s)
    gps_whole = whole.point_fields["gps_time"]
    idx = np.searchsorted(gps_whole, block.records["gps_time"], sorter=np.argsort(gps_whole))
    idx = np.argsort(gps_whole)[idx]
    assert np.array_equal(whole.positions[idx], region.positions)
    diff = np.abs(out_whole.positions[idx] - out_region.positions).max()
    assert diff <= 1e-6 * whole.diagonal


def test_info_of_copc_reads_header_and_hierarchy_only(scan, monkeypatch, capsys):
    from splatedit.cli import main
    from splatedit.io import copc
    path = scan[0]

    def no_points(*a, **k):
        raise AssertionError("info decompressed points")
    monkeypatch.setattr(copc.CopcFile, "read_records", no_points)
    assert main(["-q", "info", str(path), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["kind"] == "COPC" and info["points"] == 40_000
    assert sum(info["points_per_level"]) == 40_000 and info["nodes"] == sum(info["nodes_per_level"])
    # the origin edit scripts are relative to: the one the file read whole gets
    from splatedit.io import read
    assert np.allclose(info["origin"], read(path).origin, rtol=0, atol=1e-9)


def _choose(f, eye, target, budget, refine_px):
    from splatedit.io.copc import choose_nodes
    from splatedit.render.camera import Camera
    cam = Camera(eye, target, up=(0.0, 0.0, 1.0), fov_deg=40.0, near=1e-3, far=1e5)
    vp = cam.projection_matrix(640 / 360, cam.near, cam.far) @ cam.view_matrix()
    return choose_nodes(f, eye, vp, 40.0, (640, 360), budget=budget, refine_px=refine_px)


def test_node_choice_refines_where_the_spacing_projects_above_the_threshold(scan):
    with CopcFile.open(scan[0]) as f:
        lo, hi = f.point_bounds
        eye = np.array([lo[0], lo[1], hi[2]]) + [-3.0, -3.0, 2.0]
        target = (lo + hi) / 2
        focal = 0.5 * 360 / np.tan(np.radians(40.0) / 2)

        def px(k):          # the node's point spacing seen from the eye at its cube's nearest point
            b = f.node_bounds(k)
            return f.spacing / (1 << k.depth) * focal / np.linalg.norm(np.clip(eye, b[0], b[1]) - eye)

        keys = _choose(f, eye, target, 10**9, 10.0)
        chosen = set(keys)
        assert keys[0].depth == 0 and len(chosen) == len(keys)
        for k in keys:
            if k.depth:      # a node is drawn only below a parent whose spacing projects above 10 px
                assert px(k.parent()) > 10.0
        refined = [k for k in keys if px(k) > 10.0]
        assert refined and len(refined) < len(keys)
        for k in refined:    # ... and such a parent's children are all drawn (they all face the camera here)
            assert all(c in chosen for c in k.children() if c in f.nodes)
        assert any(k.depth == f.max_depth for k in keys) and any(px(k) <= 10.0 for k in keys if k.depth < f.max_depth)
        small = _choose(f, eye, target, 5000, 1.0)
        assert sum(f.nodes[k].point_count for k in small) <= max(5000, f.nodes[keys[0]].point_count)
        far_eye = target + [0, -5000.0, 0]         # from 5 km the root alone is below a pixel
        assert _choose(f, far_eye, target, 10**9, 1.0) == [keys[0]]
        behind = _choose(f, eye, eye - (target - eye), 10**9, 1.0)
        assert len(behind) <= 1                    # looking away: nothing but (at most) the root


@pytest.mark.gpu
def test_render_out_of_core_draws_the_scan(scan, tmp_path):
    from PIL import Image
    png = tmp_path / "scan.png"
    res = run_cli("render", scan[0], "-o", png, "--size", "160x120")
    assert res.returncode == 0, res.stderr
    assert "out of core" in res.stdout
    img = np.asarray(Image.open(png))
    assert img.shape == (120, 160, 4)
    assert 0.02 < (img[..., :3].min(axis=2) < 250).mean() < 0.95


def _damaged(scan, tmp_path):
    """(name, file) damaged copies of the scan."""
    data = scan[0].read_bytes()
    out = []
    (tmp_path / "trunc.copc.laz").write_bytes(data[: len(data) // 2])
    out.append(tmp_path / "trunc.copc.laz")
    with CopcFile.open(scan[0]) as f:
        root = f.nodes[min(f.nodes)]
        hier = int(np.frombuffer(data[375 + 54 + 40: 375 + 54 + 48], "<u8")[0])
    bad = bytearray(data)                       # a hierarchy key outside the octree
    bad[hier + 4: hier + 8] = (1 << 20).to_bytes(4, "little")
    (tmp_path / "key.copc.laz").write_bytes(bytes(bad))
    out.append(tmp_path / "key.copc.laz")
    bad = bytearray(data)                       # garbage in the root node's compressed points
    bad[root.offset + 10: root.offset + 400] = bytes(range(256)) + bytes(134)
    (tmp_path / "chunk.copc.laz").write_bytes(bytes(bad))
    out.append(tmp_path / "chunk.copc.laz")
    src = laspy.read(str(scan[0]))              # a plain LAZ named .copc.laz
    hdr = laspy.LasHeader(point_format=7, version="1.4")
    hdr.scales, hdr.offsets = SCALE, OFFSET
    plain = laspy.LasData(hdr)
    plain.X, plain.Y, plain.Z = np.asarray(src.X), np.asarray(src.Y), np.asarray(src.Z)
    plain.write(str(tmp_path / "plain.copc.laz"))
    out.append(tmp_path / "plain.copc.laz")
    return out


def test_damaged_copc_files_give_one_error_line_naming_the_file(scan, tmp_path):
    for bad in _damaged(scan, tmp_path):
        for args in (("info", bad), ("deform", bad, "--edit", scan[1], "-o", tmp_path / "o.copc.laz", "--force")):
            res = run_cli(*args)
            if bad.name == "chunk.copc.laz" and args[0] == "info":
                assert res.returncode == 0, res.stderr      # info reads no point data
                continue
            assert res.returncode == 2, (bad.name, args[0], res.stdout, res.stderr)
            lines = res.stderr.strip().splitlines()
            assert len(lines) == 1 and lines[0].startswith("splatedit: error: ") and str(bad) in lines[0], \
                (bad.name, args[0], res.stderr)


def test_a_fifo_named_copc_is_refused_without_opening_it(tmp_path):
    fifo = tmp_path / "pipe.copc.laz"
    os.mkfifo(fifo)
    for args in (("info", fifo), ("render", fifo, "-o", tmp_path / "x.png")):
        res = run_cli(*args)         # an open() of the FIFO would block until the timeout
        assert res.returncode == 2 and "is not a regular file" in res.stderr and str(fifo) in res.stderr


def test_convert_laz_to_copc_on_the_command_line_streams_the_same_integers(scan, tmp_path):
    src = laspy.read(str(scan[0]))
    hdr = laspy.LasHeader(point_format=7, version="1.4")
    hdr.scales, hdr.offsets = SCALE, OFFSET
    plain = laspy.LasData(hdr)
    for nm in ("X", "Y", "Z", "gps_time", "red", "green", "blue", "intensity"):
        plain[nm] = np.asarray(src[nm])
    plain.write(str(tmp_path / "plain.laz"))
    res = run_cli("convert", tmp_path / "plain.laz", tmp_path / "back.copc.laz")
    assert res.returncode == 0, res.stderr
    assert "octree nodes (COPC)" in res.stdout
    assert np.array_equal(_table(tmp_path / "back.copc.laz"), _table(scan[0]))
    with CopcFile.open(tmp_path / "back.copc.laz") as f:
        assert f.point_count == 40_000 and f.point_format == 7    # one leaf at the default layout
