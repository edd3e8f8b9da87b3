"""The GUI's numeric transform fields without a window: the matrix they build
(scale and rotate about the handle's centroid, then translate), their
refusals, and applying them through the same path as a finished G/R/S move
(one handle: an edit committed at once; two handles: a pending pose)."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.app.ui.transform_fields import TargetKind, TransformInput, apply_position, apply_transform, field_target
from splatedit.select.selection import HANDLE, SUPPORT
from tests.app.ui.test_editor_routing import ed, key  # noqa: F401 (fixture)

glfw = pytest.importorskip("glfw")
#: model units: a committed curve move brings the splat its point was picked on
#: to the typed position (the curve interpolates its moved points: measured
#: 3e-14 on the 30 x 30 plane, grid step 0.069)
CURVE_POINT_LANDING = 1e-9


def _rig(s, handles=((0.0, 0.0),)):
    r = np.linalg.norm(s.cloud.positions[:, :2], axis=1)
    s.brush_target = SUPPORT
    s.end_stroke(s.paint(np.flatnonzero(r < 0.9)))
    s.brush_target = HANDLE
    for k, (x, y) in enumerate(handles):
        if k:
            assert s.add_handle()
        d = np.linalg.norm(s.cloud.positions[:, :2] - [x, y], axis=1)
        s.end_stroke(s.paint(np.flatnonzero(d < 0.15)))
    assert s.wait_fit() and s.active_fitted()


def test_fields_matrix_scales_and_turns_about_the_pivot_then_moves():
    f = TransformInput([0.1, -0.2, 0.3], [0.0, 0.0, 2.0], 90.0, 2.0)
    pivot = np.array([1.0, 1.0, 0.0])
    m = f.matrix(pivot)
    assert np.allclose(m[:3, :3] @ pivot + m[:3, 3], pivot + [0.1, -0.2, 0.3])    # the pivot only moves
    # a point one unit right of the pivot: doubled, turned 90 deg about +z (to +y), moved
    q = pivot + [1.0, 0.0, 0.0]
    assert np.allclose(m[:3, :3] @ q + m[:3, 3], pivot + [0.0, 2.0, 0.0] + [0.1, -0.2, 0.3])
    assert TransformInput().is_identity() and np.allclose(TransformInput().matrix(pivot), np.eye(4))


@pytest.mark.parametrize("fields,why", [
    (TransformInput(factor=0.0), "scale factor must be > 0"),
    (TransformInput(factor=-1.0), "scale factor must be > 0"),
    (TransformInput(axis=[0.0, 0.0, 0.0], degrees=10.0), "axis is zero"),
    (TransformInput(translate=[float("nan"), 0.0, 0.0]), "not a finite number"),
])
def test_fields_that_cannot_be_applied_say_why(fields, why):
    assert why in fields.problem()


def test_single_handle_typed_move_commits_one_edit_like_g(ed):  # noqa: F811
    s = ed.session
    _rig(s)
    hc = s.handle_centroid()
    before = s.cloud.positions.copy()
    inside = np.linalg.norm(before[:, :2], axis=1) < 0.15
    assert apply_transform(ed, TransformInput(translate=[0.0, 0.0, 0.25]))
    assert len(s.edits) == 1 and s.manip is None and not s.pose_pending
    moved = s.cloud.positions - before
    # the handle's splats follow the typed translation exactly, the far ones stay
    assert np.allclose(moved[inside], [0.0, 0.0, 0.25], atol=1e-6)
    outside = np.linalg.norm(before[:, :2], axis=1) > 0.95
    assert np.abs(moved[outside]).max() < 1e-9
    assert np.allclose(s.handle_centroid(), hc + [0.0, 0.0, 0.25], atol=1e-6)
    # one undo takes it back, as for a G move
    key(ed, glfw.KEY_Z, glfw.MOD_CONTROL)
    assert len(s.edits) == 0 and np.allclose(s.cloud.positions, before)


def test_two_handles_typed_rotation_is_a_pending_pose(ed):  # noqa: F811
    s = ed.session
    _rig(s, handles=((-0.4, 0.0), (0.4, 0.0)))
    assert s.selection.active == 1
    assert apply_transform(ed, TransformInput(axis=[1.0, 0.0, 0.0], degrees=30.0))
    assert len(s.edits) == 0 and s.pose_pending and s.manip is None
    m = s.pose[1]
    assert np.allclose(m[:3, :3], [[1, 0, 0], [0, np.cos(np.pi / 6), -np.sin(np.pi / 6)],
                                   [0, np.sin(np.pi / 6), np.cos(np.pi / 6)]], atol=1e-12)
    assert np.allclose(s.pose[0], np.eye(4))          # the other handle is untouched


def test_refused_while_a_move_runs_or_without_a_fitted_handle(ed):  # noqa: F811
    s = ed.session
    assert not apply_transform(ed, TransformInput(translate=[0.1, 0.0, 0.0]))
    assert "paint a support" in ed.messages[-1]
    _rig(s)
    key(ed, glfw.KEY_G)
    assert s.manip is not None
    assert not apply_transform(ed, TransformInput(translate=[0.1, 0.0, 0.0]))
    assert "a move is running" in ed.messages[-1] and s.manip.mode == "grab"
    key(ed, glfw.KEY_ESCAPE)
    assert not apply_transform(ed, TransformInput())
    assert "nothing to apply" in ed.messages[-1] and len(s.edits) == 0


def _curve(s, xs=(-0.5, 0.0, 0.5)):
    """Support r < 0.9 and a curve through plane points at x = xs, y = 0 (fitted)."""
    r = np.linalg.norm(s.cloud.positions[:, :2], axis=1)
    s.brush_target = SUPPORT
    s.end_stroke(s.paint(np.flatnonzero(r < 0.9)))
    for x in xs:
        i = int(np.argmin(np.linalg.norm(s.cloud.positions[:, :2] - [x, 0.0], axis=1)))
        assert s.add_curve_point(s.cloud.positions[i])
    assert s.wait_fit() and s.basis_groups[1] is not None


def test_fields_move_the_active_curve_point_to_a_typed_position_with_undo(ed):  # noqa: F811
    s = ed.session
    _curve(s)
    s.curve_mode = True
    t = field_target(s)
    assert t.kind is TargetKind.CURVE_POINT and t.index == 2 and t.problem is None and not t.rotates
    assert np.allclose(t.position, s.curve_points[2])
    # a relative move of the first point, one undo step
    s.select_curve_point(0)
    assert field_target(s).index == 0
    assert apply_transform(ed, TransformInput(translate=[0.0, 0.0, -0.2]))
    assert s.manip is None and s.pose_pending and len(s.edits) == 0
    assert np.allclose(s.curve_point_positions()[0], s.curve_points[0] + [0.0, 0.0, -0.2])
    key(ed, glfw.KEY_Z, glfw.MOD_CONTROL)
    assert not s.pose_pending
    # rotating or scaling a point is refused with the reason
    assert not apply_transform(ed, TransformInput(axis=[0.0, 0.0, 1.0], degrees=20.0))
    assert "only moves" in ed.messages[-1]
    # the position field: the last point goes where it is typed, the others stay
    s.select_curve_point(-1)
    goal = s.curve_points[2] + [0.0, 0.1, 0.3]
    assert apply_position(ed, goal)
    assert np.allclose(s.curve_point_positions()[2], goal, atol=1e-12)
    assert np.allclose(s.curve_point_positions()[:2], s.curve_points[:2])
    assert np.allclose(field_target(s).position, goal)                         # the fields show it
    # Enter commits: the splat the point was picked on lands on the typed position
    i = int(np.argmin(np.linalg.norm(s.cloud.positions - s.curve_points[2], axis=1)))
    assert s.commit() and len(s.edits) == 1
    assert np.linalg.norm(s.cloud.positions[i] - goal) < CURVE_POINT_LANDING
    key(ed, glfw.KEY_Z, glfw.MOD_CONTROL)
    assert len(s.edits) == 0 and np.allclose(s.curve_point_positions()[2], goal)


def test_the_target_is_the_curve_point_with_the_curve_tool_on_else_the_handle(ed):  # noqa: F811
    s = ed.session
    assert field_target(s).kind is TargetKind.NONE and "paint a support" in field_target(s).problem
    _rig(s)
    _curve(s, xs=(-0.6, 0.6))
    assert field_target(s).kind is TargetKind.HANDLE
    s.curve_mode = True
    t = field_target(s)
    assert t.kind is TargetKind.CURVE_POINT and t.index == 1
    s.remove_curve_point()
    s.wait_fit()
    t = field_target(s)
    assert t.kind is TargetKind.CURVE_POINT and "second curve point" in t.problem
    assert not apply_position(ed, t.position + 0.1) and "second curve point" in ed.messages[-1]
    s.curve_mode = False
    s.wait_fit()
    t = field_target(s)
    assert t.kind is TargetKind.HANDLE and t.problem is None and np.allclose(t.position, s.handle_centroid())
    key(ed, glfw.KEY_G)
    assert "a move is running" in field_target(s).problem


def test_position_field_moves_the_handle_centre_there_in_one_edit(ed):  # noqa: F811
    s = ed.session
    _rig(s)
    t = field_target(s)
    assert t.kind is TargetKind.HANDLE and t.rotates and np.allclose(t.position, s.handle_centroid())
    assert not apply_position(ed, t.position) and "already" in ed.messages[-1]
    goal = t.position + [0.05, -0.02, 0.2]
    assert apply_position(ed, goal)
    assert len(s.edits) == 1 and np.allclose(s.handle_centroid(), goal, atol=1e-9)
    assert np.allclose(field_target(s).position, goal, atol=1e-9)
    key(ed, glfw.KEY_Z, glfw.MOD_CONTROL)
    assert len(s.edits) == 0 and np.allclose(field_target(s).position, t.position)
