"""The 3D brush, grow / shrink / connected / invert and closure on the
bundled bunny, with a CPU pick map (nearest splat centre per pixel) of the
editor's front view."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.app.document import selection as tools
from splatedit.app.tools.pick_brush import BrushPicker, picker_for_view
from splatedit.select.closure import close_selection
from splatedit.select.selection import HANDLE, SUPPORT, Selection
from splatedit.app.view.camera_control import OrbitCamera

W, H = 640, 400


@pytest.fixture(scope="module")
def bunny():
    from splatedit.data import default_model_path
    from splatedit.io import read
    from splatedit.select.graph import NeighbourGraph
    cloud = read(default_model_path())
    return cloud, NeighbourGraph.build(cloud.positions)


@pytest.fixture(scope="module")
def view(bunny):
    """Front view camera, pick map and front depth: a CPU z-buffer of the
    splats drawn as discs of their projected radius (at most 4 px)."""
    cloud, _ = bunny
    cam = OrbitCamera()
    lo, hi = cloud.bounds()
    cam.frame((lo + hi) / 2, float(np.linalg.norm(hi - lo)) / 2, W / H)
    px, depth = cam.project(cloud.positions, W, H)
    rpx = np.minimum(cloud.radii / np.array([cam.world_per_pixel(d, H) for d in depth]), 4.0)
    cols = []
    for dy in range(-4, 5):
        for dx in range(-4, 5):
            k = np.flatnonzero((dx * dx + dy * dy <= rpx ** 2) & (depth > 0))
            cols.append((k, (px[k, 0] + dx).astype(int), (px[k, 1] + dy).astype(int)))
    k, ix, iy = (np.concatenate(c) for c in zip(*cols))
    ok = (ix >= 0) & (ix < W) & (iy >= 0) & (iy < H)
    k, ix, iy = k[ok], ix[ok], iy[ok]
    pix = iy * W + ix
    order = np.lexsort((depth[k], pix))                   # per pixel, the nearest first
    pix, k = pix[order], k[order]
    first = np.r_[True, pix[1:] != pix[:-1]]
    pick = np.full(H * W, -1, np.int64)
    front = np.full(H * W, np.nan)
    pick[pix[first]] = k[first]
    front[pix[first]] = depth[k[first]]
    pick, front = pick.reshape(H, W), front.reshape(H, W)
    return cam, pick, front


def _ear(cloud, graph):
    p = cloud.positions
    return graph.connected([int(np.argmax(p[:, 1]))], p[:, 1] > 0.3)


def _ear_centre_px(cloud, graph, cam):
    ear = _ear(cloud, graph)
    px, _ = cam.project(cloud.positions[ear], W, H)
    ey = cloud.positions[ear, 1]
    mid = np.abs(ey - np.median(ey)) < 0.01
    return px[mid].mean(axis=0), ear


def test_3d_dab_takes_front_and_back_of_the_ear_visible_dab_only_front(bunny, view):
    cloud, graph = bunny
    cam, pick, front = view
    (x, y), ear = _ear_centre_px(cloud, graph, cam)
    # a brush as wide as the ear (as a user paints a thin part: one stroke covers its width)
    px, _ = cam.project(cloud.positions[ear], W, H)
    radius_px = float(np.quantile(np.abs(px[:, 0] - x)[np.abs(px[:, 1] - y) < 2], 0.9))
    assert 10 < radius_px < 40
    sph = tools.brush_sphere(BrushPicker(pick, pick_depth=front), cam, cloud.positions, x, y, radius_px, (W, H))
    got = tools.splats_in_sphere(graph.tree, sph)
    facing = cloud.normals[:, 2] > 0                         # the camera looks along -z
    # the ear's cross-section under the dab: ear splats projecting well inside the circle (at its
    # rim the sphere is thin in depth and an inclined surface leaves it)
    px, depth = cam.project(cloud.positions, W, H)
    under = ear & (np.hypot(px[:, 0] - x, px[:, 1] - y) <= 0.6 * radius_px)
    assert (under & facing).sum() > 20 and (under & ~facing).sum() > 20
    sel = np.zeros(cloud.n, bool)
    sel[got] = True
    assert sel[under & facing].mean() > 0.95 and sel[under & ~facing].mean() > 0.95
    visible = picker_for_view(pick, front, cam, cloud.positions, cloud.radii).query(x, y, radius_px)
    vis = np.zeros(cloud.n, bool)
    vis[visible] = True
    assert vis[under & ~facing].mean() < 0.2 < vis[under & facing].mean()
    # the sphere is the brush circle at the surface's depth: what it takes projects near the circle
    d = np.hypot(px[got, 0] - x, px[got, 1] - y)
    assert d.max() <= radius_px * 1.25
    assert np.all(np.abs(depth[got] - sph.depth) <= sph.radius + 1e-12)


def test_dab_over_the_background_uses_the_nearest_model_pixel_in_the_circle(bunny, view):
    cloud, graph = bunny
    cam, pick, front = view
    ys, xs = np.nonzero(pick >= 0)
    x = float(xs.max()) + 4.5                                # right of the model's rightmost pixel
    y = float(ys[np.argmax(xs)]) + 0.5
    assert tools.surface_under(pick, front, None, x, y, 3.0) is None
    hit = tools.surface_under(pick, front, None, x, y, 8.0)
    assert hit is not None and hit[0] == pick[int(y), int(xs.max())]
    sph = tools.brush_sphere(BrushPicker(pick, pick_depth=front), cam, cloud.positions, x, y, 8.0, (W, H))
    assert len(tools.splats_in_sphere(graph.tree, sph)) > 0


def test_grow_and_shrink_by_one_ring(bunny):
    cloud, graph = bunny
    p = cloud.positions
    sel = Selection(cloud.n, np.linalg.norm(p - p[0], axis=1) < 0.1)
    grown = tools.grown(sel, graph, SUPPORT)
    ring = grown & ~sel.support
    assert ring.any() and np.array_equal(np.flatnonzero(ring), graph.ring(sel.support))
    assert tools.set_target(sel, SUPPORT, grown) and np.array_equal(sel.support, grown)
    back = tools.shrunk(sel, graph, SUPPORT)
    assert (back & ~grown).sum() == 0 and back.sum() < grown.sum()
    # a handle grows only inside the support and outside the other handles
    sel.handles[0][:] = False
    sel.handles[0][np.argmin(np.linalg.norm(p - p[0], axis=1))] = True
    for _ in range(30):
        tools.set_target(sel, HANDLE, tools.grown(sel, graph, HANDLE))
    assert sel.handle.sum() > 1 and not (sel.handle & ~sel.support).any()


def test_invert_support_clears_handles_and_invert_handle_stays_in_support(bunny):
    cloud, _ = bunny
    p = cloud.positions
    sup = p[:, 1] > 0.2
    sel = Selection(cloud.n, sup, handles=[p[:, 1] > 0.45, (p[:, 1] > 0.2) & (p[:, 1] < 0.25)], active=0)
    inv = tools.inverted(sel, HANDLE)
    assert not (inv & ~sup).any() and not (inv & sel.handles[1]).any() and not (inv & sel.handles[0]).any()
    assert inv.sum() == sup.sum() - sel.handles[0].sum() - sel.handles[1].sum()
    tools.set_target(sel, SUPPORT, tools.inverted(sel, SUPPORT))
    assert np.array_equal(sel.support, ~sup) and sel.counts[1] == 0


def test_connected_stays_within_the_reach_and_is_one_piece(bunny):
    cloud, graph = bunny
    p = cloud.positions
    tip = int(np.argmax(p[:, 1]))
    reach = np.linalg.norm(p - p[tip], axis=1) < 0.12
    part = tools.connected_region(graph, tip, reach)
    assert part[tip] and not (part & ~reach).any()
    count, _ = graph.components(np.flatnonzero(part))
    assert count == 1
    whole = tools.connected_region(graph, tip, None)
    assert whole.sum() > 0.9 * cloud.n


def test_closure_fills_a_painted_hole_and_reports_it(bunny):
    cloud, graph = bunny
    p = cloud.positions
    c = p[np.argmax(p[:, 0])]
    d = np.linalg.norm(p - c, axis=1)
    hole = (d > 0.03) & (d < 0.045)
    sel = Selection(cloud.n, (d < 0.12) & ~hole)
    added = tools.apply_closure(sel, cloud, graph)
    assert hole.sum() > 10 and sel.support[hole].all()
    assert added[hole].all() and not (added & ~sel.support).any()
    again = tools.apply_closure(sel, cloud, graph)                  # closed: nothing more to add
    assert not again.any()


def test_tool_with_closure_is_one_undo_step(bunny):
    from splatedit.app.document.session import Session
    cloud, graph = bunny
    s = Session(cloud, fit_sync=True)
    t = tools.SelectionTools()
    p = cloud.positions
    s.paint(np.flatnonzero(np.linalg.norm(p - p[0], axis=1) < 0.08))
    s.end_stroke(True)
    before = s.selection.support.copy()
    assert t.apply(s, SUPPORT, tools.grown(s.selection, t.graph(cloud), SUPPORT), "grow support")
    assert s.selection.support.sum() > before.sum()
    assert t.highlighted(cloud) is None or t.highlighted(cloud).sum() == t.last_added
    assert s.undo() and np.array_equal(s.selection.support, before)
    s.close()


def _erase_stroke(s, t, centre, radius, within):
    """An erase stroke of the support (a ball of ``radius`` about ``centre``),
    then the stroke's closure (cut to the selection before it when ``within``)."""
    p = s.cloud.positions
    before = s.selection.copy()
    s.paint(np.flatnonzero(np.linalg.norm(p - centre, axis=1) < radius), erase=True)
    stroked = s.selection.support.copy()
    t.close(s, within=before if within else None)
    return before.support, stroked, s.selection.support.copy()


