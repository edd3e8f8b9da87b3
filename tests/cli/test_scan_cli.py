"""``info`` reports outliers, boundary splats and the radius spread;
``convert --remove-outliers`` drops outliers of point clouds."""

from __future__ import annotations

import json

import numpy as np

from splatedit.cli import main
from splatedit.io import read
from tests.model.scan_helpers import inject_outliers


def _info(path, capsys) -> dict:
    assert main(["-q", "info", str(path), "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_info_and_remove_outliers_on_a_scan_with_strays(shared_data, tmp_path, capsys):
    """kitten.xyz (positions only, so normals and sizes are estimated) with 1 %
    uniform outliers and 5 far strays."""
    p = read(shared_data / "kitten.xyz").positions
    q = inject_outliers(p)
    raw = tmp_path / "kitten-strays.xyz"
    np.savetxt(raw, q)
    info = _info(raw, capsys)
    injected = len(q) - len(p)
    assert 0.7 * injected <= info["outliers"] <= injected + 2
    stat, iso = info["outliers_statistical"], info["outliers_isolated"]
    assert max(stat, iso) <= info["outliers"] <= stat + iso     # a point may be both
    assert info["splat_radius_max_rel_median"] < 3.0       # 45x with the spacing rule alone
    assert info["boundary_splats"] < 0.01 * len(q)         # a closed scan

    out = tmp_path / "clean.ply"
    assert main(["-q", "convert", str(raw), str(out), "--remove-outliers"]) == 0
    line = capsys.readouterr().out.splitlines()[0]
    assert line.startswith(f"removed {info['outliers']} outlier(s) of {len(q)} points")
    cleaned = read(out)
    assert cleaned.n == len(q) - info["outliers"]
    assert _info(out, capsys)["outliers"] <= 0.002 * cleaned.n


def test_info_text_lists_boundary_splats_of_an_open_scan(tmp_path, capsys):
    rng = np.random.default_rng(0)
    xy = rng.uniform(-1, 1, size=(4000, 2))
    raw = tmp_path / "patch.xyz"
    np.savetxt(raw, np.c_[xy, 0.1 * np.sin(3 * xy[:, 0])])
    assert main(["-q", "info", str(raw)]) == 0
    rows = dict(line.split(None, 1) for line in capsys.readouterr().out.splitlines())
    # a square patch of 4000 random points has about 4 * 2 / 0.03 border points
    assert 100 < int(rows["boundary_splats"]) < 600
    assert int(rows["outliers"]) == 0


def test_remove_outliers_refuses_a_mesh_in_one_line(shared_data, tmp_path, capsys):
    out = tmp_path / "bunny.ply"
    assert main(["-q", "convert", str(shared_data / "bunny00.off"), str(out), "--remove-outliers"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("splatedit: error: ")
    assert "bunny00.off" in err[0] and "point clouds only" in err[0]
    assert not out.exists()


def test_info_counts_the_border_vertices_of_a_cut_mesh(shared_data, tmp_path, capsys):
    from splatedit.io import write
    from splatedit.model.mesh import cloud_from_mesh
    from splatedit.model.sizing import mesh_boundary_vertices
    from tests.model.scan_helpers import cut_mesh
    whole = read(shared_data / "bunny00.off")
    assert _info(shared_data / "bunny00.off", capsys)["boundary_splats"] == 0     # closed
    v, f = cut_mesh(whole.positions, whole.faces)
    path = tmp_path / "half.off"
    write(path, cloud_from_mesh(v, f))
    info = _info(path, capsys)
    assert info["boundary_splats"] == int(mesh_boundary_vertices(len(v), f).sum()) > 100
