"""Closure respects what the user gave (issue 20, item 1).

Closure adds only what a selection encloses or hides: it never moves the
rim of a region a script names (splats outside a sphere support stay put to
1e-9 of the diagonal), never gives back splats the user erased, keeps the
handle margin inside the support's region, and closes a handle painted on
one side of a thick part through it (the back of a head turns with its
face).  Figures: the embedded bunny, the team's scans where present, and
synthetic limbs and a head (:mod:`tests.select.figures`).
"""

import numpy as np
import pytest

import splatedit.select.closure as closure_mod
from splatedit.data import default_model_path
from splatedit.deform import DeformationBasis, transform
from splatedit.deform.distortion import distortion_from_axes
from splatedit.io import read
from splatedit.script import parse_script, run_script
from splatedit.select.closure import close_selection
from splatedit.select.graph import NeighbourGraph
from splatedit.select.selection import HANDLE, SUPPORT, Selection
from splatedit.select.view import one_view_disc, view_axes

from tests.select.figures import hand_next_to_thigh, head_on_neck

#: splats outside a script's region may move by at most this fraction of the diagonal
OUTSIDE_MOVE_REL = 1e-9


@pytest.fixture(scope="module")
def bunny():
    return read(default_model_path())


@pytest.fixture(scope="module")
def bunny_graph(bunny):
    return NeighbourGraph.build(bunny.positions)


def _outside_move(cloud, out, inside: np.ndarray) -> float:
    """Largest move of the splats outside ``inside``, relative to the diagonal."""
    mv = np.linalg.norm(out.positions[~inside] - cloud.positions[~inside], axis=1)
    return float(mv.max()) / cloud.diagonal if len(mv) else 0.0


def _ear_sphere_script(cloud, curve: bool = False) -> tuple[dict, np.ndarray, float]:
    """A sphere support around the highest point (the bunny's ear tip) whose
    handle sphere reaches over the support's rim, or a control curve along
    the tip; (script document, centre, radius)."""
    p, diag = cloud.positions, cloud.diagonal
    tip = p[np.argmax(p[:, 1])]
    r = 0.15 * diag
    c = tip - [0.0, 0.5 * r, 0.0]
    edit = {"support": {"sphere": {"center": c.tolist(), "radius": r}}}
    if curve:
        a, b = tip - [0.0, 0.3 * r, 0.0], tip - [0.0, 0.9 * r, 0.0]
        edit["curves"] = [{"points": [a.tolist(), ((a + b) / 2).tolist(), b.tolist()],
                           "move": [[0.05 * diag, 0, 0], [0.03 * diag, 0, 0], [0.0, 0, 0]]}]
    else:
        edit["handle"] = {"sphere": {"center": tip.tolist(), "radius": 0.6 * r}}
        edit["transform"] = {"translate": [0.05 * diag, 0.02 * diag, 0.0]}
    return {"version": 1, "edits": [edit]}, c, r


@pytest.mark.parametrize("curve", [False, True], ids=["handle", "control-curve"])
def test_a_script_sphere_support_moves_no_splat_outside_the_sphere(bunny, curve):
    """The measured defect: closure's back sides and handle margin moved
    splats up to 1.3 radii from the centre (416 on the bunny, 1.0% of the
    diagonal).  Now the sphere is the support's rim."""
    doc, c, r = _ear_sphere_script(bunny, curve)
    out, reps = run_script(bunny, parse_script(doc))
    inside = np.linalg.norm(bunny.positions - c, axis=1) <= r
    assert np.linalg.norm(out.positions - bunny.positions, axis=1).max() > 0.01 * bunny.diagonal
    assert _outside_move(bunny, out, inside) <= OUTSIDE_MOVE_REL
    assert reps[0].support == int(inside.sum())


@pytest.mark.parametrize("name", ["kitten.xyz", "hippo1.ply"])
def test_a_script_sphere_support_on_a_scan_moves_no_splat_outside_it(shared_data, name):
    cloud = read(shared_data / name)
    for curve in (False, True):
        doc, c, r = _ear_sphere_script(cloud, curve)
        out, _ = run_script(cloud, parse_script(doc))
        inside = np.linalg.norm(cloud.positions - c, axis=1) <= r
        assert _outside_move(cloud, out, inside) <= OUTSIDE_MOVE_REL, curve


def test_a_script_box_support_keeps_its_rim(bunny):
    p, diag = bunny.positions, bunny.diagonal
    tip = p[np.argmax(p[:, 1])]
    lo, hi = tip - 0.12 * diag, tip + [0.12 * diag, 0.0, 0.12 * diag]
    doc = {"version": 1, "edits": [{"support": {"box": {"min": lo.tolist(), "max": hi.tolist()}},
                                    "handle": {"sphere": {"center": tip.tolist(), "radius": 0.08 * diag}},
                                    "transform": {"rotate": {"axis": [0, 0, 1], "degrees": 30}}}]}
    out, _ = run_script(bunny, parse_script(doc))
    inside = np.all((p >= lo) & (p <= hi), axis=1)
    assert _outside_move(bunny, out, inside) <= OUTSIDE_MOVE_REL


