"""Several simultaneous handles and a non-rigid control curve in one session
(paper Sect. 3 end, Sect. 6 end): pose, commit, undo/redo, script export."""

import json

import numpy as np
import pytest

from splatedit.deform.modes import DeformationMode

from splatedit.select.selection import HANDLE, SUPPORT
from splatedit.app.document.session import Session, ViewInfo, GRAB
from splatedit.errors import SplatEditError
from splatedit.model import SplatCloud
from splatedit.script import load_script, run_script
from tests.app.sessions import plane_cloud, view




@pytest.fixture
def session():
    s = Session(plane_cloud(), fit_sync=True)
    yield s
    s.close()


def typed_move(s, axis, value, curve_point=None):
    ok = s.begin(GRAB, view(), (100, 100)) if curve_point is None else \
        s.begin_curve_point(curve_point, view(), (100, 100))
    assert ok
    s.manip.set_axis(axis)
    for ch in value:
        s.manip.type_char(ch)
    return s.finish()


def paint_support(s, radius=0.9):
    p = s.cloud.positions
    s.brush_target = SUPPORT
    s.end_stroke(s.paint(np.flatnonzero(np.linalg.norm(p[:, :2], axis=1) < radius)))


def near(s, c, r=0.16):
    return np.flatnonzero(np.linalg.norm(s.cloud.positions[:, :2] - c, axis=1) < r)


def replay(tmp_path, s, base):
    path = tmp_path / "e.json"
    s.edit_script().save(path)
    out, _ = run_script(base, load_script(path))
    return out, json.loads(path.read_text())


def test_two_handles_follow_their_own_transforms(tmp_path, session):
    s = session
    base = s.cloud
    paint_support(s)
    s.brush_target = HANDLE
    a, b = near(s, (-0.5, 0.0)), near(s, (0.5, 0.0))
    s.end_stroke(s.paint(a))
    assert s.add_handle() and s.selection.active == 1 and len(s.selection.handles) == 2
    s.end_stroke(s.paint(np.union1d(a, b)))           # the other handle's splats are not taken
    assert np.array_equal(np.flatnonzero(s.selection.handles[1]), b)
    assert s.wait_fit() and s.basis.n_columns == 8 and s.stats().columns == 8
    assert not s.single_rig
    # move the active handle (B) down, then A up: each keeps its own transform
    assert typed_move(s, 2, "-0.1") == "pose"
    assert s.select_handle(0)
    assert typed_move(s, 2, "0.2") == "pose"
    assert s.pose_pending and s.cloud is base
    dc = s.current_dc()
    assert dc.shape == (8, 3)
    assert s.commit()
    new = s.cloud
    assert np.allclose(new.positions[a], base.positions[a] + [0, 0, 0.2], atol=1e-12)
    assert np.allclose(new.positions[b], base.positions[b] + [0, 0, -0.1], atol=1e-12)
    out_sup = ~s.selection.support
    assert np.array_equal(new.positions[out_sup], base.positions[out_sup])
    assert not s.pose_pending and len(s.selection.handles) == 2    # handles kept, pose reset
    # export: handles + transforms; replay reproduces the cloud bitwise
    again, doc = replay(tmp_path, s, base)
    e = doc["edits"][0]
    assert len(e["handles"]) == 2 and len(e["transforms"]) == 2 and "curves" not in e
    assert e["transforms"][0]["matrix"][2][3] == 0.2
    assert np.array_equal(again.positions, new.positions) and np.array_equal(again.u, new.u)
    # undo: back to the pending pose (both transforms), then to A unmoved
    assert s.undo() and s.cloud is base and s.pose_pending
    assert s.pose[0][2, 3] == 0.2
    assert s.undo() and s.pose[0][2, 3] == 0.0 and s.pose[1][2, 3] == -0.1
    assert s.redo() and s.redo() and s.cloud is new
    # remove the active handle (its transform goes with it); Esc-like reset of a pose
    s.select_handle(1)
    assert s.remove_handle() and len(s.selection.handles) == 1 and s.selection.active == 0
    assert s.wait_fit() and s.basis.n_columns == 4


