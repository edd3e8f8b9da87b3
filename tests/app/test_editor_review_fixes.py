"""Review fixes of the editor that need no window: save refusal, typed
scale factors, commit validation, the curve-point check, the shared Job and
the shared perspective matrix."""

from __future__ import annotations

import threading
import types
from pathlib import Path

import numpy as np
import pytest

from splatedit.select.selection import HANDLE, SUPPORT
from splatedit.app.view.camera_control import OrbitCamera
from splatedit.app.editor import Editor, check_model_file, save_refusal
from splatedit.app.file_actions import FileActions
from splatedit.app.document.jobs import Cancelled, Job
from splatedit.app.document.session import GRAB, SCALE, Manipulation, Session, ViewInfo
from splatedit.errors import InputError, SplatEditError
from splatedit.model import SplatCloud
from splatedit.render.camera import Camera, perspective
from tests.app.sessions import plane_cloud, view




def paint(s, support_r=0.8, handle_r=0.15):
    r = np.linalg.norm(s.cloud.positions[:, :2], axis=1)
    s.brush_target = SUPPORT
    s.end_stroke(s.paint(np.flatnonzero(r < support_r)))
    s.brush_target = HANDLE
    s.end_stroke(s.paint(np.flatnonzero(r < handle_r)))
    return r


# ------------------------------------------------------------------ saving
def test_save_refusal_of_the_input_file(tmp_path, monkeypatch):
    model = tmp_path / "scan.ply"
    model.write_bytes(b"ply")
    monkeypatch.chdir(tmp_path)
    for same in (model, Path("scan.ply"), tmp_path / "sub" / ".." / "scan.ply"):
        msg = save_refusal(same, model)
        assert msg and "opened model" in msg and "scan.ply" in msg
    link = tmp_path / "link.ply"
    link.symlink_to(model)
    assert save_refusal(link, model)                       # resolves symlinks
    assert save_refusal(tmp_path / "scan-edited.ply", model) is None
    assert save_refusal(tmp_path / "new.ply", None) is None
    # the edit script written beside the save must not replace the model either
    odd = tmp_path / "odd.edits.json"
    assert save_refusal(tmp_path / "odd.ply", odd)


def test_editor_save_refuses_the_input_and_writes_nothing(tmp_path):
    model = tmp_path / "scan.ply"
    model.write_bytes(b"original")
    said = []
    stub = types.SimpleNamespace(session=object(), jobs={}, path=model, say=said.append)
    FileActions(stub).save(tmp_path / "." / "scan.ply")
    assert stub.jobs == {} and len(said) == 1 and "not saved" in said[0]
    assert model.read_bytes() == b"original"