def test_the_handle_margin_stays_inside_the_support_region(bunny, bunny_graph):
    """A handle strip reaching the support's edge: without a region the
    margin grows the support past its rim (the Python API's bare masks);
    with the region it adds nothing outside it."""
    cloud, graph = bunny, bunny_graph
    p = cloud.positions
    tip = p[np.argmax(p[:, 1])]
    d = np.linalg.norm(p - tip, axis=1)
    sup = d < 0.2
    hnd = sup & (np.abs(p[:, 0] - tip[0]) < 0.04) & (d > 0.12)
    free = close_selection(cloud, sup, [hnd], graph=graph)
    assert (free.support & ~sup).any() and free.counts.handle_margin > 0
    kept = close_selection(cloud, sup, [hnd], graph=graph, reach=sup, handle_reach=[hnd])
    assert not (kept.support & ~sup).any()
    assert not (kept.handles[0] & ~hnd).any()


# ---------------------------------------------------------------- editor
@pytest.fixture(scope="module")
def limbs():
    cloud, arm, thigh = hand_next_to_thigh()
    return cloud, arm, thigh, NeighbourGraph.build(cloud.positions)


def _stretch(cloud, out, basis) -> np.ndarray:
    """(n,) per-splat stretch (1 outside the support)."""
    i = basis.indices
    st = np.ones(cloud.n)
    st[i] = distortion_from_axes(cloud.u[i], cloud.v[i], out.u[i], out.v[i]).stretch
    return st


def test_an_erased_thigh_stays_erased_and_does_not_move_when_the_arm_lifts(limbs):
    """A hand hanging next to a thigh: a support stroke down the arm whose
    brush also takes part of the thigh next to the hand, the thigh erased,
    the hand painted as the handle.  Closure keeps the thigh out (without
    the erase memory the same masks close over it again: back sides, gaps
    and the hand's margin), and lifting the arm leaves the thigh untouched."""
    from splatedit.app.document import selection as tools
    cloud, arm, thigh, graph = limbs
    p = cloud.positions
    hand = p[arm][np.argmin(p[arm][:, 1])]
    sel = Selection(cloud.n)
    ball = np.linalg.norm(p - (hand + [0.6, 0.5, 0.0]), axis=1) < 1.3
    sel.paint(np.flatnonzero((arm & (p[:, 1] < -1)) | ball), SUPPORT)
    tools.apply_closure(sel, cloud, graph)
    assert (sel.support & thigh).sum() > 300                      # the brush took the thigh
    before = sel.copy()
    sel.paint(np.flatnonzero(thigh & sel.support), SUPPORT, erase=True)
    tools.apply_closure(sel, cloud, graph, within=before)
    sel.paint(np.flatnonzero(arm & (p[:, 1] < -4.3)), HANDLE)
    tools.apply_closure(sel, cloud, graph)
    assert not (sel.support & thigh).any()                        # the erase wins
    forgetful = close_selection(cloud, sel.support, sel.handles, graph=graph)
    assert (forgetful.support & thigh).sum() > 100                # what the memory prevents

    basis = DeformationBasis.fit(cloud, sel.support, sel.handles)
    out = basis.apply(cloud, basis.displacement([transform.translate([-1.0, 0.5, 0.0])]))
    assert np.array_equal(out.positions[thigh], p[thigh])        # the thigh is not touched
    assert _stretch(cloud, out, basis).max() < 4.0


def test_erase_memory_survives_undo_and_redo(limbs):
    from splatedit.app.document.session import Session
    cloud, arm, thigh, _ = limbs
    s = Session(cloud, fit_sync=True)
    s.paint(np.flatnonzero(arm | thigh))
    s.end_stroke(True)
    s.paint(np.flatnonzero(thigh), erase=True)
    s.end_stroke(True)
    assert s.selection.erased[thigh].all() and not s.selection.erased[arm].any()
    assert s.undo() and not s.selection.erased.any()
    assert s.redo() and s.selection.erased[thigh].all()
    s.paint(np.flatnonzero(thigh))                                # painting again clears the mark
    assert not s.selection.erased.any()
    s.close()


def test_a_shrink_counts_as_erasing_and_a_grow_as_painting(limbs):
    from splatedit.app.document import selection as tools
    cloud, arm, _, graph = limbs
    sel = Selection(cloud.n)
    sel.paint(np.flatnonzero(arm & (cloud.positions[:, 1] < -2)), SUPPORT)
    old = sel.support.copy()
    tools.set_target(sel, SUPPORT, tools.shrunk(sel, graph, SUPPORT))
    assert sel.erased[old & ~sel.support].all() and (old & ~sel.support).any()
    tools.set_target(sel, SUPPORT, tools.grown(sel, graph, SUPPORT, 2))
    assert not sel.erased[sel.support].any() and sel.reach[sel.support].all()


# ------------------------------------------------------------------ heads
@pytest.fixture(scope="module")
def head():
    cloud, is_head = head_on_neck()
    return cloud, is_head, NeighbourGraph.build(cloud.positions)


