"""Delete and crop of the selected splats through the editor's keys: one
undo step each, recorded as ``delete`` / ``crop`` items of the edit script,
and the script replays to the document (also after a later deformation,
whose indices count in the smaller model)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from splatedit.app.document.session import Session
from splatedit.errors import EditScriptError
from splatedit.script import parse_script, run_script
from tests.app.sessions import plane_cloud
from tests.app.ui.test_editor_routing import StubEditor, key

glfw = pytest.importorskip("glfw")


@pytest.fixture
def ed():
    s = Session(plane_cloud(), fit_sync=True)
    yield StubEditor(s)
    s.close()


def _replayed(session):
    """The document the session's edit script gives from its source, via JSON."""
    script = parse_script(json.loads(json.dumps(session.edit_script().to_json())))
    out, reports = run_script(plane_cloud(), script)
    return out, reports


def test_delete_removes_the_support_and_undo_brings_it_back(ed):
    s = ed.session
    n0 = s.cloud.n
    floor = s.cloud.positions[:, 1] < -0.5
    s.set_selection(floor, np.zeros(n0, bool))
    key(ed, glfw.KEY_DELETE)
    assert s.cloud.n == n0 - floor.sum()
    assert np.array_equal(s.cloud.positions, plane_cloud().positions[~floor])
    assert s.history.labels[-1] == "delete" and not s.selection.support.any() and s.dirty
    out, reports = _replayed(s)
    assert np.array_equal(out.positions, s.cloud.positions) and "delete" in reports[0].line()
    key(ed, glfw.KEY_Z, glfw.MOD_CONTROL)
    assert s.cloud.n == n0 and s.selection.support.sum() == floor.sum()
    key(ed, glfw.KEY_Z, glfw.MOD_CONTROL | glfw.MOD_SHIFT)
    assert s.cloud.n == n0 - floor.sum()


def test_crop_keeps_only_the_support_and_a_later_edit_replays(ed):
    s = ed.session
    n0 = s.cloud.n
    p = s.cloud.positions
    keep = np.abs(p[:, 0]) < 0.5
    s.set_selection(keep, np.zeros(n0, bool))
    key(ed, glfw.KEY_DELETE, glfw.MOD_SHIFT)
    assert s.cloud.n == keep.sum() and s.history.labels[-1] == "crop"
    # a deformation after the crop: its indices count in the cropped model
    q = s.cloud.positions
    sup = np.ones(s.cloud.n, bool)
    top = q[:, 1] > 0.7
    s.set_selection(sup, top)
    s.wait_fit()
    s.pose[0] = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0.2], [0, 0, 0, 1]], float)
    s.commit()
    s.wait_commit()
    assert len(s.edits) == 2
    out, reports = _replayed(s)
    assert out.n == s.cloud.n
    assert np.allclose(out.positions, s.cloud.positions, rtol=0, atol=1e-9)
    assert s.cloud.positions[:, 2].max() > 0.1                  # the edit moved something


def test_delete_is_refused_without_a_support_or_when_nothing_would_be_left(ed):
    s = ed.session
    key(ed, glfw.KEY_DELETE)
    assert s.cloud.n == plane_cloud().n and "support" in ed.messages[-1]
    key(ed, glfw.KEY_A)
    key(ed, glfw.KEY_DELETE)
    assert s.cloud.n == plane_cloud().n and "whole model" in ed.messages[-1]
    assert len(s.edits) == 0


@pytest.mark.parametrize("item,path,text", [
    ({"delete": {"indices": [0, 5000]}}, "$.edits[0].delete.indices[1]", "out of range"),
    ({"crop": {"box": {"min": [5, 5, 5], "max": [6, 6, 6]}}}, "$.edits[0].crop", "selects no splat"),
    ({"delete": {"box": {"min": [-2, -2, -2], "max": [2, 2, 2]}}}, "$.edits[0].delete", "every splat"),
    ({"delete": {"indices": [0]}, "crop": {"indices": [1]}}, "$.edits[0]", "unknown key"),
    ({"delete": {"sphere": {"center": [0, 0, 0], "radius": -1}}}, "$.edits[0].delete.sphere.radius", "> 0"),
])
def test_bad_delete_and_crop_items_name_their_json_path(item, path, text):
    with pytest.raises(EditScriptError) as exc:
        script = parse_script({"version": 1, "edits": [item]})
        run_script(plane_cloud(), script)
    msg = str(exc.value)
    assert path in msg and text in msg, msg


def test_a_gaussian_scene_crops_with_its_properties_and_the_saved_file_replays(tmp_path):
    from splatedit.app.document import files
    from splatedit.app.document.gaussian import gaussian_document, gaussians_of
    from splatedit.data import gaussian_scene_path
    from splatedit.script.gaussian import run_script_gaussians
    from splatedit.io import read_gaussians
    scene = read_gaussians(gaussian_scene_path())
    s = Session(gaussian_document(scene), fit_sync=True)
    y = s.cloud.positions[:, 1]
    top = y > np.median(y)
    s.set_selection(top, np.zeros(len(y), bool))
    assert s.remove_splats(keep=True) == int((~top).sum())
    g = gaussians_of(s.cloud)
    assert len(g) == top.sum() and s.cloud.n == top.sum()
    assert list(g.extra) == list(scene.extra) and np.array_equal(g.sh, scene.sh[top])

    class Ed:            # what files.save needs of the editor
        session, jobs, path, save_as = s, {}, gaussian_scene_path(), None

        def say(self, text):
            pass

        def wake(self):
            pass
    ed = Ed()
    out = tmp_path / "top.ply"
    files.save(ed, out)
    ed.jobs["save"].wait()
    assert ed.jobs["save"].error is None
    saved = read_gaussians(out)
    replayed, reports = run_script_gaussians(scene, s.edit_script())
    assert "crop" in reports[0].line()
    assert np.array_equal(replayed.positions, saved.positions) and np.array_equal(replayed.sh, saved.sh)
    assert list(saved.extra) == list(scene.extra)
    s.undo()
    assert len(gaussians_of(s.cloud)) == len(scene)
    s.close()


def test_messages_name_gaussians_in_a_gaussian_scene_and_splats_otherwise(ed):
    """The tools' messages call a Gaussian scene's elements Gaussians, as
    the panel does (a tester saw "removed 512 splats" on a Gaussian scene)."""
    from splatedit.app.document.gaussian import gaussian_document
    from splatedit.data import gaussian_scene_path
    from splatedit.io import read_gaussians
    key(ed, glfw.KEY_DELETE)                                        # nothing selected
    assert "paint the splats" in ed.messages[-1]
    s = Session(gaussian_document(read_gaussians(gaussian_scene_path())), fit_sync=True)
    try:
        g = StubEditor(s)
        key(g, glfw.KEY_DELETE)
        assert "paint the Gaussians" in g.messages[-1]
        top = s.cloud.positions[:, 1] > np.median(s.cloud.positions[:, 1])
        s.set_selection(top, np.zeros(s.cloud.n, bool))
        key(g, glfw.KEY_DELETE)
        assert f"removed {int(top.sum()):,} Gaussians" in g.messages[-1], g.messages[-1]
    finally:
        s.close()
