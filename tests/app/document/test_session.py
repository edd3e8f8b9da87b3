"""Edit session: fit in the background, G/R/S matrices, commit, undo/redo, script export."""

import json
import math

import numpy as np
import pytest

from splatedit.select.selection import HANDLE, SUPPORT
from splatedit.app.document.session import GRAB, ROTATE, SCALE, Manipulation, Session, ViewInfo
from splatedit.model import SplatCloud
from tests.app.sessions import plane_cloud, view




def test_grab_matrix_mouse_axis_and_typed():
    m = Manipulation(GRAB, np.zeros(3), view(), (100, 100))
    m.mouse = (110, 80)
    assert np.allclose(m.matrix()[:3, 3], [0.1, 0.2, 0])
    m.set_axis(0)
    assert np.allclose(m.matrix()[:3, 3], [0.1, 0, 0])
    for ch in "-0.25":
        m.type_char(ch) if ch != "-" else None
    m.type_char("-")
    assert m.typed == "-0.25"
    assert np.allclose(m.matrix()[:3, 3], [-0.25, 0, 0])
    m.set_axis(2)
    assert np.allclose(m.matrix()[:3, 3], [0, 0, -0.25])


def test_rotate_and_scale_matrices():
    piv = np.array([1.0, 2.0, 3.0])
    r = Manipulation(ROTATE, piv, view(), (150, 100))
    r.mouse = (100, 50)  # quarter turn counter-clockwise on screen (y down)
    m = r.matrix()
    assert np.allclose(m[:3, :3] @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    assert np.allclose(m[:3, :3] @ piv + m[:3, 3], piv)
    r.type_char("9"); r.type_char("0"); r.set_axis(0)
    assert np.allclose(r.matrix()[:3, :3] @ [0, 1, 0], [0, 0, 1], atol=1e-12)
    s = Manipulation(SCALE, piv, view(), (110, 100))
    s.mouse = (120, 100)
    assert np.allclose(np.diag(s.matrix())[:3], 2.0)
    s.set_axis(1)
    assert np.allclose(np.diag(s.matrix())[:3], [1, 2, 1])
    assert np.allclose(s.matrix()[:3, :3] @ piv + s.matrix()[:3, 3], piv)


@pytest.fixture
def session():
    c = plane_cloud()
    s = Session(c, fit_sync=True)
    yield s
    s.close()


def paint_regions(s):
    c = s.cloud
    r = np.linalg.norm(c.positions[:, :2], axis=1)
    s.brush_target = SUPPORT
    s.end_stroke(s.paint(np.flatnonzero(r < 0.8)))
    s.brush_target = HANDLE
    s.end_stroke(s.paint(np.flatnonzero(r < 0.15)))
    return r


def test_full_session_commit_undo_redo_and_script(tmp_path, session):
    s = session
    r = paint_regions(s)
    assert s.wait_fit() and s.state == "ready"
    st = s.stats()
    assert st.fit.centers > 0 and st.support > st.handle > 0
    base = s.cloud
    assert s.begin(GRAB, view(), (100, 100))
    s.manip.set_axis(2)
    for ch in "0.3":
        s.manip.type_char(ch)
    dc = s.current_dc()
    assert dc.shape[1] == 3 and np.abs(dc).max() > 0
    assert s.commit()
    new = s.cloud
    h = r < 0.15
    fixed = r >= 0.8
    assert np.allclose(new.positions[h], base.positions[h] + [0, 0, 0.3])
    assert np.array_equal(new.positions[fixed], base.positions[fixed])
    free = (r < 0.8) & ~h
    dz = new.positions[free, 2]
    assert (dz > -1e-6).all() and (dz < 0.3 + 1e-6).all() and dz.max() > 0.05
    assert s.dirty and len(s.edits) == 1
    assert s.selection.counts == (int((r < 0.8).sum()), int(h.sum()))   # selection kept
    # undo the edit, redo it
    assert s.undo()
    assert s.cloud is base and not s.dirty
    assert s.redo()
    assert s.cloud is new
    # export + replay through the script runner gives the same cloud
    path = tmp_path / "e.json"
    s.edit_script().save(path)
    doc = json.loads(path.read_text())
    assert doc["edits"][0]["transform"]["matrix"][2][3] == 0.3
    from splatedit.deform.basis import DeformationBasis
    from splatedit.script import load_script, resolve_edit
    script = load_script(path)
    sup, hands, mats = resolve_edit(base, script.edits[0])
    assert script.edits[0].fill_holes is False   # the editor's selection, replayed as is
    b = DeformationBasis.fit(base, sup, hands, method=script.solver.method, tol=script.solver.tol,
                             max_centers=script.solver.max_centers, fill_holes=False)
    out = b.apply(base, b.displacement(mats))
    assert np.array_equal(out.positions, new.positions)
    assert np.array_equal(out.u, new.u)


def test_cancel_and_identity_commit(session):
    s = session
    paint_regions(s)
    s.wait_fit()
    base = s.cloud
    s.begin(SCALE, view(), (110, 100))
    s.manip.mouse = (130, 100)
    s.cancel()
    assert s.cloud is base and s.manip is None and s.state == "ready"
    s.begin(GRAB, view(), (100, 100))
    assert not s.commit()      # no motion: nothing recorded
    assert len(s.edits) == 0


def test_background_fit_stale_results_are_dropped():
    c = plane_cloud(40)
    s = Session(c)
    try:
        paint_regions(s)
        key1 = s.fit_job.key
        # change the selection while fitting: the old job is abandoned
        s.brush_target = HANDLE
        s.end_stroke(s.paint(np.flatnonzero(np.linalg.norm(c.positions[:, :2], axis=1) < 0.3)))
        assert s.fit_job.key != key1
        assert s.wait_fit(60)
        assert s.basis_key == s.selection_key()
    finally:
        s.close()


def test_rotation_mode_is_the_default_cycles_and_is_exported(tmp_path, session):
    """A 150-degree rotation in the session's default (rotation) mode keeps the
    handle's neighbourhood wide where the linear mode pulls it in; switching
    to linear and back keeps the fitted basis and the exported script carries it per edit."""
    from splatedit.deform.modes import DeformationMode
    from splatedit.deform.rotation import RotationDisplacement
    s = session
    r = paint_regions(s)
    assert s.deformation is DeformationMode.ROTATION
    assert s.wait_fit()
    assert s.begin(ROTATE, view(), (150, 100))
    s.manip.set_axis(0)
    for ch in "150":
        s.manip.type_char(ch)
    assert isinstance(s.current_dc(), RotationDisplacement)
    plain = s.basis
    assert s.set_deformation(DeformationMode.LINEAR) is DeformationMode.LINEAR
    assert s.basis is plain and isinstance(s.current_dc(), np.ndarray)   # no refit
    assert s.cycle_deformation() is DeformationMode.ROTATION
    assert s.basis is plain
    base = s.cloud
    assert s.commit()
    ring = (r > 0.35) & (r < 0.45)
    ring_r = lambda c: np.linalg.norm(c.positions[ring] - c.positions[ring].mean(0), axis=1).mean()  # noqa: E731
    doc = s.edit_script().to_json()
    assert doc["edits"][0]["deformation"] == "rotation"
    from splatedit.deform.basis import DeformationBasis
    from splatedit.script import parse_script, resolve_edit
    script = parse_script(doc)
    sup, hands, mats = resolve_edit(base, script.edits[0])
    b = DeformationBasis.fit(base, sup, hands, method=script.solver.method, tol=script.solver.tol,
                             fill_holes=False)
    out = b.apply(base, b.displacement(mats, mode=script.edits[0].deformation))
    assert np.array_equal(out.positions, s.cloud.positions)
    lin = b.apply(base, b.displacement(mats))
    assert ring_r(s.cloud) > ring_r(lin)


def test_history_entries_are_named_after_what_they_did(session):
    """Paint / Erase strokes and committed moves get their own names (not "edit")."""
    s = session
    paint_regions(s)
    assert s.wait_fit()
    p = s.cloud.positions
    s.brush_target = SUPPORT
    edge = np.flatnonzero(s.selection.support)[0]
    assert s.paint(np.flatnonzero(np.linalg.norm(p - p[edge], axis=1) < 0.05), erase=True)  # the rim
    s.end_stroke(True)
    assert s.wait_fit() and s.begin(GRAB, view(), (100, 100))
    s.manip.set_axis(2)
    for ch in "0.12":
        s.manip.type_char(ch)
    assert s.finish() == "commit"
    assert s.history.labels == ["open", "Paint support", "Paint handle", "Erase support", "Grab 0.12 along Z"]
    assert s.last_edit.label == "Grab 0.12 along Z"