def test_curve_identity_and_translation(tmp_path, session):
    s = session
    base = s.cloud
    paint_support(s)
    p = base.positions
    picks = [int(np.argmin(np.linalg.norm(p - [x, y, 0], axis=1))) for x, y in
             ((-0.55, -0.1), (-0.2, 0.1), (0.2, -0.1), (0.55, 0.1))]
    s.curve_mode = True
    for i in picks:
        assert s.add_curve_point(p[i])
    with pytest.raises(SplatEditError):
        s.add_curve_point(p[picks[-1]])                  # the same point twice in a row
    assert s.wait_fit() and s.basis.n_columns == 4
    assert s.basis.group_kinds == ["curve"]
    # moving no point changes nothing, bitwise
    dc = s.current_dc()
    assert not dc.any()
    out = s.basis.apply(base, dc)
    assert np.array_equal(out.positions, base.positions) and np.array_equal(out.u, base.u)
    assert not s.commit() and s.cloud is base and len(s.edits) == 0
    # moving every picked point by the same translation moves the splats near the curve by it
    t = np.array([0.0, 0.0, 0.12])
    for j in range(len(picks)):
        assert typed_move(s, 2, "0.12", curve_point=j) == "pose"
    assert np.allclose(s.curve_moves, t)
    poly = s.curve_polyline(400)
    assert np.allclose(poly[:, 2], 0.12)
    assert s.commit()
    new = s.cloud
    d = new.positions - base.positions
    close = np.min(np.linalg.norm(base.positions[:, None, :] - (poly - t)[None], axis=2), axis=1) < 0.03
    assert close.sum() >= 8
    assert np.allclose(d[close], t, atol=0.01)
    assert np.array_equal(new.positions[~s.selection.support], base.positions[~s.selection.support])
    assert s.curve_points == [] and not s.pose_pending     # the curve is consumed
    # export: curves with points and move; replay reproduces the cloud bitwise
    again, doc = replay(tmp_path, s, base)
    c = doc["edits"][0]["curves"][0]
    assert np.array_equal(np.array(c["points"]), p[picks]) and np.allclose(c["move"], t)
    assert "handles" not in doc["edits"][0] and "handle" not in doc["edits"][0]
    assert np.array_equal(again.positions, new.positions) and np.array_equal(again.v, new.v)
    # undo brings the bent curve back, twice more the unmoved points
    assert s.undo() and len(s.curve_points) == 4 and np.allclose(s.curve_moves, t)
    assert s.undo() and np.allclose(s.curve_moves[:3], t) and not s.curve_moves[3].any()
    assert s.remove_curve_point() and len(s.curve_points) == 3


def test_handle_and_curve_together_replay(tmp_path, session):
    s = session
    base = s.cloud
    paint_support(s)
    s.brush_target = HANDLE
    s.end_stroke(s.paint(near(s, (0.0, 0.5))))
    p = base.positions
    for x in (-0.5, 0.0, 0.5):
        s.add_curve_point(p[int(np.argmin(np.linalg.norm(p - [x, -0.4, 0], axis=1)))])
    assert s.wait_fit() and s.basis.group_kinds == ["handle", "curve"] and s.basis.n_columns == 7
    typed_move(s, 2, "0.1")
    typed_move(s, 1, "0.05", curve_point=1)
    assert s.commit()
    again, doc = replay(tmp_path, s, base)
    assert "handle" in doc["edits"][0] and "curves" in doc["edits"][0]
    assert np.array_equal(again.positions, s.cloud.positions)


def test_column_budget(session):
    s = session
    paint_support(s)
    s.brush_target = HANDLE
    for k, c in enumerate(((-0.5, -0.5), (0.5, -0.5), (-0.5, 0.5), (0.5, 0.5))):
        if k:
            assert s.add_handle()
        s.end_stroke(s.paint(near(s, c, 0.12)))
    assert s.wait_fit() and s.basis.n_columns == 16
    with pytest.raises(SplatEditError, match="16"):
        s.add_handle()
    p = s.cloud.positions
    s.add_curve_point(p[0] * 0.1)          # one point: no curve columns yet
    with pytest.raises(SplatEditError, match="columns"):
        s.add_curve_point(p[5] * 0.1)
    # a lone 16-point curve fits
    s.clear()
    paint_support(s)
    s.clear_curve()
    xs = np.linspace(-0.6, 0.6, 16)
    for x in xs:
        s.add_curve_point([x, 0.3 * np.sin(3 * x), 0.0])
    with pytest.raises(SplatEditError, match="at most 16"):
        s.add_curve_point([0.7, 0.0, 0.0])
    assert s.wait_fit() and s.basis.n_columns == 16


