"""The editor's first view of a scan with far outlier clumps (window-less):
opening poste_france.xyz frames its main body, not the 262-unit box of the
clumps, and the status line says how many points are left out and how to
remove them."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from splatedit.app.document.session import Session
from tests.app.sessions import plane_cloud

pytest.importorskip("glfw")


def test_opening_a_scan_with_far_clumps_frames_its_body_and_says_so(shared_data, tmp_path):
    from tests.app.test_editor_files import StubEditor
    s = Session(plane_cloud(8), fit_sync=True)
    ed = StubEditor(s, tmp_path / "plane.ply")
    try:
        ed.panel_visible = False
        ed.file_actions.open_path(shared_data / "poste_france.xyz")
        ed.settle()
        cloud = ed.session.cloud
        assert cloud.n == 9031
        loaded = [m for m in ed.messages if m.startswith("loaded poste_france.xyz")]
        assert loaded and loaded[-1].endswith("points far outside the main body (outliers?): "
                                              "`splatedit convert --remove-outliers`")
        ext = ed.camera.extent()
        w, h = ed.size
        px, depth = ed.cam.project(cloud.positions, w, h)
        body = np.all((cloud.positions >= ext.lo) & (cloud.positions <= ext.hi), axis=1)
        # the body spans about half the window (measured 0.59 of its height at
        # this stub's view angles); framing the full box it spanned 0.064
        span = ((px[body].max(0) - px[body].min(0)) / (w, h)).max()
        full = copy.deepcopy(ed.cam)
        lo, hi = cloud.bounds()
        full.frame((lo + hi) / 2, float(np.linalg.norm(hi - lo)) / 2, w / h)
        fpx, _ = full.project(cloud.positions[body], w, h)
        full_span = ((fpx.max(0) - fpx.min(0)) / (w, h)).max()
        assert span > 0.45 and span > 5 * full_span and np.all(depth[body] > 0), (span, full_span)
        assert px[body].min() >= 0 and np.all(px[body].max(0) <= (w, h))
        # the clipping and levels of detail keep the true bounds
        assert np.isclose(ed.cam.scene_radius, np.linalg.norm(hi - lo) / 2)
    finally:
        ed.session.close()
