"""The editor's progressive full-quality refinement (FrameScheduler +
ProgressiveRefinement), without a window: a fake editor around a real
Session, Viewport (lavapipe) and level-of-detail pyramid."""

from __future__ import annotations

import types

import numpy as np
import pytest

from splatedit.bench.editor import bunny_surface_cloud
from splatedit.app.view.camera_control import OrbitCamera
from splatedit.app.view.frames import FrameScheduler
from splatedit.app.tools.base import DragMode
from splatedit.model.lod import LodPyramid

pytestmark = pytest.mark.gpu

W, H = 160, 120


class _Presenter:
    def __init__(self):
        self.frames = []

    def present(self, frame):
        self.frames.append(frame.copy())


def _editor(n=60000, cloud=None, budgets=(8000, 2000), **session):
    from splatedit.app.document.session import Session
    from splatedit.app.view.viewport import Viewport
    cloud = bunny_surface_cloud(n) if cloud is None else cloud
    vp = Viewport(budget_ms=100.0)
    vp.set_pyramid(LodPyramid(cloud, budgets=budgets))
    cam = OrbitCamera(scene_radius=cloud.diagonal / 2, yaw=0.3, pitch=0.2)
    lo, hi = cloud.bounds()
    cam.frame((lo + hi) / 2, cloud.diagonal / 2, W / H)
    ed = types.SimpleNamespace(
        session=Session(cloud, **session), viewport=vp, cam=cam, size=(W, H), drag=DragMode.NONE, gui=None,
        presenter=_Presenter(), said=[], overlay_patches=lambda w, h: [], wake=lambda: None,
        window=types.SimpleNamespace(iconified=lambda: False),
        camera=types.SimpleNamespace(view_hint=lambda: None),      # the still view's edge-on hint
        selection_tools=types.SimpleNamespace(prepare=lambda c: None),
        picking=types.SimpleNamespace(invalidate=lambda: None, key=lambda: None))
    ed.say = ed.said.append
    return ed


@pytest.fixture
def ed(monkeypatch):
    # chunks of 8000 splats (about 8 steps per phase) whatever this machine's speed
    import splatedit.app.view.frames as frames
    import splatedit.app.view.progressive_refine as pr
    monkeypatch.setattr(frames, "EDITOR_PROGRESSIVE_MIN_CHUNK", 8000)
    monkeypatch.setattr(pr, "EDITOR_PROGRESSIVE_MIN_CHUNK", 8000)
    monkeypatch.setattr(pr, "EDITOR_PROGRESSIVE_CHUNK_MAX_GROWTH", 1.0)
    # one chunk per presented frame (a slow device: a chunk fills the frame budget)
    monkeypatch.setattr(pr.ProgressiveRefinement, "budget_ms", lambda self: 0.0)
    e = _editor()
    e.frames = FrameScheduler(e, 100.0)
    yield e
    e.frames.close()
    e.session.close()
    e.viewport.close()


def _slow(ed):
    """Pretend full-quality frames are slow (LOD while moving, progressive when still)."""
    ed.viewport.assume_cost(4000.0 / ed.session.cloud.n, W * H)
    ed.frames.budget_ms = ed.viewport.budget_ms = 100.0


