"""`splatedit deform` prints each edit's distortion figures and warns (stderr)
when an edit stretches splats beyond DISTORTION_WARN_STRETCH."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from splatedit.deform.distortion import distortion_from_axes
from splatedit.io import read
from splatedit.tolerances import DISTORTION_WARN_STRETCH
from tests.cli.test_cli import run_cli, small_ply  # noqa: F401 - fixture

_LINE = re.compile(r"distortion: stretch max ([0-9.]+|inf)x, (\d+) > 3x, (\d+) > 4x, "
                   r"area change ([0-9.e+-]+)\.\.([0-9.e+-]+)")


def _script(tmp_path, lift):
    path = tmp_path / f"edit{lift}.json"
    path.write_text(json.dumps({"version": 1, "edits": [
        {"support": {"sphere": {"center": [0, 0, 1], "radius": 0.6}},
         "handle": {"sphere": {"center": [0, 0, 1], "radius": 0.15}}, "transform": {"translate": [0, 0, lift]}}]}))
    return path


def _figures(stdout):
    m = _LINE.search(stdout)
    assert m, stdout
    return float(m[1]), int(m[2]), int(m[3]), float(m[4]), float(m[5])


def test_mild_edit_prints_figures_that_match_the_written_model_and_does_not_warn(small_ply, tmp_path):  # noqa: F811
    out = tmp_path / "out.ply"
    res = run_cli("deform", small_ply, "--edit", _script(tmp_path, 0.1), "-o", out)
    assert res.returncode == 0, res.stderr
    mx, n3, n4, amin, amax = _figures(res.stdout)
    assert 1.0 < mx < DISTORTION_WARN_STRETCH and n3 == n4 == 0
    assert "warning" not in res.stderr
    a, b = read(small_ply), read(out)
    sup = np.linalg.norm(a.positions - [0, 0, 1], axis=1) <= 0.6
    ref = distortion_from_axes(a.u[sup], a.v[sup], b.u[sup], b.v[sup])
    # printed figures (3 significant digits) vs the written model (float32 axes)
    assert mx == pytest.approx(ref.max_stretch, abs=0.006)      # printed with 2 decimals
    assert (amin, amax) == (pytest.approx(ref.min_area_change, rel=6e-3), pytest.approx(ref.max_area_change, rel=6e-3))


def test_overstretching_edit_warns_on_stderr_with_the_counts(small_ply, tmp_path):  # noqa: F811
    res = run_cli("deform", small_ply, "--edit", _script(tmp_path, 1.5), "-o", tmp_path / "out.ply")
    assert res.returncode == 0, res.stderr
    mx, n3, n4, _, amax = _figures(res.stdout)
    assert mx > DISTORTION_WARN_STRETCH and n3 > 0 and n4 <= n3
    assert amax > 1.0
    warn = [ln for ln in res.stderr.splitlines() if ln.startswith("splatedit: warning: ")]
    assert len(warn) == 1, res.stderr
    assert f"edit 0 stretches {n3} of " in warn[0] and "more than 3x" in warn[0]
