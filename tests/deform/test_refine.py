"""Fewer needles in big grabs (issue 20.3): the rotation mode refines a
committed far translation (splatedit.deform.refine) and keeps exact control.

Figures (python -m splatedit.bench.needles, docs/PERFORMANCE.md): splats
beyond 4x among the moved ones, linear -> rotation: the bunny's ear moved
14.5 % of the diagonal 55 (0.52 %) -> 2 (0.02 %); its head bent 8 % 406
(2.53 %) -> 5 (0.03 %); the hippo's leg 31 (5.3 %) -> 0.
"""

from pathlib import Path

import numpy as np
import pytest

from splatedit.bench.needles import HIPPO, measure, prepare
from splatedit.deform.distortion import distortion_from_axes
from splatedit.deform.modes import DeformationMode
from splatedit.deform.refine import arap_refine, needs_refine, refine_committed
from splatedit.tolerances import DISTORTION_BROKEN_STRETCH

#: the issue's goal: under 0.1 % of the moved splats beyond 4x
GOAL_SHARE = 1e-3
#: exact control: the handle at p + t, the fixed band where it was (share of the diagonal)
EXACT_REL = 1e-9


@pytest.fixture(scope="module")
def bunny_ear():
    return prepare("arm-bunny-ear")


def _check_exact(cloud, basis, new, m, diag):
    con = basis.constraints
    hi = np.concatenate(con.handle_index)
    assert np.abs(new.positions[hi] - cloud.positions[hi] - m[:3, 3]).max() <= EXACT_REL * diag
    assert np.abs(new.positions[con.fixed_index] - cloud.positions[con.fixed_index]).max() <= EXACT_REL * diag
    outside = np.setdiff1d(np.arange(cloud.n), basis.indices)
    for a, b in ((new.positions, cloud.positions), (new.u, cloud.u), (new.v, cloud.v)):
        assert np.array_equal(a[outside], b[outside])


def test_arm_lift_rotation_mode_has_under_a_thousandth_needles_and_exact_control(bunny_ear):
    cloud, basis, m, h, diag = bunny_ear
    lin = measure("arm-bunny-ear", cloud, basis, m, h, diag, DeformationMode.LINEAR)
    rot = measure("arm-bunny-ear", cloud, basis, m, h, diag, DeformationMode.ROTATION)
    assert lin.share > 4e-3                    # measured 0.52 %: the needles the refinement removes
    assert rot.share < GOAL_SHARE              # measured 0.02 %
    assert rot.max_stretch < 0.75 * lin.max_stretch    # measured 7.5x against 14.6x
    assert rot.tears <= lin.tears
    assert rot.handle_error <= EXACT_REL and rot.fixed_error <= EXACT_REL


def test_refined_commit_keeps_handle_fixed_band_and_outside_splats(bunny_ear):
    cloud, basis, m, h, diag = bunny_ear
    seed = basis.commit(cloud, basis.displacement([m], mode=DeformationMode.ROTATION))
    new, stats, note = refine_committed(basis, cloud, seed, DeformationMode.ROTATION, [m])
    assert "needles refined" in note
    assert stats.n_above_broken < GOAL_SHARE * stats.n
    _check_exact(cloud, basis, new, m, diag)


def test_linear_mode_and_edits_without_needles_keep_the_rbf_result_bitwise(bunny_ear):
    cloud, basis, m, h, diag = bunny_ear
    seed = basis.commit(cloud, basis.displacement([m]))
    new, _, note = refine_committed(basis, cloud, seed, DeformationMode.LINEAR, [m])
    assert new is seed and note == ""
    small = m.copy()
    small[:3, 3] *= 0.1                         # a gentle grab: no splat beyond 4x
    seed = basis.commit(cloud, basis.displacement([small], mode=DeformationMode.ROTATION))
    new, stats, note = refine_committed(basis, cloud, seed, DeformationMode.ROTATION, [small])
    assert stats.n_above_broken == 0 and new is seed and note == ""


def test_rotations_scales_and_curves_are_not_refined(bunny_ear):
    """The rule is for translations: a far grab that also turns or scales
    the handle keeps the RBF (rotation-aware) result."""
    from splatedit.deform.transform import compose, rotate, scale
    cloud, basis, m, h, diag = bunny_ear
    g = basis.constraints.groups[0].controls[0]
    for extra in (rotate((0, 0, 1), 90.0, g), scale(2.0, g)):
        mm = compose(extra, m)
        seed = basis.commit(cloud, basis.displacement([mm], mode=DeformationMode.ROTATION))
        idx = basis.indices
        stats = distortion_from_axes(cloud.u[idx], cloud.v[idx], seed.u[idx], seed.v[idx])
        assert needs_refine(stats)              # measured 458 / 188 splats beyond 4x
        new, _, note = refine_committed(basis, cloud, seed, DeformationMode.ROTATION, [mm])
        assert new is seed and note == ""


