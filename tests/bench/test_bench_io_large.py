"""`bench io --large`'s whole-process cases: `info` and `render` of a
normals + radius PLY beside Open3D's read of the same file."""

from __future__ import annotations

import numpy as np

from splatedit.bench.io import bench_large_file, write_normals_radius_ply
from splatedit.io import read


def test_normals_radius_file_is_read_as_written(tmp_path):
    size = write_normals_radius_ply(tmp_path / "s.ply", 3000)
    assert size == 28 * 3000 + len((tmp_path / "s.ply").read_bytes().split(b"end_header\n")[0]) + 11
    c = read(tmp_path / "s.ply")
    assert c.n == 3000
    np.testing.assert_allclose(np.linalg.norm(c.positions, axis=1), 1.0, rtol=1e-6)
    r = np.linalg.norm(c.u, axis=1)
    np.testing.assert_allclose(r, 1.5 * np.sqrt(2 * 4 * np.pi / (np.sqrt(3) * 3000)), rtol=1e-6)


def test_large_file_cases_time_both_commands_and_say_when_open3d_is_missing(tmp_path, monkeypatch):
    monkeypatch.setenv("SPLATEDIT_OPEN3D_PYTHON", "/nonexistent/python")
    rows = list(bench_large_file(20_000, tmp_path))
    assert [r["case"] for r in rows] == ["info_file", "render_file"]
    for r in rows:
        assert r["seconds"] > 0 and r["peak_rss_mb"] > 0, r
        assert r["open3d"].startswith("not available"), r
        assert "ratio_to_open3d" not in r
    assert not (tmp_path / "scan20000.ply").exists()
