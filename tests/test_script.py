"""Edit scripts: every bad value is reported with its JSON path; good ones round-trip."""

from __future__ import annotations

import copy
import json

import numpy as np
import pytest

from splatedit.errors import EditScriptError
from splatedit.script import (
    Curve,
    EditScript,
    Matrix,
    TRS,
    load_script,
    parse_script,
    resolve_edit_inputs,
    run_script,
)
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
        {"support": {"sphere": {"center": [0, 0, 0], "radius": 0.7}},
         "curves": [{"points": [[-0.4, 0, 0], [0, 0.1, 0], [0.4, 0, 0]],
                     "move": [[0, 0, 0], [0, 0, 0.1], [0, 0, 0]]},
                    {"points": [[0, -0.3, 0], [0, 0.3, 0.05]], "move": [[0, 0, 0.05], [0, 0, 0.05]],
                     "samples": 12}]},
        {"support": {"sphere": {"center": [0, 0, 0], "radius": 0.9}},
         "handle": {"sphere": {"center": [0.5, 0, 0], "radius": 0.1}},
         "transform": {"translate": [0, 0, 0.1]},
         "curves": [{"points": [[-0.5, -0.2, 0], [-0.5, 0.2, 0]], "move": [[0, 0, 0.1], [0, 0, 0.1]]}]},
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
    (["edits", 1, "transforms", 0, "matrix"], [[-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]],
     "$.edits[1].transforms[0].matrix", "mirrors the handle"),
    (["edits", 1, "transforms", 0, "matrix", 3], [0, 0, 0, 1.0000000001], "$.edits[1].transforms[0].matrix[3]",
     "last row"),
    # control curves
    (["edits", 2, "curves"], [], "$.edits[2].curves", "non-empty list of curves"),
    (["edits", 2, "curves"], _DELETE, "$.edits[2]", "at least one handle or curve"),
    (["edits", 2, "transform"], {"translate": [0, 0, 1]}, "$.edits[2].transform", "without 'handle'"),
    (["edits", 2, "curves", 0, "points"], [[0, 0, 0]], "$.edits[2].curves[0].points", "at least 2 points"),
    (["edits", 2, "curves", 0, "points", 1], [0, 0], "$.edits[2].curves[0].points[1]", "3 numbers"),
    (["edits", 2, "curves", 0, "points", 2], [0, 0.1, 0], "$.edits[2].curves[0].points[2]",
     "coincides with points[1]"),
    (["edits", 2, "curves", 0, "move"], [[0, 0, 0]], "$.edits[2].curves[0].move", "one [dx, dy, dz] per point (3)"),
    (["edits", 2, "curves", 0, "move", 1, 2], "up", "$.edits[2].curves[0].move[1][2]", "must be a number"),
    (["edits", 2, "curves", 0, "move", 1, 2], float("inf"), "$.edits[2].curves[0].move[1][2]", "finite"),
    (["edits", 2, "curves", 0, "move"], _DELETE, "$.edits[2].curves[0]", "missing key 'move'"),
    (["edits", 2, "curves", 1, "samples"], 1, "$.edits[2].curves[1].samples", "integer >= 2"),
    (["edits", 2, "curves", 1, "samples"], 2.5, "$.edits[2].curves[1].samples", "integer >= 2"),
    (["edits", 2, "curves", 1, "knots"], [0, 1], "$.edits[2].curves[1].knots", "unknown key"),
    (["edits", 3, "curves", 0], [[0, 0, 0]], "$.edits[3].curves[0]", "must be an object"),
    # issue 12 class 5: numbers beyond what a model can hold, named by path
    (["edits", 0, "transform", "translate", 0], 10 ** 400, "$.edits[0].transform.translate[0]", "finite"),
    (["edits", 0, "transform", "translate", 1], -1e300, "$.edits[0].transform.translate[1]",
     "beyond the supported magnitude"),
    (["edits", 0, "transform", "rotate", "axis"], [1e308, 1e308, 0], "$.edits[0].transform.rotate.axis[0]",
     "beyond the supported magnitude"),
    (["edits", 2, "curves", 0, "points", 1], [1e20, 0, 0], "$.edits[2].curves[0].points[1][0]",
     "beyond the supported magnitude"),
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
    e0, e1 = s.edits[:2]
    assert isinstance(e0.support, Sphere) and isinstance(e0.transforms[0], TRS)
    assert isinstance(e1.support, Box) and isinstance(e1.handles[0], Indices)
    assert isinstance(e1.transforms[0], Matrix)
    e2, e3 = s.edits[2:]
    assert e2.handles == () and len(e2.curves) == 2 and e2.curves[1].samples == 12
    assert isinstance(e2.curves[0], Curve) and e2.curves[0].move[1] == (0.0, 0.0, 0.1)
    assert len(e3.handles) == 1 and len(e3.curves) == 1 and e3.curves[0].samples is None
    # the existing handle-only format is unchanged
    assert s.edits[0].curves == () and s.edits[1].curves == ()