def test_a_region_beyond_the_cap_keeps_the_rbf_result_and_says_so(bunny_ear, monkeypatch):
    import splatedit.tolerances as tol
    cloud, basis, m, h, diag = bunny_ear
    seed = basis.commit(cloud, basis.displacement([m], mode=DeformationMode.ROTATION))
    monkeypatch.setattr(tol, "ARAP_MAX_REGION_SPLATS", 10)
    new, stats, note = refine_committed(basis, cloud, seed, DeformationMode.ROTATION, [m])
    assert new is seed and note.startswith("needles not refined") and stats.n_above_broken == 55


def test_conjugate_gradients_give_the_direct_solve_figures(bunny_ear, monkeypatch):
    """Regions above ARAP_DIRECT_MAX_SPLATS take CG: forced here on the ear."""
    import splatedit.tolerances as tol
    cloud, basis, m, h, diag = bunny_ear
    direct = measure("arm-bunny-ear", cloud, basis, m, h, diag, DeformationMode.ROTATION)
    monkeypatch.setattr(tol, "ARAP_DIRECT_MAX_SPLATS", 0)
    iterative = measure("arm-bunny-ear", cloud, basis, m, h, diag, DeformationMode.ROTATION)
    assert iterative.broken <= direct.broken + 1 and iterative.share < GOAL_SHARE
    assert iterative.p99_stretch == pytest.approx(direct.p99_stretch, rel=0.02)
    assert iterative.handle_error <= EXACT_REL and iterative.fixed_error <= EXACT_REL


def test_arap_refine_with_no_free_splat_or_no_iteration_returns_copies(bunny_ear):
    cloud, basis, m, h, diag = bunny_ear
    seed = basis.commit(cloud, basis.displacement([m]))
    idx = basis.indices
    for fixed, iters in ((np.ones(len(idx), bool), 3), (np.zeros(len(idx), bool), 0)):
        r = arap_refine(cloud, idx, fixed, seed.positions, seed.u, seed.v, iterations=iters)
        assert r.iterations == 0
        assert np.array_equal(r.positions, seed.positions) and np.array_equal(r.u, seed.u)


def test_head_bend_rotation_mode_has_under_a_thousandth_needles():
    cloud, basis, m, h, diag = prepare("head-bunny")
    lin = measure("head-bunny", cloud, basis, m, h, diag, DeformationMode.LINEAR)
    rot = measure("head-bunny", cloud, basis, m, h, diag, DeformationMode.ROTATION)
    assert lin.share > 1e-2                    # measured 2.53 %, max 50x
    assert rot.share < GOAL_SHARE              # measured 0.03 %, max 7.3x
    assert rot.handle_error <= EXACT_REL and rot.fixed_error <= EXACT_REL


@pytest.mark.skipif(not Path(HIPPO).exists(), reason="sample scan /work/shared/data/hippo1.ply absent")
def test_script_edit_of_hippo_leg_is_refined_in_rotation_mode_and_plain_in_linear_mode():
    from splatedit.script.parse import parse_script
    from splatedit.script.run import run_script
    cloud, basis, m, h, diag = prepare("arm-hippo-leg")
    sup = basis.indices.tolist()
    hd = np.concatenate(basis.constraints.handle_index).tolist()
    reports, outs = {}, {}
    for mode in ("linear", "rotation"):
        script = parse_script({"version": 1, "edits": [{
            "support": {"indices": sup, "fill_holes": False}, "handle": {"indices": hd},
            "transform": {"translate": m[:3, 3].tolist()}, "deformation": mode}]})
        outs[mode], (reports[mode],) = run_script(cloud, script)
    lin, rot = reports["linear"].distortion, reports["rotation"].distortion
    assert lin.n_above_broken > 10 * GOAL_SHARE * lin.n        # measured 31 of 584
    assert rot.n_above_broken <= GOAL_SHARE * rot.n            # measured 0
    assert any("needles refined" in n for n in reports["rotation"].notes)
    assert not any("needles refined" in n for n in reports["linear"].notes)
    assert rot.max_stretch < DISTORTION_BROKEN_STRETCH
    _check_exact(cloud, basis, outs["rotation"], m, diag)