def _face_handle(cloud, graph):
    """The support (head and neck), the handle painted over the face from
    the front (visible splats only) and that stroke's reach (every splat
    whose centre projects into the brush circle, at any depth)."""
    p, c, view = cloud.positions, np.array([0.0, 1.5, 0.0]), (0.0, 0.0, -1.0)
    sup = p[:, 1] > -0.5
    hnd = one_view_disc(p, cloud.normals, view, c, 0.95, 2 * graph.spacing) & sup
    right, up, _ = view_axes(view)
    reach = np.hypot((p - c) @ right, (p - c) @ up) <= 0.95
    return sup, hnd, reach, c


def _turn_head(cloud, support, handles, c, degrees=60.0):
    basis = DeformationBasis.fit(cloud, support, handles)
    t = transform.rotate(axis=(0, 1, 0), degrees=degrees, center=c)
    out = basis.apply(cloud, basis.displacement([t]))
    rigid = (np.c_[cloud.positions, np.ones(cloud.n)] @ t.T)[:, :3]
    return out, np.linalg.norm(out.positions - rigid, axis=1), _stretch(cloud, out, basis)


def test_a_face_painted_from_the_front_takes_the_back_of_the_head(head):
    """The handle closes through the head: front and back turn together (the
    back within 0.1% of the diagonal of the rigid turn, no splat of the
    head stretched beyond 1.1x)."""
    cloud, is_head, graph = head
    sup, hnd, reach, c = _face_handle(cloud, graph)
    back = is_head & (cloud.positions[:, 2] < -0.3)
    assert not (hnd & back).any()
    res = close_selection(cloud, sup, [hnd], graph=graph, reach=sup, handle_reach=[reach])
    assert (res.handles[0] & back).sum() > 0.9 * back.sum()
    assert not (res.support & ~sup).any()
    _, off, stretch = _turn_head(cloud, res.support, res.handles, c)
    assert np.percentile(off[back], 95) < 1e-3 * cloud.diagonal
    assert stretch[is_head].max() < 1.1


def test_a_face_handle_closed_with_the_support_thickness_bound_smears_the_back(head, monkeypatch):
    """The baseline: with the support's thickness bound (1 RMS radius) the
    back of the head stays out of the handle and lags behind the face."""
    cloud, is_head, graph = head
    sup, hnd, reach, c = _face_handle(cloud, graph)
    back = is_head & (cloud.positions[:, 2] < -0.3)
    monkeypatch.setattr(closure_mod, "CLOSURE_HANDLE_THIN_MAX_REL", closure_mod.CLOSURE_THIN_MAX_REL)
    res = close_selection(cloud, sup, [hnd], graph=graph, reach=sup, handle_reach=[reach])
    assert not (res.handles[0] & back).any()
    _, off, _ = _turn_head(cloud, res.support, res.handles, c)
    assert np.percentile(off[back], 95) > 0.05 * cloud.diagonal


def test_the_bunny_head_painted_from_the_front_turns_with_its_back(bunny, bunny_graph, monkeypatch):
    """A real head: the bunny's face painted from the front (visible splats
    in a disc), the support a ball about the head, the head turned 30
    degrees.  The closed handle takes the back of the head behind the face;
    without that (the support's thickness bound) the back lags behind: max
    stretch 30x and 171 splats beyond 4x, against 9.7x and 26 (1,223 LU
    constraints)."""
    cloud, graph = bunny, bunny_graph
    p, c, view = cloud.positions, np.array([-0.36, 0.1, 0.15]), (1.0, 0.0, 0.0)
    sup = np.linalg.norm(p - c, axis=1) < 0.35
    hnd = one_view_disc(p, cloud.normals, view, c, 0.15, 2 * graph.spacing) & sup
    right, up, _ = view_axes(view)
    reach = np.hypot((p - c) @ right, (p - c) @ up) <= 0.15
    behind = reach & sup & ~hnd & (p[:, 0] > p[hnd, 0].mean())

    def turned(bound):
        monkeypatch.setattr(closure_mod, "CLOSURE_HANDLE_THIN_MAX_REL", bound)
        res = close_selection(cloud, sup, [hnd], graph=graph, reach=sup, handle_reach=[reach])
        basis = DeformationBasis.fit(cloud, res.support, res.handles)
        t = transform.rotate(axis=(0, 1, 0), degrees=30, center=p[res.handles[0]].mean(0))
        out = basis.apply(cloud, basis.displacement([t]))
        return res, _stretch(cloud, out, basis)

    res, stretch = turned(closure_mod.CLOSURE_HANDLE_THIN_MAX_REL)
    assert (res.handles[0] & behind).sum() > 0.5 * behind.sum()
    base, base_stretch = turned(closure_mod.CLOSURE_THIN_MAX_REL)
    assert (base.handles[0] & behind).sum() < 0.01 * behind.sum()
    assert stretch.max() < 0.5 * base_stretch.max()
    assert (stretch > 4).sum() < 0.25 * (base_stretch > 4).sum()
    assert (stretch > 4).sum() < 5e-3 * sup.sum()