def test_script_json_round_trip_is_identity():
    s = parse_script(GOOD)
    out = s.to_json()
    assert parse_script(json.loads(json.dumps(out))) == s
    assert "handle" not in out["edits"][2] and "handles" not in out["edits"][2]
    assert "samples" not in out["edits"][2]["curves"][0] and out["edits"][2]["curves"][1]["samples"] == 12


# ------------------------------------------------------------- running curves
def _on_surface(xy):
    """Points of ``wavy_plane_cloud``'s surface (default amplitude and waves) above ``xy``."""
    xy = np.asarray(xy, dtype=np.float64)
    w = 1.5 * np.pi
    return np.column_stack([xy, 0.15 * np.sin(w * xy[:, 0]) * np.cos(w * xy[:, 1])]).tolist()


def test_run_curve_script_moves_the_surface_with_the_curve():
    from scipy.spatial import cKDTree

    from splatedit.bench.solve import wavy_plane_cloud
    from splatedit.deform.basis import DeformationBasis

    cloud = wavy_plane_cloud(50)
    pts = _on_surface([[-0.4, -0.1], [-0.1, 0.1], [0.2, 0.0], [0.4, 0.1]])
    lift = [0.0, 0.0, 0.08]
    doc = {"version": 1, "solver": {"method": "lu"},
           "edits": [{"support": {"sphere": {"center": [0, 0, 0], "radius": 0.7}},
                      "curves": [{"points": pts, "move": [lift] * 4}]},
                     {"support": {"sphere": {"center": [0, 0, 0], "radius": 0.9}},
                      "handle": {"sphere": {"center": [0.6, 0, 0], "radius": 0.12}},
                      "transform": {"translate": [0, 0, -0.05]},
                      "curves": [{"points": _on_surface([[-0.6, -0.2], [-0.6, 0.2]]),
                                  "move": [[0, 0, 0.05], [0, 0, 0.1]], "samples": 20}]}]}
    script = parse_script(doc)
    first_only = EditScript(script.edits[:1], script.solver)
    out1, reps1 = run_script(cloud, first_only)
    # the same edit through the API: identical result
    r = resolve_edit_inputs(cloud, script.edits[0])
    b = DeformationBasis.fit(cloud, r.support, r.handles, curves=r.curves, method="lu")
    np.testing.assert_array_equal(b.apply(cloud, b.displacement(r.inputs, mode=r.deformation)).positions, out1.positions)
    # splats right at the curve are lifted with it; outside the support nothing moves
    d = out1.positions - cloud.positions
    dist, _ = cKDTree(b.constraints.groups[0].points).query(cloud.positions)
    near = r.support & (dist < 0.5 * b.constraints.spacing)
    assert near.sum() >= 5
    assert np.abs(d[near] - lift).max() < 0.05 * 0.08
    assert np.array_equal(out1.positions[~r.support], cloud.positions[~r.support])
    assert reps1[0].handles == [] and reps1[0].curves[0][0] == 4
    assert "curve 4 points/" in reps1[0].line()
    # handle + curve edit after it
    out2, reps2 = run_script(cloud, script)
    assert reps2[1].curves == [(2, 20)] and len(reps2[1].handles) == 1
    assert "handle" in reps2[1].line() and "curve 2 points/20 samples" in reps2[1].line()
    hnd = np.linalg.norm(out1.positions - [0.6, 0, 0], axis=1) <= 0.12
    np.testing.assert_allclose(out2.positions[hnd], out1.positions[hnd] + [0, 0, -0.05], atol=1e-12)


def test_curve_entirely_outside_the_free_region_is_reported_with_the_edit_path():
    from splatedit.bench.solve import wavy_plane_cloud
    cloud = wavy_plane_cloud(30)
    doc = {"version": 1, "edits": [{"support": {"sphere": {"center": [0, 0, 0], "radius": 0.3}},
                                    "curves": [{"points": [[0.8, 0.8, 0.0], [0.9, 0.8, 0.0]],
                                                "move": [[0, 0, 0.1]] * 2}]}]}
    with pytest.raises(EditScriptError, match=r"\$\.edits\[0\]: curve 0: none of its"):
        run_script(cloud, parse_script(doc))


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


def test_uniform_tiny_scale_is_not_called_singular():
    doc = copy.deepcopy(GOOD)
    doc["edits"][1]["transforms"][0] = {"matrix": [[1e-4, 0, 0, 0], [0, 1e-4, 0, 0], [0, 0, 1e-4, 0], [0, 0, 0, 1]]}
    parse_script(doc)


