"""``splatedit bench estimate|render|editor --splats N``: one JSON line per case."""

from __future__ import annotations

import json
import sys

import pytest

from splatedit.cli import main


def _lines(capsys):
    return [json.loads(x) for x in capsys.readouterr().out.splitlines() if x.strip()]


def test_bench_estimate_reports_stages_and_full_orientation(capsys):
    code = main(["bench", "estimate", "--splats", "30000"])
    assert code == 0
    (line,) = _lines(capsys)
    assert line["bench"] == "estimate" and line["points"] == 30000
    assert line["oriented"] == 1.0
    stages = [line[k] for k in ("finding_s", "estimating_s", "orienting_s", "sizing_s")]
    assert all(s >= 0 for s in stages) and sum(stages) <= line["total_s"] + 0.05
    assert "open3d_normals_k16_s" in line or "not installed" in line.get("open3d", "")
    if sys.platform == "linux":                  # peak RSS from /proc/self/status
        assert line["peak_rss_gb"] > 0
        # a process that freed memory before (this test session) reuses it: the rise can be 0
        assert line["rss_rise_bytes_per_point"] >= 0


def test_bench_render_scale_line_has_upload_frame_and_lod(capsys):
    from splatedit.bench.scale import bench_upload_lod
    line = bench_upload_lod(120_000, size=(160, 90))
    assert line["splats"] == 120_000
    assert line["upload_s"] >= 0 and line["frame_gpu_ms"]["total"] > 0
    assert line["lod_levels"] and max(line["lod_levels"]) <= 60_000
    assert line["lod_frame_splats"] == line["lod_levels"][0]


@pytest.mark.parametrize("bad", ["0", "-5", "ten"])
def test_bench_splats_must_be_positive_counts(capsys, bad):
    with pytest.raises(SystemExit) as exc:
        main(["bench", "estimate", "--splats", bad])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err.startswith("splatedit: error: bench: argument --splats") and "\n" == err[-1]


def test_bench_render_case_draws_both_paths_and_names_device_and_path(tmp_path):
    """One `bench render` case: both rasterization paths in the same run, their
    ratio, how far apart their images are, the device and the default path."""
    from splatedit.bench.render import bench_render
    from splatedit.io import write
    from tests.render.scenes import sphere
    model = tmp_path / "ball.ply"
    write(model, sphere(3000))
    lines = list(bench_render(counts=(5000,), size=(96, 64), repeats=1, bunny=False, models=(str(model),),
                              deform_max=0))
    assert [x["model"] for x in lines] == ["sphere", "ball.ply"]
    for x in lines:
        assert x["device"] and x["path"] in ("raster", "compute") and (x["width"], x["height"]) == (96, 64)
        assert x["ms_frame_raster"] > 0 and x["ms_frame_compute"] > 0
        assert x["compute_over_raster"] == pytest.approx(x["ms_frame_compute"] / x["ms_frame_raster"], rel=0.01)
        if x["path_compute_ran"] == "compute":
            assert x["image_max_diff"] <= 24 and x["coverage_mismatch"] <= 0.005 * x["coverage_raster"]
        assert "ms_frame_deformed_all" not in x                 # deform_max=0


def test_bench_render_takes_size_and_model_flags():
    from splatedit.cli import build_parser
    args = build_parser().parse_args(["bench", "render", "--size", "320x200", "--model", "a.ply", "--model", "b.xyz",
                                      "--splats", "20000000"])
    assert args.size == (320, 200) and args.model == ["a.ply", "b.xyz"] and args.splats == [20_000_000]
