"""The editor's commit of a far grab in the rotation mode refines its needles
(issue 20.3, splatedit.deform.refine) as ``splatedit deform`` does; the
linear mode commits the paper's plain translation."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.app.document.session import GRAB, Session
from splatedit.deform.distortion import distortion_from_axes
from splatedit.deform.modes import DeformationMode
from tests.app.sessions import plane_cloud, view
from tests.app.document.test_session import paint_regions


@pytest.mark.parametrize("mode", [DeformationMode.ROTATION, DeformationMode.LINEAR])
def test_committed_far_grab_is_refined_in_rotation_mode_and_plain_in_linear_mode(mode):
    s = Session(plane_cloud(), fit_sync=True)
    try:
        s.set_deformation(mode)
        paint_regions(s)
        assert s.wait_fit()
        before = s.cloud
        assert s.begin(GRAB, view(), (100, 100))
        s.manip.set_axis(0)                     # in the plane, towards the fixed band: needles
        for ch in "0.5":
            s.manip.type_char(ch)
        live = s.distortion()
        basis, dc = s.basis, s.current_dc()
        assert live.n_above_broken > 0.05 * live.n          # measured 50 of 432
        assert s.finish() == "commit" and s.wait_commit()
        idx = basis.indices
        after = distortion_from_axes(before.u[idx], before.v[idx], s.cloud.u[idx], s.cloud.v[idx])
        con = basis.constraints
        hi = np.concatenate(con.handle_index)
        moved = s.cloud.positions - before.positions
        assert np.abs(moved[hi] - [0.5, 0.0, 0.0]).max() <= 1e-9 * before.diagonal    # exact control
        assert np.abs(moved[con.fixed_index]).max() <= 1e-9 * before.diagonal
        plain = basis.commit(before, dc)
        if mode is DeformationMode.ROTATION:
            assert after.n_above_broken < live.n_above_broken / 2          # measured 15
            assert s.last_edit is None          # the basis and dC no longer draw the document
        else:
            assert np.array_equal(s.cloud.positions, plain.positions)
            assert s.last_edit is not None and s.distortion() is not None
    finally:
        s.close()
