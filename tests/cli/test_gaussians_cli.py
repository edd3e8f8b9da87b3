"""`splatedit info|convert|deform` on Gaussian splatting PLYs."""

from __future__ import annotations

import json

import numpy as np
import plyfile

from splatedit.data import gaussian_scene_path
from splatedit.io import is_gaussian_file, read, read_gaussians
from tests.cli.test_cli import run_cli

EARS = {"version": 1, "edits": [{
    "support": {"box": {"min": [-1, 0.1, -1], "max": [1, 1, 1]}},
    "handle": {"box": {"min": [-1, 0.38, -1], "max": [1, 1, 1]}},
    "transform": {"rotate": {"axis": [1, 0, 0], "degrees": 30}, "translate": [0, 0.02, 0]}}]}


def test_info_reports_kind_degree_and_statistics():
    r = run_cli("info", "--json", gaussian_scene_path())
    assert r.returncode == 0, r.stderr
    info = json.loads(r.stdout)
    g = read_gaussians(gaussian_scene_path())
    assert (info["kind"], info["gaussians"], info["sh_degree"]) == ("3dgs", 5000, 3)
    lo, med, hi = info["opacity_p5_p50_p95"]
    assert 0 < lo < med < hi < 1
    assert abs(med - np.median(g.opacities())) < 1e-3
    assert info["opacity_below_0.5"] == int((g.opacities() < 0.5).sum())
    assert abs(info["scale_max_p5_p50_p95"][1] / np.median(g.scales().max(1)) - 1) < 1e-3   # 4 digits
    np.testing.assert_allclose(info["bounds_min"], g.positions.min(0), rtol=1e-6)
    assert info["anisotropy_p5_p50_p95"][2] > 2       # a spread of anisotropies


def test_convert_keeps_gaussians_bit_for_bit_or_writes_lossy_splats(tmp_path):
    out = tmp_path / "copy.ply"
    r = run_cli("convert", gaussian_scene_path(), out)
    assert r.returncode == 0, r.stderr
    a = plyfile.PlyData.read(str(gaussian_scene_path()))["vertex"].data
    assert plyfile.PlyData.read(str(out))["vertex"].data.tobytes() == a.tobytes()
    disc = tmp_path / "discs.ply"
    r = run_cli("convert", "--to-splats", gaussian_scene_path(), disc)
    assert r.returncode == 0 and "5000 splats" in r.stdout, r.stderr
    assert not is_gaussian_file(disc) and read(disc).n == 5000


def test_deform_writes_a_valid_deformed_gaussian_file(tmp_path):
    script = tmp_path / "ears.json"
    script.write_text(json.dumps(EARS))
    out = tmp_path / "ears.ply"
    r = run_cli("deform", gaussian_scene_path(), "--edit", script, "-o", out)
    assert r.returncode == 0, r.stderr
    assert "edit 0: rotation deformation, support" in r.stdout and "5000 Gaussians" in r.stdout
    g0, g1 = read_gaussians(gaussian_scene_path()), read_gaussians(out)
    moved = np.linalg.norm(g1.positions - g0.positions, axis=1)
    ears = g0.positions[:, 1] > 0.38
    assert np.median(moved[ears]) > 0.03 and moved[g0.positions[:, 1] < -0.2].max() == 0.0
    # the ears' Gaussians turned with them: their thin axes rotated by about 30 degrees
    thin = np.argmin(g0.log_scales, 1)
    rows = np.flatnonzero(ears)
    n0 = g0.rotation_matrices()[rows, :, thin[rows]]
    n1 = g1.rotation_matrices()[rows, :, thin[rows]]
    angle = np.degrees(np.arccos(np.clip(np.abs((n0 * n1).sum(1)), 0, 1)))
    assert 20 < np.median(angle) < 31
    assert g1.layout == g0.layout


def test_deform_errors_are_one_line(tmp_path):
    script = tmp_path / "bad.json"
    bad = json.loads(json.dumps(EARS))
    bad["edits"][0]["handle"] = {"box": {"min": [5, 5, 5], "max": [6, 6, 6]}}
    script.write_text(json.dumps(bad))
    r = run_cli("deform", gaussian_scene_path(), "--edit", script, "-o", tmp_path / "o.ply")
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "$.edits[0].handle" in r.stderr
    script.write_text(json.dumps(EARS))
    r = run_cli("deform", gaussian_scene_path(), "--edit", script, "-o", tmp_path / "o.xyz")
    assert r.returncode == 2 and "must be a .ply" in r.stderr and "Traceback" not in r.stderr
    broken = tmp_path / "broken.ply"
    broken.write_bytes(gaussian_scene_path().read_bytes().replace(b"property float opacity\n", b""))
    r = run_cli("info", broken)
    assert r.returncode == 2 and str(broken) in r.stderr and "'opacity'" in r.stderr, r.stderr


def test_deform_detail_mode_of_a_gaussian_scene_is_a_one_line_error(tmp_path):
    """The detail mode has no Gaussian version: a one-line error naming the key, not a traceback."""
    script = tmp_path / "detail.json"
    detail = json.loads(json.dumps(EARS))
    detail["edits"][0]["deformation"] = "detail"
    script.write_text(json.dumps(detail))
    r = run_cli("deform", gaussian_scene_path(), "--edit", script, "-o", tmp_path / "o.ply")
    assert r.returncode == 2 and r.stderr.count("\n") == 1, r.stderr
    assert "$.edits[0].deformation" in r.stderr and "Traceback" not in r.stderr
    assert not (tmp_path / "o.ply").exists()
