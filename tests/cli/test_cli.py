"""The command line: exit codes, one-line errors, outputs that never clobber inputs."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from splatedit.cli import main
from splatedit.data import default_model_path
from splatedit.commands.demo import DEMO_SCRIPT
from splatedit.io import read


def run_cli(*args, cwd=None):
    """Run ``python -m splatedit.cli`` in a subprocess (real exit code, stderr)."""
    return subprocess.run([sys.executable, "-m", "splatedit.cli", "-q", *map(str, args)],
                          capture_output=True, text=True, cwd=cwd, timeout=300)


@pytest.fixture
def small_ply(tmp_path):
    """A 2000-splat sphere written as a splat PLY."""
    from splatedit.io import write
    from splatedit.model.estimate import estimate_splats
    rng = np.random.default_rng(3)
    p = rng.normal(size=(2000, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    path = tmp_path / "sphere.ply"
    write(path, estimate_splats(p, normals=p))
    return path


def test_info_prints_counts_and_bounds_as_json(small_ply, capsys):
    assert main(["-q", "info", str(small_ply), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["splats"] == 2000
    assert np.allclose(info["bounds_min"], -1, atol=0.1) and np.allclose(info["bounds_max"], 1, atol=0.1)
    assert 0 < info["spacing"] < 0.2


@pytest.mark.parametrize("content,needle", [
    ("", "empty"),
    ("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nend_header\n1 2\n3 4\n",
     "'z'"),
    ("1 2 3\n4 five 6\n", "row 1"),
])
def test_bad_input_file_exits_2_with_one_line_naming_the_file(tmp_path, content, needle):
    suffix = ".ply" if content.startswith("ply") else ".xyz"
    bad = tmp_path / f"bad{suffix}"
    bad.write_text(content)
    res = run_cli("info", bad)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    assert lines[0].startswith("splatedit: error: ") and str(bad) in lines[0] and needle in lines[0]
    assert "Traceback" not in res.stderr


def test_missing_file_exits_2(tmp_path):
    res = run_cli("info", tmp_path / "nope.ply")
    assert res.returncode == 2 and "nope.ply" in res.stderr and "Traceback" not in res.stderr


def test_bad_edit_script_exits_2_naming_the_json_path(small_ply, tmp_path):
    script = tmp_path / "edit.json"
    script.write_text(json.dumps({"version": 1, "edits": [
        {"support": {"sphere": {"center": [0, 0, 1], "radius": -1}},
         "handle": {"sphere": {"center": [0, 0, 1], "radius": 0.1}}, "transform": {"translate": [0, 0, 1]}}]}))
    res = run_cli("deform", small_ply, "--edit", script, "-o", tmp_path / "out.ply")
    assert res.returncode == 2
    assert "$.edits[0].support.sphere.radius" in res.stderr and "edit.json" in res.stderr
    assert not (tmp_path / "out.ply").exists()


def test_deform_refuses_to_overwrite_its_input_unless_forced(small_ply, tmp_path):
    script = tmp_path / "edit.json"
    script.write_text(json.dumps({"version": 1, "edits": [
        {"support": {"sphere": {"center": [0, 0, 1], "radius": 0.6}},
         "handle": {"sphere": {"center": [0, 0, 1], "radius": 0.2}}, "transform": {"translate": [0, 0, 0.2]}}]}))
    before = small_ply.read_bytes()
    res = run_cli("deform", small_ply, "--edit", script, "-o", small_ply)
    assert res.returncode == 2 and "refusing to overwrite the input" in res.stderr
    assert small_ply.read_bytes() == before
    res = run_cli("deform", small_ply, "--edit", script, "-o", small_ply, "--force")
    assert res.returncode == 0, res.stderr
    assert small_ply.read_bytes() != before


def test_deform_moves_handle_by_the_transform_and_keeps_fixed_splats_bitwise(small_ply, tmp_path):
    script = tmp_path / "edit.json"
    script.write_text(json.dumps({"version": 1, "edits": [
        {"support": {"sphere": {"center": [0, 0, 1], "radius": 0.8}, "fill_holes": False},
         "handle": {"sphere": {"center": [0, 0, 1], "radius": 0.25}}, "transform": {"translate": [0, 0, 0.3]}}]}))
    out = tmp_path / "out.ply"
    res = run_cli("deform", small_ply, "--edit", script, "-o", out)
    assert res.returncode == 0, res.stderr
    assert "edit 0:" in res.stdout
    a, b = read(small_ply), read(out)
    d = np.linalg.norm(a.positions - [0, 0, 1], axis=1)
    fixed, handle = d > 0.8, d <= 0.25
    assert np.array_equal(a.positions[fixed], b.positions[fixed])
    np.testing.assert_allclose(b.positions[handle] - a.positions[handle], [[0, 0, 0.3]] * handle.sum(), atol=1e-9)
    free = ~fixed & ~handle
    dz = (b.positions - a.positions)[free, 2]
    assert (dz > -1e-3).all() and (dz < 0.3 + 1e-3).all() and np.ptp(dz) > 0.1


def test_demo_writes_results_and_its_script_replays_to_the_same_file(tmp_path):
    res = run_cli("demo", "-o", tmp_path, "--no-render")
    assert res.returncode == 0, res.stderr
    assert "edit 0:" in res.stdout and "edit 1:" in res.stdout
    saved = json.loads((tmp_path / "bunny-demo.json").read_text())
    assert len(saved["edits"]) == len(DEMO_SCRIPT["edits"])
    res = run_cli("deform", default_model_path(), "--edit", tmp_path / "bunny-demo.json", "-o", tmp_path / "replay.ply")
    assert res.returncode == 0, res.stderr
    a, b = read(tmp_path / "bunny-demo.ply"), read(tmp_path / "replay.ply")
    assert np.array_equal(a.positions, b.positions) and np.array_equal(a.u, b.u)
    moved = np.linalg.norm(a.positions - read(default_model_path()).positions, axis=1)
    assert moved.max() > 0.05 and (moved == 0).sum() > a.n // 2


def test_convert_estimates_normals_for_a_raw_scan(tmp_path):
    raw = tmp_path / "raw.xyz"
    rng = np.random.default_rng(1)
    xy = rng.uniform(-1, 1, size=(3000, 2))
    np.savetxt(raw, np.c_[xy, 0.1 * np.sin(3 * xy[:, 0])])
    out = tmp_path / "raw.ply"
    res = run_cli("convert", raw, out)
    assert res.returncode == 0, res.stderr
    cloud = read(out)
    assert cloud.n == 3000
    assert np.abs(cloud.normals[:, 2]).min() > 0.5   # a gently curved height field


def test_bad_flag_values_exit_2(small_ply, tmp_path):
    res = run_cli("render", small_ply, "-o", tmp_path / "x.png", "--size", "12xq")
    assert res.returncode == 2 and "size must look like" in res.stderr
    res = run_cli("render", small_ply, "-o", tmp_path / "x.png", "--eye", "1,2")
    assert res.returncode == 2 and "--eye" in res.stderr


@pytest.mark.parametrize("ext,kept", [(".off", True), (".ply", True), (".xyz", False), (".pts", False),
                                      (".pcd", False), (".las", False), (".e57", False)])
def test_convert_of_a_mesh_says_whether_its_faces_are_kept_or_dropped(tmp_path, capsys, ext, kept):
    """Issue 19 item 8: a mesh written to a point format reported its faces as if written."""
    if ext == ".e57":
        pytest.importorskip("pye57")
    if ext == ".las":
        pytest.importorskip("laspy")
    mesh = tmp_path / "tet.off"
    mesh.write_text("OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n")
    out = tmp_path / f"out{ext}"
    assert main(["-q", "convert", str(mesh), str(out)]) == 0
    said = capsys.readouterr().out
    assert (": 4 splats, 4 faces" in said) is kept and ("faces were dropped" in said) is (not kept), said
    assert (read(out).faces is not None) is kept


def test_deform_and_convert_keep_the_up_axis_the_input_header_names(tmp_path):
    """A model saved by the editor with ``comment up_axis +Z`` stays Z-up
    through ``convert`` and ``deform`` (PLY outputs)."""
    import json

    from splatedit.cli import main
    from splatedit.data import default_model_path
    from splatedit.io import read, write
    from splatedit.model.orientation import header_up_hint
    src = write(tmp_path / "zup.ply", read(default_model_path()), up_axis="+Z")
    assert main(["-q", "convert", str(src), str(tmp_path / "conv.ply")]) == 0
    assert header_up_hint(tmp_path / "conv.ply").label == "+Z"
    script = tmp_path / "e.json"
    script.write_text(json.dumps({"version": 1, "edits": [{"support": {"sphere": {"center": [0, 0.4, 0], "radius": 0.2}},
                                                             "handle": {"sphere": {"center": [0, 0.47, -0.1], "radius": 0.06}},
                                                             "transform": {"translate": [0.02, 0, 0]}}]}))
    assert main(["-q", "deform", str(src), "--edit", str(script), "-o", str(tmp_path / "def.ply")]) == 0
    assert header_up_hint(tmp_path / "def.ply").label == "+Z"
