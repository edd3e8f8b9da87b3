"""Distortion feedback in the editor: the session's figures for the live pose,
the panel line, and the viewport's heat-map toggle reaching the renderer."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.app.ui import overlay as ov
from splatedit.app.document.session import GRAB, SCALE, Session
from splatedit.deform.distortion import basis_distortion
from tests.app.sessions import plane_cloud, view
from tests.app.document.test_session import paint_regions


@pytest.fixture
def session():
    s = Session(plane_cloud(), fit_sync=True)
    yield s
    s.close()


def test_session_figures_follow_the_live_pose_and_match_the_exact_computation(session):
    s = session
    paint_regions(s)
    assert s.wait_fit()
    assert s.distortion() is None                       # nothing moved yet
    assert s.begin(GRAB, view(), (100, 100))
    s.manip.set_axis(2)
    for ch in "0.3":
        s.manip.type_char(ch)
    lift = s.distortion()
    ref = basis_distortion(s.basis, s.cloud, s.current_dc())
    assert lift.max_stretch == pytest.approx(ref.max_stretch, rel=1e-5)
    assert lift.n_above_warn == ref.n_above_warn and lift.n == int(s.selection.support.sum())
    assert s.distortion() is lift                       # same pose: cached, not recomputed
    s.cancel()
    assert s.begin(SCALE, view(), (110, 100))           # scale the handle 4x about its centre
    s.manip.type_char("4")
    big = s.distortion()
    assert big.max_stretch > lift.max_stretch and big.n_above_warn > 0
    s.cancel()
    assert s.distortion() is None


def test_panel_line_format_and_colour(session):
    s = session
    paint_regions(s)
    assert s.wait_fit()
    assert s.begin(SCALE, view(), (110, 100))
    s.manip.type_char("4")
    st = s.distortion()
    lines = ov.distortion_lines(st, heat_map=False)
    assert len(lines) == 1
    text, rgb = lines[0]
    assert text.startswith(f"stretch max {st.max_stretch:.1f}x, {st.n_above_warn:,} > 3x")
    assert rgb == ov.DISTORTION_WARN_RGB
    assert len(ov.distortion_lines(None, heat_map=True)) == 1  # legend only
    assert ov.distortion_lines(None, heat_map=False) == []


def test_viewport_toggle_draws_the_heat_map(session):
    from splatedit.app.view.camera_control import OrbitCamera
    from splatedit.app.view.viewport import Viewport
    s = session
    paint_regions(s)
    assert s.wait_fit()
    assert s.begin(SCALE, view(), (110, 100))
    s.manip.type_char("3")
    vp = Viewport()
    try:
        vp.set_cloud(s.cloud)
        vp.set_selection(s.selection.support, s.selection.handle, s.version)
        vp.set_basis(s.basis)
        vp.set_dc(s.current_dc())
        cam = OrbitCamera(np.zeros(3), 3.0, 0.0, 0.5, 40.0, np.array([0.0, 0.0, 1.0]), 1.5)
        plain = vp.render(cam, 128, 128)
        vp.distortion_map = True
        heat = vp.render(cam, 128, 128)
        assert vp.full.r.distortion_map
        px = heat[..., :3].astype(int)
        # the tinted support is blue-ish; the heat map has none of that blue, and some warm pixels
        assert (plain[..., 2].astype(int) - plain[..., 0]).max() > 60
        assert (px[..., 2] - px[..., 0]).max() < 10
        assert ((px[..., 0] - px[..., 2]) > 60).sum() > 20
    finally:
        vp.close()


def _show(vp, s, heat_map):
    cloud, basis, dc = s.display_state(heat_map)
    vp.set_cloud(cloud)
    vp.set_selection(s.selection.support, s.selection.handle, s.version)
    vp.set_basis(basis)
    vp.set_dc(dc)


def test_the_last_committed_edit_keeps_its_figures_and_heat_map_until_the_document_changes(session):
    """A one-handle move commits on release; its stretch figures, the panel's
    "of edit N" line and the heat map (same warm pixels as during the move)
    stay until undo or the next stroke."""
    from splatedit.app.view.camera_control import OrbitCamera
    from splatedit.app.view.viewport import Viewport
    s = session
    paint_regions(s)
    assert s.wait_fit()
    assert s.begin(SCALE, view(), (110, 100))
    s.manip.type_char("3")
    live = basis_distortion(s.basis, s.cloud, s.current_dc())
    vp = Viewport()
    cam = OrbitCamera(np.zeros(3), 3.0, 0.0, 0.5, 40.0, np.array([0.0, 0.0, 1.0]), 1.5)
    try:
        vp.distortion_map = True
        _show(vp, s, True)
        during = vp.render(cam, 128, 128)[..., :3].astype(int)
        assert s.finish() == "commit" and len(s.edits) == 1
        s.wait_fit()            # the fit on the committed cloud (this 3x scale leaves none: too far apart)
        after = s.distortion()
        assert after is not None and after.max_stretch == pytest.approx(live.max_stretch, rel=1e-4)
        assert after.n_above_warn == live.n_above_warn
        assert ov.distortion_source(s).startswith("of edit 1: ")
        lines = ov.distortion_lines(after, True, ov.distortion_source(s))
        assert any(t.startswith("of edit 1") for t, _ in lines)
        # the viewport draws the edit's cloud + basis + dC: the same surface, coloured as during the move
        cloud, basis, dc = s.display_state(True)
        assert cloud is not s.cloud and basis is not s.basis
        from splatedit.app.document.gaussian import commit_cloud
        assert np.allclose(commit_cloud(basis, cloud, dc).positions, s.cloud.positions, rtol=0, atol=1e-12)
        _show(vp, s, True)
        kept = vp.render(cam, 128, 128)[..., :3].astype(int)
        warm = lambda px: ((px[..., 0] - px[..., 2]) > 60).sum()  # noqa: E731
        assert warm(during) > 20 and abs(warm(kept) - warm(during)) <= 0.05 * warm(during)
        assert s.display_state(False)[0] is s.cloud     # without the heat map: the document
        # undo ends it: nothing shown, the plain document drawn (all grey: nothing warm)
        assert s.undo()
        assert s.shown_edit() is None and s.distortion() is None and ov.distortion_source(s) == ""
        _show(vp, s, True)
        assert warm(vp.render(cam, 128, 128)[..., :3].astype(int)) == 0
        # redo returns to the state the edit made: shown again; a stroke (any new state) ends it
        assert s.redo() and s.shown_edit() is s.last_edit
        s.paint(np.flatnonzero(~s.selection.support)[:5])
        s.end_stroke(True)
        assert s.shown_edit() is None and s.distortion() is None
    finally:
        vp.close()