@pytest.mark.parametrize("within", [False, True])
def test_an_erase_stroke_stays_erased_and_never_grows_the_support(bunny, within):
    """A painted support with a notch at its rim that the stroke did not
    cover; an erase stroke in its middle.  The erased hole is small enough to
    be an enclosed island, but closure never gives erased splats back, and
    it does not fill the notch either (outside the strokes' reach), with or
    without cutting it to the selection before the stroke (the tester saw
    the hole refilled and the support grow: 9158 -> 9209)."""
    from splatedit.app.document.session import Session
    cloud, graph = bunny
    p = cloud.positions
    s = Session(cloud, fit_sync=True)
    t = tools.SelectionTools()
    t._store(cloud, graph)
    c = p[np.argmax(p[:, 0])]
    d = np.linalg.norm(p - c, axis=1)
    rim = p[np.flatnonzero((d > 0.105) & (d < 0.12))[0]]
    notch = np.linalg.norm(p - rim, axis=1) < 0.012
    s.paint(np.flatnonzero((d < 0.12) & ~notch))
    s.end_stroke(True)
    inside = np.flatnonzero(s.selection.support & (d < 0.04))[0]
    before, stroked, after = _erase_stroke(s, t, p[inside], 0.02, within)
    erased = before & ~stroked
    assert erased.sum() > 10
    assert not after[erased].any()                       # the erase wins
    assert not (after & ~before).any()                   # nothing new: the notch stays open
    forgetful = close_selection(cloud, stroked, [], graph=graph)
    assert forgetful.support[erased].all()               # what the memory prevents: an island refilled
    assert tools.erase_message(before, after, "support") == f"erased {int(erased.sum()):,} splats from the support"
    s.close()


