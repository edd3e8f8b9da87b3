"""``splatedit render``'s default camera (the main body from the front about
the detected up axis), vector options with a leading minus, and the wording
of ``info`` for folders and all-zero LAS dimensions."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

import splatedit.cli as cli
from splatedit.data import default_model_path
from splatedit.io import read

SIZE = ["--size", "160x120"]


def _image(path) -> np.ndarray:
    return np.asarray(Image.open(path)).astype(int)


def _foreground(img) -> np.ndarray:
    return img[..., :3].min(axis=2) < 230


def test_render_of_a_scan_with_far_clumps_frames_its_body_and_says_so(shared_data, tmp_path, capsys):
    out = tmp_path / "poste.png"
    assert cli.main(["-q", "render", str(shared_data / "poste_france.xyz"), "-o", str(out), *SIZE]) == 0
    err = capsys.readouterr().err
    assert err.startswith("splatedit: note: ") and err.count("\n") == 1
    assert "points far outside the main body (outliers?): `splatedit convert --remove-outliers`" in err
    assert _foreground(_image(out)).mean() > 0.05       # measured 9.5 % (0.16 % framing the full box)


def _vec(v) -> str:
    return ",".join(str(float(x)) for x in v)


def _z_up_las(tmp_path):
    """The bundled bunny turned Z-up, written as LAS (laspy, as tests/io do)."""
    import laspy
    p = read(default_model_path()).positions
    header = laspy.LasHeader(point_format=1, version="1.2")
    header.scales = np.full(3, 1e-5)
    header.offsets = np.zeros(3)
    las = laspy.LasData(header)
    las.x, las.y, las.z = p[:, 0], -p[:, 2], p[:, 1]
    path = tmp_path / "geo.las"
    las.write(str(path))
    return path


def test_render_of_a_z_up_las_uses_its_up_axis_and_up_alone_works(tmp_path, capsys):
    """``render geo.las`` looks at the front (as the editor's first view):
    the same image as ``--up 0,0,1`` alone (which used to be refused as
    parallel to the view) and as the explicit front camera, not the view
    from above it used to be (``--eye`` above alone works too: north up)."""
    from splatedit.render.framing import default_view
    las = _z_up_las(tmp_path)
    outs = [tmp_path / f"{k}.png" for k in ("default", "up", "explicit", "top")]
    cam = default_view(read(las), (160, 120)).camera
    c, d = cam.target, float(np.linalg.norm(cam.eye - cam.target))
    assert cli.main(["-q", "render", str(las), "-o", str(outs[0]), *SIZE]) == 0
    assert cli.main(["-q", "render", str(las), "-o", str(outs[1]), *SIZE, "--up", "0,0,1"]) == 0
    assert cli.main(["-q", "render", str(las), "-o", str(outs[2]), *SIZE, "--eye", _vec(c - [0.0, d, 0.0]),
                     "--target", _vec(c), "--up", "0,0,1"]) == 0
    assert cli.main(["-q", "render", str(las), "-o", str(outs[3]), *SIZE, "--eye", _vec(c + [0.0, 0.0, d])]) == 0
    assert capsys.readouterr().err == ""
    default, up, explicit, top = (_foreground(_image(p)) for p in outs)
    assert (default ^ up).sum() <= 0.005 * default.sum()       # the same camera (blending rounds 1 level apart)
    assert (default ^ explicit).sum() <= 0.01 * default.sum()
    assert (default ^ top).sum() > 0.3 * default.sum()


def test_vector_options_take_a_leading_minus(tmp_path, capsys):
    model = str(default_model_path())
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    assert cli.main(["-q", "render", model, "-o", str(a), *SIZE, "--eye", "-0.4,1,2",
                     "--target", "-0.05,0.1,0", "--up", "-0.1,1,0"]) == 0
    assert cli.main(["-q", "render", model, "-o", str(b), *SIZE, "--eye=-0.4,1,2",
                     "--target=-0.05,0.1,0", "--up=-0.1,1,0"]) == 0
    assert np.abs(_image(a) - _image(b)).max() <= 2        # the renderer rounds blending 1 level apart run to run
    assert _foreground(_image(a)).mean() > 0.05
    # a value that is no vector is still reported as the option's bad value
    with pytest.raises(SystemExit) as exit_:
        cli.main(["-q", "render", model, "-o", str(a), "--eye", "-0.4,1"])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and "--eye must be three comma-separated numbers" in err and err.count("\n") == 1


def test_info_of_a_folder_says_it_is_a_directory(tmp_path, capsys):
    assert cli.main(["-q", "info", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err == f"splatedit: error: {tmp_path}: is a directory, not a file\n"


def test_info_of_a_las_written_without_scan_fields_reports_them_absent(tmp_path, capsys):
    """A LAS record always holds intensity and classification: written from a
    model without them they are all zero, and info says so."""
    las = tmp_path / "bunny.las"
    assert cli.main(["-q", "convert", str(default_model_path()), str(las)]) == 0
    capsys.readouterr()
    assert cli.main(["-q", "info", str(las), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["intensity"] is False and info["classification"] is False
    assert info["all_zero"] == ["intensity", "classification"]
    assert info["far_from_main_body"] == 0 and "note" not in info


def test_info_counts_the_points_far_outside_the_main_body(shared_data, capsys):
    assert cli.main(["-q", "info", str(shared_data / "poste_france.xyz"), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert 0 < info["far_from_main_body"] < 0.05 * info["splats"]
    assert info["main_body_diagonal"] < 0.15 * info["diagonal"]
    assert info["note"].startswith(f"{info['far_from_main_body']} points far outside the main body")
    assert list(info)[-1] == "note"