def test_edit_that_makes_splats_degenerate_is_refused_with_its_json_path():
    from splatedit.bench.solve import sphere_cloud
    from splatedit.script import run_script
    cloud = sphere_cloud(3000)
    doc = {"version": 1, "edits": [
        {"support": {"sphere": {"center": [0, 0, 1], "radius": 0.8}},
         "handle": {"sphere": {"center": [0, 0, 1], "radius": 0.3}}, "transform": {"scale": 1e-9}}]}
    with pytest.raises(EditScriptError, match=r"\$\.edits\[0\]: the edit makes splats degenerate"):
        run_script(cloud, parse_script(doc))


# ------------------------------------------- issue 12 class 5: hostile script files
HOSTILE_SCRIPT_FILES = [
    # (id, file bytes, expected substrings of the error)
    ("10^400 integer literal", b'{"version": 1, "edits": [{"support": {"indices": [1' + b"0" * 400 + b']}}]}',
     ["$.edits[0].support.indices[0]", "non-negative integer"]),
    ("5000-digit integer", b'{"version": 1, "edits": [{"support": {"sphere": {"center": [0, 0, 0], "radius": '
     + b"7" * 5000 + b"}}}]}", ["$.edits[0].support.sphere.radius", "finite"]),
    ("100,000 nested brackets", b"[" * 100_000 + b"]" * 100_000, ["nested too deeply"]),
    ("non-UTF-8 bytes", b'{"version": 1, "edits": [\xff\xfe]}', ["not UTF-8", "0xff", "offset 25", "line 1"]),
]


@pytest.mark.parametrize("data,expected", [c[1:] for c in HOSTILE_SCRIPT_FILES],
                         ids=[c[0] for c in HOSTILE_SCRIPT_FILES])
def test_hostile_script_file_is_one_edit_script_error(tmp_path, data, expected):
    path = tmp_path / "edit.json"
    path.write_bytes(data)
    with pytest.raises(EditScriptError) as info:
        load_script(path)
    msg = str(info.value)
    assert msg.startswith(f"{path}: ")
    for sub in expected:
        assert sub in msg, f"{sub!r} not in {msg!r}"


@pytest.mark.parametrize("curve,json_path", [
    ({"points": [[-0.1, 0.4, -0.05], [0, 0.45, -0.05]], "move": [[0, 0.02, 0]] * 2, "samples": 10_000_000},
     "$.edits[0].curves[0].samples"),
    ({"points": [[-0.1, 0.4, -0.05], [1e9, 0, 0]], "move": [[0, 0.02, 0]] * 2}, "$.edits[0].curves[0].points"),
])
def test_curve_sample_count_is_bounded_by_the_model_before_allocating(curve, json_path):
    """"samples": 10^7 ran 37 s to a MemoryError, a point at 1e9 asked for
    1.25 TiB: both are refused at once, naming the curve."""
    import time
    import tracemalloc
    from splatedit.data import default_model_path
    from splatedit.io import read
    cloud = read(default_model_path())
    doc = {"version": 1, "edits": [{"support": {"sphere": {"center": [-0.07, 0.37, -0.05], "radius": 0.2}},
                                    "curves": [curve]}]}
    tracemalloc.start()
    t0 = time.perf_counter()
    try:
        with pytest.raises(EditScriptError) as info:
            run_script(cloud, parse_script(doc))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert time.perf_counter() - t0 < 5.0 and peak < 200 * 2**20
    assert info.value.json_path == json_path and "more than the model can use" in str(info.value)


def test_rotation_axis_of_extreme_magnitude_keeps_its_direction():
    """[1e-200, 1e-200, 0] must rotate about the diagonal (its squared norm underflows)."""
    from splatedit.deform.transform import rotation_matrix
    r = rotation_matrix([1e-200, 1e-200, 0], 90.0)
    ref = rotation_matrix([1.0, 1.0, 0], 90.0)
    np.testing.assert_allclose(r, ref, atol=1e-15)
    r = rotation_matrix([1e300, 1e300, 0], 90.0)
    np.testing.assert_allclose(r, ref, atol=1e-15)


def test_deformation_key_selects_the_detail_mode_and_round_trips(tmp_path):
    import json as _json
    from splatedit.deform.modes import DeformationMode
    from splatedit.errors import EditScriptError
    from splatedit.script import load_script
    doc = {"version": 1, "edits": [{"support": {"sphere": {"center": [0, 0, 0], "radius": 1}},
                                    "handle": {"sphere": {"center": [0, 0.4, 0], "radius": 0.1}},
                                    "transform": {"translate": [0, 0.1, 0]}, "deformation": "Detail"}]}
    p = tmp_path / "e.json"
    p.write_text(_json.dumps(doc))
    s = load_script(p)
    assert s.edits[0].deformation is DeformationMode.DETAIL
    assert s.to_json()["edits"][0]["deformation"] == "detail"
    doc["edits"][0]["deformation"] = "bendy"
    p.write_text(_json.dumps(doc))
    with pytest.raises(EditScriptError, match=r"\$\.edits\[0\]\.deformation"):
        load_script(p)


