"""Edit scripts: every bad value is reported with its JSON path; good ones round-trip."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest

from splatedit.errors import EditScriptError
from splatedit.script import EditScript, Matrix, TRS, load_script, parse_script
from splatedit.select import Box, Indices, Sphere

GOOD = {
    "version": 1,
    "solver": {"method": "iqr", "tol": 1e-7},
    "edits": [
        {"support": {"sphere": {"center": [0, 0, 0], "radius": 1.0}},
         "handle": {"sphere": {"center": [0, 0.5, 0], "radius": 0.2}},
         "transform": {"translate": [0, 0.1, 0],
                       "rotate": {"axis": [0, 0, 1], "degrees": 30, "center": [0, 0, 0]},
                       "scale": 1.2}},
        {"support": {"box": {"min": [-1, -1, -1], "max": [1, 1, 1]}},
         "handles": [{"indices": [1, 2, 3]}, {"indices": [7]}],
         "transforms": [{"matrix": [[1, 0, 0, 0.1], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]},
                        {"translate": [0, 0, 1]}]},
    ],
}


def _with(path, value):
    """A copy of GOOD with the value at a simple path replaced (None deletes)."""
    doc = copy.deepcopy(GOOD)
    node = doc
    for key in path[:-1]:
        node = node[key]
    if value is _DELETE:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return doc


_DELETE = object()

BAD_SCRIPTS = [
    (["version"], 2, "$.version", "unsupported version"),
    (["version"], _DELETE, "$", "missing key 'version'"),
    (["edits"], [], "$.edits", "non-empty list"),
    (["solver", "method"], "cholesky", "$.solver.method", "must be one of auto, iqr, lu"),
    (["solver", "tol"], -1, "$.solver.tol", "must be > 0"),
    (["solver", "tol"], "small", "$.solver.tol", "must be a number"),
    (["edits", 0, "support"], {"cube": {}}, "$.edits[0].support.cube", "unknown key"),
    (["edits", 0, "support", "sphere", "radius"], 0, "$.edits[0].support.sphere.radius", "must be > 0"),
    (["edits", 0, "support", "sphere", "center"], [0, 0], "$.edits[0].support.sphere.center", "3 numbers"),
    (["edits", 0, "handle", "sphere", "center"], [0, "x", 0], "$.edits[0].handle.sphere.center[1]", "must be a number"),
    (["edits", 0, "transform", "rotate", "axis"], [0, 0, 0], "$.edits[0].transform.rotate.axis", "zero vector"),
    (["edits", 0, "transform", "rotate", "degrees"], float("nan"), "$.edits[0].transform.rotate.degrees", "finite"),
    (["edits", 0, "transform", "scale"], -2, "$.edits[0].transform.scale", "must be > 0"),
    (["edits", 0, "transform", "shear"], 1, "$.edits[0].transform.shear", "unknown key"),
    (["edits", 0, "transform"], {}, "$.edits[0].transform", "is empty"),
    (["edits", 0, "handle"], _DELETE, "$.edits[0]", "exactly one of 'handle' or 'handles'"),
    (["edits", 1, "support", "box", "min"], [2, -1, -1], "$.edits[1].support.box.min[0]", "greater than max"),
    (["edits", 1, "handles", 0, "indices"], [1, -2], "$.edits[1].handles[0].indices[1]", "non-negative integer"),
    (["edits", 1, "transforms"], [{"translate": [0, 0, 1]}], "$.edits[1].transforms", "one transform per handle"),
    (["edits", 1, "transforms", 0, "matrix", 3], [0, 0, 1, 1], "$.edits[1].transforms[0].matrix[3]", "last row"),
    (["edits", 1, "transforms", 0, "matrix"], [[0] * 4] * 3 + [[0, 0, 0, 1]], "$.edits[1].transforms[0].matrix", "singular"),
    (["edits", 1, "transforms", 0, "matrix", 0], [1, 0, 0], "$.edits[1].transforms[0].matrix[0]", "4 numbers"),
]


@pytest.mark.parametrize("path,value,json_path,message", BAD_SCRIPTS,
                         ids=[b[2] + ":" + b[3] for b in BAD_SCRIPTS])
def test_bad_script_value_is_reported_with_its_json_path(path, value, json_path, message):
    with pytest.raises(EditScriptError) as info:
        parse_script(_with(path, value), source="edit.json")
    assert info.value.json_path == json_path
    assert message in str(info.value)
    assert str(info.value).startswith(f"edit.json: {json_path}: ")


def test_good_script_parses_into_regions_and_transforms():
    s = parse_script(GOOD)
    assert s.solver.method == "iqr"
    e0, e1 = s.edits
    assert isinstance(e0.support, Sphere) and isinstance(e0.transforms[0], TRS)
    assert isinstance(e1.support, Box) and isinstance(e1.handles[0], Indices)
    assert isinstance(e1.transforms[0], Matrix)


def test_script_json_round_trip_is_identity():
    s = parse_script(GOOD)
    assert parse_script(json.loads(json.dumps(s.to_json()))) == s


def test_trs_matrix_scales_then_rotates_then_translates():
    t = parse_script(GOOD).edits[0].transforms[0]
    m = t.matrix(handle_centroid=np.array([5.0, 5.0, 5.0]))  # rotation centre given, scale centre = centroid
    p = np.array([1.0, 0.0, 0.0, 1.0])
    # scale 1.2 about (5,5,5), then rotate 30 deg about z through the origin, then translate (0,0.1,0)
    q = np.array([5, 5, 5]) + 1.2 * (p[:3] - 5)
    c, s_ = np.cos(np.radians(30)), np.sin(np.radians(30))
    q = np.array([c * q[0] - s_ * q[1], s_ * q[0] + c * q[1], q[2]]) + [0, 0.1, 0]
    np.testing.assert_allclose((m @ p)[:3], q, atol=1e-12)


def test_invalid_json_names_file_and_line(tmp_path):
    p = tmp_path / "broken.json"
    p.write_text('{"version": 1,\n "edits": [}\n')
    with pytest.raises(EditScriptError, match=r"broken.json: \$: invalid JSON at line 2"):
        load_script(p)


def test_missing_script_file_is_a_clear_error(tmp_path):
    with pytest.raises(EditScriptError, match="cannot read"):
        load_script(tmp_path / "nope.json")
