"""``splatedit bench basis --splats N``: one JSON line per support size, measured
in a fresh process (time and peak memory per stage, scipy beside it)."""

from __future__ import annotations

import json

from splatedit.cli import main


def test_bench_basis_line_reports_stages_memory_and_scipy(capsys):
    code = main(["bench", "basis", "--splats", "30000"])
    assert code == 0
    (line,) = [json.loads(x) for x in capsys.readouterr().out.splitlines() if x.strip()]
    assert "error" not in line, line
    assert line["bench"] == "basis" and abs(line["support"] - 30000) < 0.02 * 30000
    assert line["splats"] > line["support"] and 0 < line["centers"] <= line["m"]
    # one handle: K = 4 columns, the basis keeps (N, 4, 4) float64
    assert abs(line["basis_kept_mb"] - line["support"] * 128 / 2**20) < 0.1
    assert line["kept_mb"] > line["basis_kept_mb"]
    for key in ("constraints_s", "fit_s", "basis_s", "hot_build_s", "apply_s", "copy_s", "jacobians_s",
                "rbf_eval_s", "scipy_eval_s"):
        assert line[key] >= 0, key
    for key in ("basis_peak_mb", "hot_build_peak_mb", "apply_peak_mb", "jacobians_peak_mb", "scipy_peak_mb"):
        assert line[key] >= 0, key
    assert line["scipy_centers"] == line["m"]