@pytest.mark.parametrize("value, message", [
    ("sideways", "unknown deformation mode 'sideways'"),
    (3, "must be one of"),
])
def test_bad_deformation_mode_names_its_json_path(value, message):
    data = copy.deepcopy(GOOD)
    data["edits"][1]["deformation"] = value
    with pytest.raises(EditScriptError) as info:
        parse_script(data)
    assert info.value.json_path == "$.edits[1].deformation" and message in str(info.value)


def test_deformation_mode_defaults_to_rotation_and_round_trips():
    from splatedit.deform.modes import DeformationMode
    data = copy.deepcopy(GOOD)
    data["edits"][0]["deformation"] = "Linear"
    s = parse_script(data)
    n = len(s.edits)
    assert [e.deformation for e in s.edits] == [DeformationMode.LINEAR] + [DeformationMode.ROTATION] * (n - 1)
    out = s.to_json()
    assert [e["deformation"] for e in out["edits"]] == ["linear"] + ["rotation"] * (n - 1)
    assert parse_script(out) == s


def test_script_modes_differ_only_in_rotation_and_report_the_mode():
    """A 120-degree rotation of the bunny's ear: the rotation mode keeps the
    ear's size (its splats' spread about their centroid) where the linear mode
    shrinks it; the report line names the mode."""
    from splatedit.data import default_model_path
    from splatedit.io import read
    cloud = read(default_model_path())
    lo, hi = cloud.bounds()
    ear = cloud.positions[np.argmax(cloud.positions[:, 1])]
    size = float(np.linalg.norm(hi - lo))
    base = {"support": {"sphere": {"center": ear.tolist(), "radius": 0.35 * size}},
            "handle": {"sphere": {"center": ear.tolist(), "radius": 0.08 * size}},
            "transform": {"rotate": {"axis": [0, 0, 1], "degrees": 120}}}
    spread = {}
    for mode in ("linear", "rotation"):
        s = parse_script({"version": 1, "edits": [dict(base, deformation=mode)]})
        out, reps = run_script(cloud, s)
        assert reps[0].line().startswith(f"edit 0: {mode} deformation, ")
        dp = np.linalg.norm(out.positions - cloud.positions, axis=1)
        moved = dp > 1e-3 * size
        mid = moved & (np.linalg.norm(cloud.positions - ear, axis=1) > 0.1 * size)
        spread[mode] = np.linalg.norm(out.positions[mid] - out.positions[mid].mean(0), axis=1).mean() / \
            np.linalg.norm(cloud.positions[mid] - cloud.positions[mid].mean(0), axis=1).mean()
    print(spread)
    assert spread["rotation"] > spread["linear"]


def test_a_misspelt_required_key_is_named_with_the_missing_one():
    """A user wrote "degress": the error names the missing 'degrees' and the
    misspelling (it used to name only the missing key)."""
    script = {"version": 1, "edits": [{
        "support": {"sphere": {"center": [0, 0, 0], "radius": 1}},
        "handle": {"sphere": {"center": [0, 0, 0], "radius": 0.2}},
        "transform": {"rotate": {"axis": [0, 0, 1], "degress": 30}}}]}
    with pytest.raises(EditScriptError) as err:
        parse_script(script)
    assert err.value.json_path == "$.edits[0].transform.rotate"
    assert "missing key 'degrees' (is 'degress' a misspelling of it?)" in str(err.value)


@pytest.mark.parametrize("path,typo,json_path,meant", [
    (["edits", 0, "support"], {"sphere": {"center": [0, 0, 0], "radius": 1.0}, "fill_hole": False},
     "$.edits[0].support.fill_hole", "fill_holes"),
    (["edits", 0], None, "$.edits[0].transfrom", "transform"),
])
def test_misspelt_key_error_names_the_key_it_resembles(path, typo, json_path, meant):
    """A typo in a key (a hand-edited saved script) is one error naming the
    known key it resembles; a support's ``fill_holes`` is among the keys listed."""
    doc = copy.deepcopy(GOOD)
    if typo is None:
        doc["edits"][0]["transfrom"] = doc["edits"][0].pop("transform")
    else:
        doc = _with(path, typo)
    with pytest.raises(EditScriptError) as info:
        parse_script(doc, source="edit.json")
    assert info.value.json_path == json_path
    assert f"misspelling of {meant!r}" in str(info.value)
    assert meant in str(info.value).split("allowed: ")[1]
