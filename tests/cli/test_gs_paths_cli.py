"""The draw path and sort flags on the command line: ``splatedit render
--path raster|compute`` on a Gaussian scene draws the same picture both ways
(and is a one-line error on a plain splat model); ``bench gaussian-render``
takes ``--size`` and ``--path`` and reports the device, path and sort per
case; ``bench gpu-sort`` compares the radix sort with the bitonic sort and
numpy and checks it exactly; ``--size`` on another bench is a one-line error."""

from __future__ import annotations

import json

import numpy as np
from PIL import Image

import splatedit.cli as cli
from splatedit.data import default_model_path, gaussian_scene_path
from splatedit.tolerances import GS_TILE_MAX_TOL, GS_TILE_MEAN_TOL


def _exit_code(argv) -> int:
    try:
        return cli.main(argv)
    except SystemExit as e:
        return e.code


def test_render_path_flag_draws_the_same_gaussian_image_both_ways(tmp_path, capsys):
    imgs = {}
    for path in ("raster", "compute"):
        out = tmp_path / f"{path}.png"
        assert cli.main(["render", str(gaussian_scene_path()), "-o", str(out), "--size", "120x90",
                         "--path", path]) == 0
        imgs[path] = np.asarray(Image.open(out).convert("RGB")).astype(int)
    diff = np.abs(imgs["raster"] - imgs["compute"])
    assert diff.mean() <= GS_TILE_MEAN_TOL["rgba16f"] and diff.max() <= GS_TILE_MAX_TOL["rgba16f"]
    assert imgs["compute"].std() > 5


def test_render_path_flag_draws_plain_splats_on_either_path_alike(tmp_path):
    """--path chooses the splat renderer's rasterization too (raster passes or
    compute shaders): both write the same picture of the bunny."""
    import numpy as np
    from PIL import Image
    imgs = []
    for path in ("raster", "compute"):
        out = tmp_path / f"{path}.png"
        assert _exit_code(["-q", "render", str(default_model_path()), "-o", str(out), "--size", "160x120",
                           "--path", path]) == 0
        imgs.append(np.asarray(Image.open(out).convert("RGB"), dtype=int))
    diff = np.abs(imgs[0] - imgs[1])
    assert (imgs[0].min(axis=2) < 200).sum() > 2000            # the bunny is in the picture
    assert diff.mean() < 0.05 and diff.max() <= 24


def test_bench_gaussian_render_reports_device_path_and_sort_per_case(capsys):
    assert cli.main(["bench", "gaussian-render", "--splats", "3000", "--size", "64x48"]) == 0
    lines = [json.loads(x) for x in capsys.readouterr().out.splitlines()]
    cases = {(ln["path"], ln["sort"]) for ln in lines}
    assert cases == {("raster", "cpu"), ("raster", "gpu"), ("raster", "bitonic"), ("compute", "cpu"),
                     ("compute", "gpu")}
    for ln in lines:
        assert ln["device"] and (ln["width"], ln["height"]) == (64, 48) and ln["visible"] > 0
        assert ln["ms_frame"] > 0 and ln["frame_over_first"] > 0
    assert cli.main(["bench", "gaussian-render", "--splats", "3000", "--size", "64x48", "--path", "compute",
                     ]) == 0
    assert {json.loads(x)["path"] for x in capsys.readouterr().out.splitlines()} == {"compute"}


def test_bench_gpu_sort_compares_radix_bitonic_and_numpy(capsys):
    assert cli.main(["bench", "gpu-sort", "--splats", "5000"]) == 0
    lines = [json.loads(x) for x in capsys.readouterr().out.splitlines()]
    cases = [ln["case"] for ln in lines]
    assert cases[0] == "radix" and {"bitonic", "numpy", "numpy_stable"} <= set(cases)
    assert all(ln["exact"] for ln in lines if ln["case"].startswith("radix"))
    assert lines[0]["over_radix"] == 1.0 and all(ln["pairs"] == 5000 for ln in lines)


def test_bench_size_on_another_bench_is_a_one_line_error(capsys):
    assert _exit_code(["bench", "qr", "--size", "64x48"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("splatedit: error:") and "--size" in err and err.count("\n") == 1