def test_still_view_sharpens_monotonically_and_ends_equal_to_the_full_frame(ed):
    """After motion stops on a slow model, each idle frame draws chunks and
    composes them over the LOD frame on the device: the shown image keeps the
    LOD frame where nothing has arrived, the splats drawn grow every shown
    step, the area changed from the LOD frame grows, and the last shown image
    equals the one-submit full frame (within the pre-pass tolerance: the
    chunks go through the compute pre-pass)."""
    fr, vp = ed.frames, ed.viewport
    _slow(ed)
    fr.motion()
    fr.draw()                                       # moving: a level of detail
    assert vp.last_info.lod and fr.scene_interactive
    lod = ed.presenter.frames[-1]
    fr.last_motion -= 1.0                           # motion stopped
    shown, drawn = [], []
    for _ in range(200):
        assert fr.pending() or fr.progressive is None
        fr.draw()
        p = fr.progressive or fr.last_progressive
        if p is not None and p.shown_splats and (not drawn or p.shown_splats[-1] != drawn[-1]):
            shown.append(ed.presenter.frames[-1])
            drawn.append(p.shown_splats[-1])
        if fr.progressive is None and fr.last_progressive is not None:
            break
    p = fr.last_progressive
    assert p is not None and p.done and not fr.scene_interactive and not fr.pending()
    assert len(shown) >= 3
    assert all(a < b for a, b in zip(drawn, drawn[1:])) and drawn[-1] == ed.session.cloud.n
    # the visibility frames show the LOD frame unchanged; then it fills in
    assert all(np.array_equal(f, lod) for f in ed.presenter.frames[1:len(ed.presenter.frames) - len(shown)])
    changed = np.array([int((s != lod).any(axis=2).sum()) for s in shown])
    assert changed[0] > 0 and changed[0] < 0.9 * changed[-2]
    assert (np.diff(changed[:-1]) >= -0.01 * changed[-2]).all(), changed     # grows (a pixel may match by chance)
    from splatedit.app.view.viewport import render_camera
    assert p.frame.prepared                         # the chunks went through the compute pre-pass
    ref = vp.full.r.render(render_camera(ed.cam), W, H)
    # the pre-pass tolerance (tests/render/test_paths.py): records blend in atomic order
    diff = np.abs(shown[-1][..., :3].astype(int) - ref[..., :3].astype(int))
    assert diff.mean() < 0.6, diff.mean()
    assert (diff.max(axis=2) > 24).mean() < 0.003
    assert p.first_chunk_s is not None and p.first_chunk_s <= p.done_s
    assert len(p.frame_ms) == len(p.work_ms) == len(p.show_ms)


def test_any_change_drops_the_refinement(ed):
    """A camera change between steps drops the half-drawn refinement and draws
    a LOD frame of the new view; a display option change does the same."""
    fr, vp = ed.frames, ed.viewport
    _slow(ed)
    fr.motion()
    fr.draw()
    fr.last_motion -= 1.0
    for _ in range(3):
        fr.draw()
    assert fr.progressive is not None and not fr.progressive.done
    ed.cam.yaw += 0.2
    fr.motion()
    fr.draw()
    assert fr.progressive is None and vp.last_info.lod and fr.scene_interactive
    fr.last_motion -= 1.0
    fr.draw()
    first = fr.progressive
    assert first is not None
    vp.grey = True
    fr.draw()
    assert first.frame._rb is None and first.frame._shown is None     # closed
    assert fr.progressive is None or fr.progressive is not first


def test_several_chunks_per_presented_frame_up_to_the_budget(ed, monkeypatch):
    """With a real frame budget (40 ms here) a presented frame draws as many
    chunks as fit: more steps than presented frames, every frame's steps stay
    within the budget plus one step, and the refinement still ends in the
    full frame."""
    import splatedit.app.view.progressive_refine as pr
    monkeypatch.undo()
    monkeypatch.setattr(pr, "EDITOR_PROGRESSIVE_MIN_CHUNK", 4000)
    monkeypatch.setattr(pr, "EDITOR_PROGRESSIVE_CHUNK_MAX_GROWTH", 1.0)
    fr = ed.frames
    _slow(ed)
    fr.budget_ms = 40.0
    fr.motion()
    fr.draw()
    fr.last_motion -= 1.0
    for _ in range(200):
        fr.draw()
        if fr.progressive is None and fr.last_progressive is not None:
            break
    p = fr.last_progressive
    assert p is not None and p.done and not fr.scene_interactive
    assert len(p.step_ms) > len(p.work_ms) >= 2
    # a frame stops once the next step would pass the budget: at most one step over it
    assert all(w <= 40.0 + max(p.step_ms) + 1.0 for w in p.work_ms), (p.work_ms, max(p.step_ms))


