"""The editor's progressive full-quality refinement (FrameScheduler +
ProgressiveRefinement), without a window: a fake editor around a real
Session, Viewport (lavapipe) and level-of-detail pyramid."""

from __future__ import annotations

import types

import numpy as np
import pytest

from splatedit.app.bench import bunny_surface_cloud
from splatedit.app.camera_control import OrbitCamera
from splatedit.app.frames import FrameScheduler
from splatedit.app.tools.base import DragMode
from splatedit.model.lod import LodPyramid

pytestmark = pytest.mark.gpu

W, H = 160, 120


class _Presenter:
    def __init__(self):
        self.frames = []

    def present(self, frame):
        self.frames.append(frame.copy())


def _editor(n=60000):
    from splatedit.app.session import Session
    from splatedit.app.viewport import Viewport
    cloud = bunny_surface_cloud(n)
    vp = Viewport(budget_ms=100.0)
    vp.set_pyramid(LodPyramid(cloud, budgets=(8000, 2000)))
    cam = OrbitCamera(scene_radius=cloud.diagonal / 2, yaw=0.3, pitch=0.2)
    lo, hi = cloud.bounds()
    cam.frame((lo + hi) / 2, cloud.diagonal / 2, W / H)
    ed = types.SimpleNamespace(
        session=Session(cloud), viewport=vp, cam=cam, size=(W, H), drag=DragMode.NONE, gui=None,
        presenter=_Presenter(), said=[], overlay_patches=lambda w, h: [], wake=lambda: None,
        window=types.SimpleNamespace(iconified=lambda: False),
        brush=types.SimpleNamespace(picker=None, tools=types.SimpleNamespace(prepare=lambda c: None),
                                    pick_key=lambda: None))
    ed.say = ed.said.append
    return ed


@pytest.fixture
def ed(monkeypatch):
    # chunks of 8000 splats (about 8 steps per phase) whatever this machine's speed
    import splatedit.app.frames as frames
    import splatedit.app.progressive_refine as pr
    monkeypatch.setenv("SPLATEDIT_REFINE", "progressive")   # opt-in (see frames._progressive_step)
    monkeypatch.setattr(frames, "EDITOR_PROGRESSIVE_MIN_CHUNK", 8000)
    monkeypatch.setattr(pr, "EDITOR_PROGRESSIVE_MIN_CHUNK", 8000)
    monkeypatch.setattr(pr, "EDITOR_PROGRESSIVE_CHUNK_MAX_GROWTH", 1.0)
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
    """After motion stops on a slow model, each idle frame draws one chunk: the
    shown image keeps the LOD frame where nothing has arrived, the splats drawn
    grow every shown step, the area covered by full-quality splats never
    shrinks, and the last shown image equals the one-submit full frame (within
    the pre-pass tolerance: the chunks go through the compute pre-pass)."""
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
    # the first chunk image is the LOD frame outside the pixels already refined
    covered = p.covered_pixels
    assert all(a <= b for a, b in zip(covered, covered[1:])) and covered[0] < 0.9 * covered[-2]
    changed = [int((s != lod).any(axis=2).sum()) for s in shown]
    assert all(c <= k for c, k in zip(changed[:-1], covered[:-1]))
    assert changed[0] > 0
    from splatedit.app.viewport import render_camera
    assert p.frame.prepared                         # the chunks went through the compute pre-pass
    ref = vp.full.r.render(render_camera(ed.cam), W, H)
    # the pre-pass tolerance (tests/render/test_paths.py): records blend in atomic order
    diff = np.abs(shown[-1][..., :3].astype(int) - ref[..., :3].astype(int))
    assert diff.mean() < 0.6, diff.mean()
    assert (diff.max(axis=2) > 24).mean() < 0.003
    assert p.first_chunk_s is not None and p.first_chunk_s <= p.done_s


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
    assert first.frame._rb is None                  # closed
    assert fr.progressive is None or fr.progressive is not first