def test_check_model_file(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        check_model_file(tmp_path / "missing.ply")
    with pytest.raises(InputError, match="directory"):
        check_model_file(tmp_path)
    (tmp_path / "a.obj").write_text("v 0 0 0\n")
    with pytest.raises(InputError, match="unsupported file extension '.obj'"):
        check_model_file(tmp_path / "a.obj")
    (tmp_path / "ok.XYZ").write_text("0 0 0\n")
    check_model_file(tmp_path / "ok.XYZ")


# ------------------------------------------------------------ typed scale
def test_typed_scale_factor_must_be_positive():
    piv = np.array([1.0, 2.0, 3.0])
    m = Manipulation(SCALE, piv, view(), (110, 100))
    m.mouse = (120, 100)
    for typed in ("-2", "0", "0.0", "-0.5"):
        m.typed = typed
        assert m.problem() and "> 0" in m.problem()
        assert "> 0" in m.describe()
        a = m.matrix()
        assert np.linalg.det(a[:3, :3]) > 0          # never a reflection
        assert np.allclose(np.diag(a)[:3], 2.0)       # the mouse's factor meanwhile
    m.typed = "0.5"
    assert m.problem() is None and np.allclose(np.diag(m.matrix())[:3], 0.5)
    m.set_axis(1)
    assert np.allclose(np.diag(m.matrix())[:3], [1, 0.5, 1])
    assert np.allclose(m.matrix()[:3, :3] @ piv + m.matrix()[:3, 3], piv)
    g = Manipulation(GRAB, piv, view(), (0, 0))
    g.typed = "-2"
    assert g.problem() is None                        # negative distances are fine


def test_session_refuses_a_negative_scale_and_keeps_the_state():
    s = Session(plane_cloud(), fit_sync=True)
    try:
        paint(s)
        assert s.wait_fit()
        base = s.cloud
        assert s.begin(SCALE, view(), (110, 100))
        for ch in "2":
            s.manip.type_char(ch)
        s.manip.type_char("-")
        assert s.manip.typed == "-2"
        with pytest.raises(SplatEditError, match="> 0"):
            s.finish()
        with pytest.raises(SplatEditError, match="> 0"):
            s.commit()
        assert s.manip is not None and s.cloud is base and s.edits == ()
        s.manip.type_char("-")                        # back to "2": applied
        assert s.finish() == "commit" and len(s.edits) == 1
    finally:
        s.close()


# ------------------------------------------------------- commit validation
def _plane_with_tiny_corner_splats(length):
    c = plane_cloud()
    r = np.linalg.norm(c.positions[:, :2], axis=1)
    corner = np.flatnonzero(r > 1.35)
    u, v = c.u.copy(), c.v.copy()
    u[corner] = [length, 0, 0]
    v[corner] = [0, length, 0]
    return SplatCloud(c.positions, u, v, name="plane")


@pytest.mark.parametrize("length, ok", [(4e-9, False), (6e-9, True)])
def test_commit_validates_against_the_whole_cloud(length, ok):
    """Tiny splats outside the support are valid in the 2.83-diagonal plane; a
    handle lifted by 3 grows the diagonal to 4.12, so the minimum axis length
    (1e-9 of it) exceeds 4e-9: the commit must fail as reading the saved file
    would, although the moved splats alone (diagonal 3.4) are fine."""
    c = _plane_with_tiny_corner_splats(length)
    s = Session(c, fit_sync=True)
    try:
        paint(s)
        assert s.wait_fit()
        assert s.begin(GRAB, view(), (100, 100))
        s.manip.set_axis(2)
        s.manip.type_char("3")
        if not ok:
            with pytest.raises(InputError, match="degenerate splat axis"):
                s.commit()
            assert s.cloud is c and s.edits == ()
            return
        assert s.commit()
        out = s.cloud
        assert out.diagonal > 4.0
        out.validate()
        SplatCloud(out.positions, out.u, out.v)       # what reading the saved file does
    finally:
        s.close()


# ------------------------------------------------------------ curve points
def test_curve_point_coincidence_uses_the_curve_check():
    s = Session(plane_cloud(), fit_sync=True)
    try:
        p = np.array([0.5, 0.25, 0.0])
        assert s.add_curve_point(p)
        with pytest.raises(SplatEditError, match="last point"):
            s.add_curve_point(p)
        with pytest.raises(SplatEditError, match="last point"):
            s.add_curve_point(p + 1e-12)
        assert s.add_curve_point(p + [0.01, 0, 0])
        assert len(s.curve_points) == 2 and s.curve() is not None
    finally:
        s.close()


# -------------------------------------------------------------------- jobs
def test_job_thread_sync_and_cancel():
    woke = threading.Event()
    j = Job("work", lambda progress: (progress("half", 0.5), 42)[1], woke.set)
    assert j.wait(10) and j.done and j.result == 42 and j.error is None and woke.is_set()
    assert j.stage == "half" and j.fraction == 0.5
    bad = Job("bad", lambda progress: (_ for _ in ()).throw(SplatEditError("nope")), sync=True)
    assert bad.done and isinstance(bad.error, SplatEditError)
    gate = threading.Event()

    def slow(progress):
        gate.wait(10)
        progress("more", 0.9)
        return "late"

    c = Job("slow", slow, key=("k",))
    c.cancel.set()
    gate.set()
    assert c.wait(10) and isinstance(c.error, Cancelled) and c.result is None and c.key == ("k",)


# -------------------------------------------------------------- projection
def test_orbit_camera_and_camera_share_the_perspective():
    oc = OrbitCamera(distance=5.0, scene_radius=1.0, fov_deg=50.0)
    n, f = oc.near_far()
    assert np.array_equal(oc.projection(1.5), perspective(50.0, 1.5, n, f))
    cam = Camera((0, 0, 5), (0, 0, 0), fov_deg=50.0)
    assert np.array_equal(cam.projection_matrix(1.5, n, f), perspective(50.0, 1.5, n, f))


def test_an_overflowing_typed_value_is_a_problem_not_a_crash():
    g = Manipulation(GRAB, np.zeros(3), view(), (0, 0))
    g.typed = "9" * 400
    assert g.problem() == "the typed value is too large"
    assert np.array_equal(g.matrix(), np.eye(4))