def test_the_detail_mode_is_refined_progressively_too(monkeypatch):
    """A bent bumpy plane in the detail mode (its own pre-pass shader): after
    motion stops the view is refined progressively on the editor's device and
    ends equal to the one-submit detail frame."""
    from splatedit.deform.modes import DeformationMode
    from tests.deform.detail_scene import bend, bumpy_plane
    import splatedit.app.view.progressive_refine as pr
    monkeypatch.setattr(pr.ProgressiveRefinement, "budget_ms", lambda self: 0.0)
    monkeypatch.setattr(pr, "EDITOR_PROGRESSIVE_MIN_CHUNK", 1000)
    monkeypatch.setattr(pr, "EDITOR_PROGRESSIVE_CHUNK_MAX_GROWTH", 1.0)
    sc = bumpy_plane(nx=90, ny=30)
    ed = _editor(cloud=sc.cloud, budgets=(800, 300), fit_sync=True)
    ed.frames = FrameScheduler(ed, 100.0)
    try:
        s, fr, vp = ed.session, ed.frames, ed.viewport
        s.set_selection(sc.support, sc.handle)
        assert s.wait_fit()
        while s.deformation is not DeformationMode.DETAIL:
            s.cycle_deformation()
            assert s.wait_fit()
        s.pose[0] = bend(sc)
        _slow(ed)
        fr.motion()
        fr.draw()
        assert vp.last_info.lod and fr.scene_interactive
        fr.last_motion -= 1.0
        for _ in range(100):
            fr.draw()
            if fr.last_progressive is not None:
                break
        p = fr.last_progressive
        assert p is not None and p.done and len(p.step_ms) >= 4
        assert vp.full.r.uploads.detail_buf is not None and p.frame.prepared
        from splatedit.app.view.viewport import render_camera
        ref = vp.full.r.render(render_camera(ed.cam), W, H)
        diff = np.abs(ed.presenter.frames[-1][..., :3].astype(int) - ref[..., :3].astype(int))
        assert diff.mean() < 0.6 and (diff.max(axis=2) > 24).mean() < 0.003
        assert (ref[..., :3] < 250).any()
    finally:
        ed.frames.close()
        ed.session.close()
        ed.viewport.close()


def test_the_brush_pick_map_is_drawn_in_chunks_after_the_refinement(ed):
    """Once the still view is refined, the scheduler keeps drawing (pending)
    until the view's pick map is complete, a chunk per frame, then hands it to
    the brush (take_pick of its key): equal to a whole pick of the view; a
    camera change drops a pick map under way."""
    fr, vp = ed.frames, ed.viewport
    key = ("view", 1)
    ed.picking.key = lambda: key
    _slow(ed)
    fr.motion()
    fr.draw()
    fr.last_motion -= 1.0
    for _ in range(100):
        fr.draw()
        if fr.last_progressive is not None:
            break
    assert fr.picking is not None and fr.pending() and fr.take_pick(key) is None
    frames = 0
    while fr.picking is not None and frames < 50:
        fr.draw()
        frames += 1
    assert frames >= 2 and not fr.pending()
    idx, depth = fr.take_pick(key)
    ref_idx, ref_depth = vp.pick(ed.cam, W, H)
    assert (ref_idx >= 0).mean() > 0.1
    # the pre-pass path: nearest-splat ties may resolve differently
    assert (idx == ref_idx).mean() > 0.99
    assert fr.take_pick(("view", 2)) is None
    # a new view: its pick map is dropped when the camera moves again
    ed.cam.yaw += 0.3
    key = ("view", 2)
    _slow(ed)                                       # the refinement measured the real (fast) cost
    fr.motion()
    fr.draw()
    fr.last_motion -= 1.0
    for _ in range(100):
        fr.draw()
        if fr.picking is not None:
            break
    assert fr.picking is not None
    p = fr.picking[0]
    ed.cam.yaw += 0.3
    fr.motion()
    fr.draw()
    assert fr.picking is None and p.frame._rb is None and fr.take_pick(key) is None
