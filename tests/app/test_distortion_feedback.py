"""Distortion feedback in the editor: the session's figures for the live pose,
the panel line, and the viewport's heat-map toggle reaching the renderer."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.app import overlay as ov
from splatedit.app.session import GRAB, SCALE, Session
from splatedit.deform.distortion import basis_distortion
from tests.app.sessions import plane_cloud, view
from tests.app.test_session import paint_regions


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
    from splatedit.app.camera_control import OrbitCamera
    from splatedit.app.viewport import Viewport
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
