"""Frame-carrying curve edits of the rotation mode (issue 19 item 4): the trunk
bend stays under 4x stretch, picked points land, fixed splats stay, the
Jacobian is the map's derivative, the linear mode is the paper's."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.bench.trunk import DRAG, LENGTH, measure, trunk_edit
from splatedit.deform.curve_frames import (CurveFrame, CurveFrameDisplacement, deform_points,
                                           double_reflection)
from splatedit.deform.curves import ControlCurve
from splatedit.deform.modes import DeformationMode


@pytest.fixture(scope="module")
def trunk():
    return trunk_edit()


def test_trunk_bend_stays_under_4x_stretch_and_the_tip_ring_follows(trunk):
    before = measure(*trunk, DeformationMode.LINEAR)
    after = measure(*trunk, DeformationMode.ROTATION)
    assert before["max_stretch"] > 4.0 and before["tip_ring_follows"] < 0.2     # the beak and the knob
    assert after["max_stretch"] < 4.0
    assert after["tip_ring_follows"] > 0.7


def test_moved_curve_points_land_on_their_targets(trunk):
    cloud, basis, q, moves = trunk
    dc = basis.displacement([moves], mode=DeformationMode.ROTATION)
    assert isinstance(dc, CurveFrameDisplacement)
    landed = deform_points(basis, dc, q)
    assert np.abs(landed - (q + moves)).max() <= 1e-9 * cloud.diagonal


def test_splats_outside_the_support_do_not_move(trunk):
    cloud, basis, q, moves = trunk
    dc = basis.displacement([moves], mode=DeformationMode.ROTATION)
    pos, u, v = basis.apply_arrays(cloud, dc)
    out = np.ones(cloud.n, bool)
    out[basis.indices] = False
    assert out.any()
    for a, b in ((pos, cloud.positions), (u, cloud.u), (v, cloud.v)):
        assert np.array_equal(a[out], b[out])


def test_linear_mode_keeps_the_papers_curve_edit(trunk):
    cloud, basis, q, moves = trunk
    dc = basis.displacement([moves], mode=DeformationMode.LINEAR)
    assert isinstance(dc, np.ndarray)
    pos = basis.apply_arrays(cloud, dc)[0]
    assert np.array_equal(pos[basis.indices], cloud.positions[basis.indices] + basis.B @ dc)


def test_unmoved_curve_takes_the_linear_path(trunk):
    cloud, basis, q, moves = trunk
    dc = basis.displacement([np.zeros_like(moves)], mode=DeformationMode.ROTATION)
    assert isinstance(dc, np.ndarray) and not dc.any()


def test_jacobians_match_finite_differences_of_the_map(trunk):
    cloud, basis, q, moves = trunk
    dc = basis.displacement([moves], mode=DeformationMode.ROTATION)
    jac = basis.jacobians(dc)
    idx = basis.indices
    rng = np.random.default_rng(3)
    rows = rng.choice(len(idx), 40, replace=False)
    x = cloud.positions[idx[rows]]
    h = 1e-5 * cloud.diagonal
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        fd = (deform_points(basis, dc, x + e) - deform_points(basis, dc, x - e)) / (2 * h)
        # deform_points takes the basis rows from the RBF: equal to the splats' rows
        assert np.abs(fd - jac[rows, :, k]).max() < 1e-4


def test_double_reflection_frame_is_orthonormal_and_follows_a_helix():
    t = np.linspace(0, 4 * np.pi, 400)
    pts = np.column_stack([np.cos(t), np.sin(t), 0.3 * t])
    tg = np.column_stack([-np.sin(t), np.cos(t), 0.3 * np.ones_like(t)])
    tg /= np.linalg.norm(tg, axis=1, keepdims=True)
    r = double_reflection(pts, tg, np.array([1.0, 0.0, 0.0]))
    assert np.abs(np.linalg.norm(r, axis=1) - 1).max() < 1e-12
    assert np.abs((r * tg).sum(1)).max() < 1e-12
    # a rotation-minimising frame turns about the tangent only as the helix' torsion
    # requires: consecutive normals differ by O(step), no flips
    assert (r[1:] * r[:-1]).sum(1).min() > 0.99


def test_translated_curve_translates_the_part_rigidly():
    q = np.array([[0.0, 0.0, 0.0], [0.0, 0.2, 0.5], [0.0, 0.0, 1.0]])
    f = CurveFrame.build(0, ControlCurve.through(q), np.tile([0.3, 0.0, 0.0], (3, 1)))
    assert np.abs(f.omega).max() < 1e-9          # no turn: frames equal
    assert np.abs(f.rotations).max() < 1e-9