def test_drawn_curve_is_the_curve_the_fit_uses(session):
    """Linear mode: the editor draws c'(t) = c(t) + W(t) dq: before and after
    dragging the tip up, the drawn polyline passes through the (moved) picked
    points, and the fitted field carries every kept curve sample onto it,
    upwards only."""
    s = session
    s.deformation = DeformationMode.LINEAR
    paint_support(s)
    p = s.cloud.positions
    picks = [int(np.argmin(np.linalg.norm(p - [x, y, 0], axis=1))) for x, y in
             ((-0.55, -0.1), (-0.3, 0.25), (0.1, 0.3), (0.5, -0.05))]
    s.curve_mode = True
    for i in picks:
        assert s.add_curve_point(p[i])
    assert s.wait_fit() and s.basis.stats["method"] == "lu"
    g = s.basis.constraints.groups[0]

    def on_polyline(points, poly, tol):
        return np.min(np.linalg.norm(points[:, None, :] - poly[None], axis=2), axis=1).max() < tol

    poly = s.curve_polyline(2000)
    assert on_polyline(p[picks], poly, 1e-12) and on_polyline(g.points, poly, 2e-3)
    assert typed_move(s, 2, "0.1", curve_point=3) == "pose"
    moved = g.points + s.basis.rbf(g.points) @ s.current_dc()
    poly = s.curve_polyline(2000)
    assert on_polyline(s.curve_point_positions(), poly, 1e-12) and on_polyline(moved, poly, 2e-3)
    np.testing.assert_allclose(moved, s.curve().evaluate(g.params, p[picks] + s.curve_moves), atol=1e-9)
    lift = (moved - g.points)[:, 2]
    assert lift.min() > -1e-9 and lift.max() > 0.099
    np.testing.assert_allclose((moved - g.points)[:, :2], 0.0, atol=1e-9)


def test_rotation_mode_draws_the_frame_curve_and_carries_the_samples_onto_it(session):
    """Rotation mode (the default): the drawn curve is the Catmull-Rom spline
    through the moved picked points, the committed deformation carries the
    picked points exactly and every kept sample close onto it."""
    from splatedit.deform.curve_frames import CurveFrameDisplacement, deform_points
    s = session
    assert s.deformation is DeformationMode.ROTATION
    paint_support(s)
    p = s.cloud.positions
    picks = [int(np.argmin(np.linalg.norm(p - [x, y, 0], axis=1))) for x, y in
             ((-0.55, -0.1), (-0.3, 0.25), (0.1, 0.3), (0.5, -0.05))]
    s.curve_mode = True
    for i in picks:
        assert s.add_curve_point(p[i])
    assert s.wait_fit()
    g = s.basis.constraints.groups[0]
    assert typed_move(s, 2, "0.1", curve_point=3) == "pose"
    dc = s.current_dc()
    assert isinstance(dc, CurveFrameDisplacement)
    poly = s.curve_polyline(2000)
    target = p[picks] + s.curve_moves
    np.testing.assert_allclose(deform_points(s.basis, dc, p[picks]), target, atol=1e-9 * s.cloud.diagonal)
    moved = deform_points(s.basis, dc, g.points)
    gap = np.min(np.linalg.norm(moved[:, None, :] - poly[None], axis=2), axis=1)
    assert gap.max() < 0.01 * s.cloud.diagonal
    # the viewport draws the pose as committed: a CPU-deformed copy (the GPU pass has no frames)
    shown, basis, shown_dc = s.display_state(False)
    assert basis is None and shown_dc is None
    np.testing.assert_array_equal(shown.positions, s.basis.apply(s.cloud, dc).positions)
    assert s.display_state(False)[0] is shown                  # kept while nothing moves
    assert s.commit()
    np.testing.assert_array_equal(s.cloud.positions, shown.positions)
    # the heat map redraws a committed edit from its base on the GPU; a curve-frame edit is shown as committed
    shown, basis, _ = s.display_state(True)
    assert shown is s.cloud and basis is s.basis
