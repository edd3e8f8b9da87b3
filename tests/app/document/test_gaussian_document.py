"""Gaussian Splatting scenes as editor documents (issue 13), without a window:
the session edits the Gaussians' splat proxy with the scene attached; a
commit deforms the Gaussians on the CPU (what a save writes) and the live
GPU frame of the pending pose draws the same scene; undo brings the old
scene back; the save job writes a 3DGS PLY; the exported script replays to
the same file."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from splatedit.app.document import files
from splatedit.app.view.camera_control import OrbitCamera
from splatedit.app.document.gaussian import commit_cloud, gaussian_document, gaussians_of
from splatedit.app.document.session import Session
from splatedit.data import gaussian_scene_path
from splatedit.deform.gaussians import deform_with_evaluator
from splatedit.deform.modes import DeformationMode
from splatedit.io import read_gaussians
from splatedit.model.spherical_harmonics import rotate_sh


@pytest.fixture(scope="module")
def scene():
    return read_gaussians(gaussian_scene_path())


def _ear_session(scene, mode=DeformationMode.ROTATION) -> Session:
    """Support: the top 15 % of the bunny (ears), handle: the top 6 %; fitted."""
    doc = gaussian_document(scene)
    s = Session(doc, fit_sync=True)
    s.deformation = mode
    y = doc.positions[:, 1]
    s.set_selection(y > np.percentile(y, 85), y > np.percentile(y, 94))
    assert s.wait_fit() and s.state == "ready"
    return s


def _turn(s: Session, degrees: float) -> np.ndarray:
    """Pose the handle turned about the view (z) axis through its centroid."""
    c = s.handle_centroid()
    a = np.eye(4)
    a[:3, :3] = Rotation.from_rotvec(np.radians(degrees) * np.array([0.0, 0.0, 1.0])).as_matrix()
    a[:3, 3] = c - a[:3, :3] @ c
    s.pose[0] = a
    return a


def test_the_document_is_the_proxy_with_the_scene_attached(scene):
    doc = gaussian_document(scene)
    assert gaussians_of(doc) is scene and doc.n == len(scene)
    assert np.array_equal(doc.positions, scene.positions)
    assert gaussians_of(doc.replace(positions=doc.positions + 1.0)) is None      # derived clouds: plain splats
    assert gaussians_of(scene.proxy_splats()) is None


@pytest.mark.parametrize("mode", [DeformationMode.ROTATION, DeformationMode.LINEAR])
def test_commit_deforms_the_gaussians_and_undo_restores_them(scene, mode):
    s = _ear_session(scene, mode)
    a = _turn(s, 90.0)
    dc = s.current_dc()
    want = deform_with_evaluator(scene, s.basis, dc)
    handle = np.flatnonzero(s.selection.handle)
    assert s.commit()
    got = gaussians_of(s.cloud)
    assert got is not None and got is not scene and len(got) == len(scene)
    for nm in ("positions", "log_scales", "rotations", "sh"):
        assert np.array_equal(getattr(got, nm), getattr(want, nm)), nm
    # the handle turned rigidly, its SH with it; the next edit fits on the new proxy
    assert np.abs(got.positions[handle] - (scene.positions[handle] @ a[:3, :3].T + a[:3, 3])).max() < 1e-6
    sh_want = rotate_sh(scene.sh[handle], np.broadcast_to(a[:3, :3], (len(handle), 3, 3)))
    assert np.abs(got.sh[handle] - sh_want).max() < 1e-4
    assert np.array_equal(s.cloud.positions, got.positions)
    assert s.edits[0].deformation is mode
    assert s.undo() and gaussians_of(s.cloud) is scene
    assert s.redo() and gaussians_of(s.cloud) is got


def test_plain_documents_commit_through_the_basis(scene):
    proxy = scene.proxy_splats()
    s = Session(proxy, fit_sync=True)
    y = proxy.positions[:, 1]
    s.set_selection(y > np.percentile(y, 85), y > np.percentile(y, 94))
    assert s.wait_fit()
    _turn(s, 30.0)
    out = commit_cloud(s.basis, proxy, s.current_dc())
    assert gaussians_of(out) is None and not np.array_equal(out.positions, proxy.positions)


@pytest.mark.gpu
def test_live_gpu_frame_equals_the_committed_scene(scene):
    """The viewport draws the pending 90-degree rotation-aware pose on the GPU
    (centres, J Sigma J^T, SH frames by the polar rotation of J); after the
    commit it draws the CPU-deformed Gaussians undeformed: the two frames
    agree within GS_REF_MEAN_TOL (mean 8-bit steps over RGB)."""
    from splatedit.app.view.viewport import Viewport
    from splatedit.tolerances import GS_REF_MEAN_TOL
    s = _ear_session(scene)
    _turn(s, 90.0)
    vp = Viewport()
    try:
        vp.set_cloud(s.cloud)
        assert vp.gaussians is scene
        cam = OrbitCamera(scene_radius=s.cloud.diagonal / 2)
        lo, hi = s.cloud.bounds()
        cam.frame((lo + hi) / 2, s.cloud.diagonal / 2, 4 / 3)
        w, h = 200, 150
        before = vp.render(cam, w, h)
        assert vp.last_info.gaussians and vp.last_info.splats == len(scene)
        vp.set_basis(s.basis)
        vp.set_dc(s.current_dc())
        live = vp.render(cam, w, h)
        assert s.commit()
        vp.set_cloud(s.cloud)
        vp.set_basis(None)
        vp.set_dc(None)
        assert vp.gaussians is gaussians_of(s.cloud)
        committed = vp.render(cam, w, h)
        moved = np.abs(live.astype(int) - before)[..., :3].max(axis=2) > 16
        assert moved.mean() > 0.01                                   # the ear did turn
        diff = np.abs(live.astype(int) - committed)[..., :3]
        assert diff.mean() < GS_REF_MEAN_TOL, diff.mean()
        # back to a plain cloud: the splat renderer draws again
        vp.set_cloud(scene.proxy_splats())
        assert vp.gaussians is None and vp.render(cam, w, h).shape == (h, w, 4)
        assert not vp.last_info.gaussians
    finally:
        vp.close()


def test_save_writes_a_3dgs_file_and_the_script_replays_it(scene, tmp_path):
    from splatedit.script.gaussian import run_script_gaussians
    s = _ear_session(scene)
    _turn(s, 90.0)
    assert s.commit()

    class Ed:            # what files.save needs of the editor
        session, jobs, path, save_as = s, {}, gaussian_scene_path(), None
        said = []

        def say(self, text):
            self.said.append(text)

        def wake(self):
            pass
    ed = Ed()
    out = tmp_path / "ears.ply"
    files.save(ed, out)
    job = ed.jobs["save"]
    job.wait()
    assert job.error is None, job.error
    saved = read_gaussians(out)
    g = gaussians_of(s.cloud)
    assert saved.sh_degree == scene.sh_degree and list(saved.extra) == list(scene.extra)
    assert np.array_equal(saved.positions, g.positions.astype(np.float32).astype(np.float64))
    assert np.array_equal(saved.sh, g.sh)
    replayed, _ = run_script_gaussians(scene, s.edit_script())
    assert np.abs(replayed.positions - saved.positions).max() < 1e-6
    assert np.abs(replayed.covariances() - saved.covariances()).max() < 1e-6
    del ed.jobs["save"]                                    # (the editor's poll_jobs collects it)
    files.save(ed, tmp_path / "ears.xyz")                 # not a .ply: refused with a message
    assert "save" not in ed.jobs and ".ply" in ed.said[-1]


@pytest.mark.gpu
def test_two_handles_and_a_curve_draw_live_and_commit_as_one_edit(scene):
    """Both ears as handles (one turned 60 degrees, one moved) and a control
    curve across the back, all pending together: the live GPU frame and the
    frame of the committed Gaussians agree, and the commit is the CPU
    deformation of the same basis and pose."""
    from splatedit.app.view.viewport import Viewport
    from splatedit.tolerances import GS_REF_MEAN_TOL
    doc = gaussian_document(scene)
    s = Session(doc, fit_sync=True)
    p = doc.positions
    y, x = p[:, 1], p[:, 0]
    top = y > np.percentile(y, 80)
    tips = y > np.percentile(y, 95)
    split = np.median(x[tips])
    s.set_selection(top | (y > np.percentile(y, 60)), [tips & (x < split), tips & (x >= split)])
    back = p[(y > np.percentile(y, 62)) & (y < np.percentile(y, 70))]
    order = np.argsort(back[:, 0])
    for q in back[order[[len(order) // 5, len(order) // 2, 4 * len(order) // 5]]]:
        s.add_curve_point(q)
    assert s.wait_fit() and s.basis.n_columns == 4 + 4 + 3
    s.select_handle(0)
    a = _turn(s, 60.0)
    m = np.eye(4)
    m[:3, 3] = [0.0, 0.05, 0.04]
    s.pose[1] = m
    s.curve_moves = np.array([[0.0, 0.0, 0.0], [0.0, 0.04, 0.0], [0.0, 0.0, 0.0]])
    dc = s.current_dc()
    want = deform_with_evaluator(scene, s.basis, dc)
    vp = Viewport()
    try:
        vp.set_cloud(s.cloud)
        cam = OrbitCamera(scene_radius=doc.diagonal / 2)
        lo, hi = doc.bounds()
        cam.frame((lo + hi) / 2, doc.diagonal / 2, 4 / 3)
        before = vp.render(cam, 200, 150)
        vp.set_basis(s.basis)
        vp.set_dc(dc)
        live = vp.render(cam, 200, 150)
        assert s.commit() and len(s.edits) == 1 and len(s.edits[0].handles) == 2 and s.edits[0].curves
        got = gaussians_of(s.cloud)
        assert np.array_equal(got.positions, want.positions) and np.array_equal(got.sh, want.sh)
        vp.set_cloud(s.cloud)
        vp.set_basis(None)
        vp.set_dc(None)
        committed = vp.render(cam, 200, 150)
    finally:
        vp.close()
    assert (np.abs(live.astype(int) - before)[..., :3].max(axis=2) > 16).mean() > 0.01
    assert np.abs(live.astype(int) - committed)[..., :3].mean() < GS_REF_MEAN_TOL
    assert not np.array_equal(a, np.eye(4))


def test_the_panel_names_gaussians_as_gaussians(scene):
    """The panel's first line says "5,000 Gaussians (3dgs, SH degree 3)" as
    the load message and README do, a plain cloud "N splats"."""
    from splatedit.app.document.gaussian import model_summary
    doc = gaussian_document(scene)
    assert model_summary(doc) == f"{len(scene):,} Gaussians ({scene.kind.value}, SH degree {scene.sh_degree})"
    assert "splats" not in model_summary(doc)
    plain = scene.proxy_splats()
    assert model_summary(plain) == f"{plain.n:,} splats"


def test_detail_mode_is_not_offered_for_a_gaussian_document_and_b_cycles_rotation_linear(scene):
    """Issue 19 item 1: B on a Gaussian scene went to DETAIL, whose basis the
    Gaussian transport cannot use (the commit raised AttributeError and the
    window closed).  As ``splatedit deform`` refuses it, the editor does not
    offer it: B cycles rotation <-> linear, choosing detail is refused with
    a message, and the plain splats' cycle still has it."""
    from splatedit.errors import SplatEditError
    s = _ear_session(scene)
    try:
        assert not s.detail_available
        assert s.deformation_cycle() == (DeformationMode.ROTATION, DeformationMode.LINEAR)
        assert s.cycle_deformation() is DeformationMode.LINEAR
        assert s.basis is not None and type(s.basis).__name__ == "DeformationBasis"
        with pytest.raises(SplatEditError, match="not available for Gaussian scenes"):
            s.set_deformation(DeformationMode.DETAIL)
        assert s.deformation is DeformationMode.LINEAR
        assert s.cycle_deformation() is DeformationMode.ROTATION
        _turn(s, 45.0)
        assert s.commit() and len(s.edits) == 1       # the commit works in the modes offered
    finally:
        s.close()
    plain = Session(scene.proxy_splats(), fit_sync=True)
    try:
        assert plain.detail_available and DeformationMode.DETAIL in plain.deformation_cycle()
    finally:
        plain.close()


def test_a_detail_basis_given_to_the_gaussian_commit_is_refused_with_a_message(scene):
    """The transport behind the issue's AttributeError: a DetailBasis reaching
    the Gaussian commit (any caller) is one clear SplatEditError, nothing changed."""
    from splatedit.deform.detail import DetailBasis
    from splatedit.errors import SplatEditError
    doc = gaussian_document(scene)
    y = doc.positions[:, 1]
    sup, hnd = y > np.percentile(y, 85), y > np.percentile(y, 94)
    basis = DetailBasis.fit(doc, sup, [hnd])
    with pytest.raises(SplatEditError, match="not available for Gaussian scenes"):
        commit_cloud(basis, doc, np.zeros((basis.n_columns, 3)))
