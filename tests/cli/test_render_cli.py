"""``splatedit render``: PNG and float buffers; the GPU edit path matches the CPU one."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
from PIL import Image

from splatedit.data import default_model_path

EDIT = {"version": 1, "edits": [
    {"support": {"sphere": {"center": [-0.07, 0.37, -0.05], "radius": 0.2}},
     "handle": {"sphere": {"center": [0.0, 0.47, -0.1], "radius": 0.06}},
     "transform": {"rotate": {"axis": [0, 0, 1], "degrees": -40, "center": [-0.15, 0.26, 0.0]}}}]}

# "--eye=..." with "=": argparse would take a value starting with "-" for an option
CAMERA = ["--size", "200x160", "--eye=-0.6,0.5,1.6", "--target=-0.05,0.1,0", "--up", "0,1,0", "--fov", "35"]


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "splatedit.cli", "-q", *map(str, args)],
                          capture_output=True, text=True, timeout=300)


def test_render_writes_png_and_buffers_with_nan_background(tmp_path):
    png, npz = tmp_path / "bunny.png", tmp_path / "bunny.npz"
    res = run_cli("render", default_model_path(), "-o", png, "--buffers", npz, *CAMERA)
    assert res.returncode == 0, res.stderr
    img = np.asarray(Image.open(png))
    assert img.shape == (160, 200, 4)
    bufs = np.load(npz)
    assert set(bufs.files) >= {"depth", "normal", "weight", "color"}
    fg = np.isfinite(bufs["depth"])
    assert 0.1 < fg.mean() < 0.9
    n = bufs["normal"][fg]
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-2)
    assert (bufs["depth"][fg] > 0).all()


def test_gpu_edit_path_matches_rendering_the_cpu_deformed_file(tmp_path):
    script = tmp_path / "edit.json"
    script.write_text(json.dumps(EDIT))
    gpu_png, cpu_png, deformed = tmp_path / "gpu.png", tmp_path / "cpu.png", tmp_path / "deformed.ply"
    undeformed_png = tmp_path / "plain.png"
    assert run_cli("render", default_model_path(), "-o", gpu_png, "--edit", script, *CAMERA).returncode == 0
    assert run_cli("deform", default_model_path(), "--edit", script, "-o", deformed).returncode == 0
    assert run_cli("render", deformed, "-o", cpu_png, *CAMERA).returncode == 0
    assert run_cli("render", default_model_path(), "-o", undeformed_png, *CAMERA).returncode == 0
    gpu = np.asarray(Image.open(gpu_png)).astype(float)
    cpu = np.asarray(Image.open(cpu_png)).astype(float)
    plain = np.asarray(Image.open(undeformed_png)).astype(float)
    # stated tolerance: mean abs difference < 0.5/255 and < 0.5% of pixels off by more than 24/255
    diff = np.abs(gpu - cpu).max(axis=2)
    assert diff.mean() < 0.5 and (diff > 24).mean() < 0.005, (diff.mean(), (diff > 24).mean())
    # and the edit is visible at all
    assert (np.abs(gpu - plain).max(axis=2) > 24).mean() > 0.005


CURVE_EDIT = {"version": 1, "edits": [
    {"support": {"sphere": {"center": [-0.07, 0.37, -0.05], "radius": 0.2}}, "deformation": "linear",
     "curves": [{"points": [[-0.12, 0.3, 0.0], [-0.07, 0.38, -0.05], [-0.02, 0.44, -0.09], [0.0, 0.48, -0.11]],
                 "move": [[0, 0, 0], [0.01, 0, 0], [0.04, -0.02, 0], [0.08, -0.05, 0]]}]}]}


def test_gpu_curve_edit_matches_rendering_the_cpu_deformed_file(tmp_path):
    """The linear curve edit is drawn on the GPU; the rotation mode's curve
    frames are applied on the CPU (and say so)."""
    script = tmp_path / "curve.json"
    script.write_text(json.dumps(CURVE_EDIT))
    frames = tmp_path / "frames.json"
    doc = json.loads(json.dumps(CURVE_EDIT))
    del doc["edits"][0]["deformation"]
    frames.write_text(json.dumps(doc))
    res = run_cli("render", default_model_path(), "-o", tmp_path / "frames.png", "--edit", frames, *CAMERA)
    assert res.returncode == 0, res.stderr
    assert "rotation edit is applied on the CPU" in res.stdout and "deformed on the GPU" not in res.stdout
    gpu_png, cpu_png, deformed = tmp_path / "gpu.png", tmp_path / "cpu.png", tmp_path / "deformed.ply"
    res = run_cli("render", default_model_path(), "-o", gpu_png, "--edit", script, *CAMERA)
    assert res.returncode == 0, res.stderr
    assert "4 basis columns" in res.stdout
    assert run_cli("deform", default_model_path(), "--edit", script, "-o", deformed).returncode == 0
    assert run_cli("render", deformed, "-o", cpu_png, *CAMERA).returncode == 0
    diff = np.abs(np.asarray(Image.open(gpu_png)).astype(float)
                  - np.asarray(Image.open(cpu_png)).astype(float)).max(axis=2)
    assert diff.mean() < 0.5 and (diff > 24).mean() < 0.005, (diff.mean(), (diff > 24).mean())


def test_render_edl_only_darkens_depth_edges_and_is_refused_for_gaussian_scenes(tmp_path, capsys):
    from splatedit import cli
    from splatedit.data import gaussian_scene_path
    plain, edl = tmp_path / "plain.png", tmp_path / "edl.png"
    assert cli.main(["-q", "render", str(default_model_path()), "-o", str(plain), *CAMERA]) == 0
    assert cli.main(["-q", "render", str(default_model_path()), "-o", str(edl), "--edl", *CAMERA]) == 0
    a = np.asarray(Image.open(plain)).astype(float)
    b = np.asarray(Image.open(edl)).astype(float)
    assert np.array_equal(a[..., 3], b[..., 3])                 # coverage and background unchanged
    assert (b[..., :3] <= a[..., :3] + 1).all()                 # EDL only darkens
    darker = (a[..., :3] - b[..., :3]).max(axis=2) > 24
    assert 0.002 < darker.mean() < 0.2, darker.mean()           # the creases and overlaps, not everything
    capsys.readouterr()
    assert cli.main(["render", str(gaussian_scene_path()), "-o", str(tmp_path / "g.png"), "--edl"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("splatedit: error: ") and "--edl" in err[0]
    assert str(gaussian_scene_path()) in err[0]                 # names the file


def test_a_scan_with_one_glitch_point_1e9_away_renders_its_body_not_a_strip(tmp_path):
    """The GPU units are centred and scaled on the main body when one far
    point blows the box up (render/uploads.gpu_body_box): a sphere with a
    point 1e9 away renders as a round disc, as it does without the point
    (before: a vertical strip, float32 steps of 32 units at 5e8)."""
    import numpy as np
    from PIL import Image

    from splatedit.cli import main
    from tests.render.scenes import sphere
    pts = sphere(20000, overlap=1.2).positions
    np.savetxt(tmp_path / "glitch.xyz", np.vstack([pts, [[1e9, 0.0, 0.0]]]), fmt="%.9g")
    assert main(["-q", "render", str(tmp_path / "glitch.xyz"), "-o", str(tmp_path / "g.png"),
                 "--size", "320x240"]) == 0
    cover = np.asarray(Image.open(tmp_path / "g.png").convert("L")) < 200
    rows, cols = np.flatnonzero(cover.any(axis=1)), np.flatnonzero(cover.any(axis=0))
    assert cover.sum() > 5000
    width, height = cols[-1] - cols[0] + 1, rows[-1] - rows[0] + 1
    assert 0.8 < width / height < 1.25                           # round, not a strip


def test_render_edit_of_a_refined_far_grab_matches_rendering_the_deformed_file(tmp_path):
    """A far grab with needles in the rotation mode is refined by `splatedit
    deform` (splatedit.deform.refine); `render --edit` draws that result too."""
    from splatedit.bench.needles import prepare
    cloud, basis, m, h, diag = prepare("arm-bunny-ear")
    script = tmp_path / "grab.json"
    script.write_text(json.dumps({"version": 1, "edits": [{
        "support": {"indices": basis.indices.tolist(), "fill_holes": False},
        "handle": {"indices": np.concatenate(basis.constraints.handle_index).tolist()},
        "transform": {"translate": m[:3, 3].tolist()}}]}))
    edit_png, cpu_png, deformed = tmp_path / "edit.png", tmp_path / "cpu.png", tmp_path / "deformed.ply"
    cam = ["--size", "160x160", "--eye=1.6,0.5,0.6", "--target=0,0.25,0", "--up", "0,1,0", "--fov", "40"]
    res = run_cli("render", default_model_path(), "-o", edit_png, "--edit", script, *cam)
    assert res.returncode == 0, res.stderr
    assert "needles refined" in res.stdout and "applied on the CPU" in res.stdout
    res = run_cli("deform", default_model_path(), "--edit", script, "-o", deformed)
    assert res.returncode == 0 and "needles refined" in res.stdout, res.stderr
    assert run_cli("render", deformed, "-o", cpu_png, *cam).returncode == 0
    a = np.asarray(Image.open(edit_png)).astype(float)
    b = np.asarray(Image.open(cpu_png)).astype(float)
    diff = np.abs(a - b).max(axis=2)
    assert diff.mean() < 0.5 and (diff > 24).mean() < 0.005, (diff.mean(), (diff > 24).mean())
