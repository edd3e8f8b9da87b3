"""`splatedit deform` and selection closure: the report line, fill_holes, conflict warnings."""

import json

import numpy as np

from splatedit.data import default_model_path
from splatedit.io import read
from tests.cli.test_cli import run_cli


def _script(tmp_path, fill_holes: bool):
    p = read(default_model_path()).positions
    tip = p[np.argmax(p[:, 1])]
    d = np.linalg.norm(p - tip, axis=1)
    # a support painted with half a ring left out right next to the handle
    support = np.flatnonzero((d < 0.2) & ~((d > 0.05) & (d < 0.056) & (p[:, 0] > tip[0])))
    handle = np.flatnonzero(d <= 0.05)
    sup = {"indices": support.tolist()}
    if not fill_holes:
        sup["fill_holes"] = False
    path = tmp_path / f"edit-{fill_holes}.json"
    path.write_text(json.dumps({"version": 1, "edits": [{
        "support": sup, "handle": {"indices": handle.tolist()},
        "transform": {"translate": [0.05, 0.0, 0.0]}}]}))
    return path


def test_deform_closes_the_ring_and_reports_it(tmp_path):
    out = tmp_path / "out.ply"
    res = run_cli("deform", default_model_path(), "--edit", _script(tmp_path, True), "-o", out)
    assert res.returncode == 0, res.stderr
    assert "(closure added " in res.stdout
    assert "fixed splats lie within" not in res.stderr


def test_deform_without_closure_warns_about_conflicting_fixed_splats(tmp_path):
    out = tmp_path / "out.ply"
    res = run_cli("deform", default_model_path(), "--edit", _script(tmp_path, False), "-o", out)
    assert res.returncode == 0, res.stderr
    assert "(closure added" not in res.stdout
    warn = [ln for ln in res.stderr.splitlines() if "fixed splats lie within" in ln]
    assert len(warn) == 1 and warn[0].startswith("splatedit: warning: edit 0: ")
    assert "handle 0" in warn[0] and "around (" in warn[0]


def test_fill_holes_must_be_a_boolean(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps({"version": 1, "edits": [{
        "support": {"sphere": {"center": [0, 0, 0], "radius": 1}, "fill_holes": "no"},
        "handle": {"sphere": {"center": [0, 0, 0], "radius": 0.1}}, "transform": {"translate": [0, 0, 0.1]}}]}))
    res = run_cli("deform", default_model_path(), "--edit", path, "-o", tmp_path / "o.ply")
    assert res.returncode == 2
    assert res.stderr.strip().splitlines() == [
        f"splatedit: error: {path}: $.edits[0].support.fill_holes: must be true or false, got the string 'no'"]