def test_an_erase_stroke_at_the_edge_stays_erased(bunny):
    from splatedit.app.document.session import Session
    cloud, graph = bunny
    p = cloud.positions
    s = Session(cloud, fit_sync=True)
    t = tools.SelectionTools()
    t._store(cloud, graph)
    c = p[np.argmax(p[:, 0])]
    d = np.linalg.norm(p - c, axis=1)
    s.paint(np.flatnonzero(d < 0.12))
    s.end_stroke(True)
    t.close(s)
    edge = p[np.flatnonzero(s.selection.support & (d > 0.11))[0]]
    before, stroked, after = _erase_stroke(s, t, edge, 0.03, True)
    erased = before & ~stroked
    assert erased.sum() > 10 and not (after & ~before).any() and not after[erased].any()
    assert tools.erase_message(before, after, "support") == f"erased {int(erased.sum()):,} splats from the support"
    assert tools.erase_message(after, after, "support") == ""
    s.close()


def test_a_dab_covers_every_splat_under_its_circle_at_any_depth(bunny):
    """The brush's reach: the visible splats under the circle and the ones
    hidden behind them (the far side of the ear), nothing outside the circle."""
    from splatedit.app.tools.pick_brush import BrushPicker
    cloud, graph = bunny
    p = cloud.positions
    w = h = 200
    lo, hi = p[:, :2].min(0), p[:, :2].max(0)
    px = (p[:, :2] - lo) / (hi - lo).max() * (w - 1)         # an orthographic view along -z
    depth = 10.0 - p[:, 2]
    pick = np.full((h, w), -1)
    order = np.argsort(-depth)                                # nearest written last
    pick[px[order, 1].astype(int), px[order, 0].astype(int)] = order
    picker = BrushPicker(pick, px, depth, np.full(len(p), 1e-3))
    cx, cy, r = 100.0, 100.0, 12.0
    covered = picker.covered(cx, cy, r)
    inside = np.flatnonzero((px[:, 0] - cx) ** 2 + (px[:, 1] - cy) ** 2 <= r * r)
    assert np.isin(inside, covered).all()
    visible = picker.query(cx, cy, r)
    hidden = np.setdiff1d(covered, visible)
    assert len(hidden) > 10 and depth[hidden].max() > depth[visible].min() + 0.1 * cloud.diagonal  # the back
    far = (px[covered, 0] - cx) ** 2 + (px[covered, 1] - cy) ** 2 > (r + 1.5) ** 2
    assert not far.any()
