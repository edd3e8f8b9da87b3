"""Issue 19 item 1: no exception in an event handler, a job's landing, a
commit or a frame takes the editor down.  Each is caught by the editor's
central guard (:mod:`splatedit.app.crash_guard`): shown in the error box,
the traceback on stderr, the document kept, and a recovery copy (model +
edit script, :mod:`splatedit.app.document.recovery`) written when there are unsaved
edits; the next start offers to restore it.  Without a window: the editor's
loop runs against a stub window and frame scheduler."""

from __future__ import annotations

import types

import numpy as np
import pytest

from splatedit.app.document import recovery
from splatedit.app.view.camera_control import OrbitCamera
from splatedit.app.editor import Editor
from splatedit.app.document.jobs import Job
from splatedit.app.ui.keymap import Action
from splatedit.app.document.session import GRAB, Session
from splatedit.app.ui.status import StatusWriter
from splatedit.io import read
from splatedit.script import load_script
from splatedit.select.selection import HANDLE, SUPPORT
from tests.app.sessions import plane_cloud, view

glfw = pytest.importorskip("glfw")


class StubWindow:
    def __init__(self):
        self.events = []

    def poll(self, timeout):
        got, self.events = self.events, []
        return got

    def iconified(self):
        return False

    def post_empty_event(self):
        pass


class StubFrames:
    """The frame scheduler's face the loop uses; ``fail``: draw raises it."""
    def __init__(self):
        self.fail = None
        self.drawn = 0
        self.scene_key = None

    def pending(self):
        return False

    def busy(self):
        return False

    def state(self):
        return "scene"

    def motion(self):
        pass

    def draw(self):
        self.drawn += 1
        if self.fail is not None:
            raise self.fail


class StubEditor(Editor):
    size = (640, 480)

    def __init__(self, session):
        self.path, self.bundled, self.offer_recent = None, False, False
        self.window = StubWindow()
        self.frames = StubFrames()
        self.status = StatusWriter(None)
        self.max_seconds = None
        self._init_state(OrbitCamera(np.zeros(3), 4.0, scene_radius=1.5), glfw)
        self.frames = self.frames if isinstance(self.frames, StubFrames) else StubFrames()
        self.session = session
        self.viewport = types.SimpleNamespace(grey=False, splat_scale=1.0, distortion_map=False, dc=None)
        self.messages = []

    def say(self, text):
        self.messages.append(text)

    def loop_once(self):
        """One pass of the editor's real loop (events, jobs, session, frame, status)."""
        self.running, self.max_seconds = True, -1.0
        self._loop()


@pytest.fixture
def ed(tmp_path, monkeypatch):
    monkeypatch.setenv(recovery.RECOVERY_DIR_ENV, str(tmp_path / "recovery"))
    s = Session(plane_cloud(), fit_sync=True)
    e = StubEditor(s)
    e.path = tmp_path / "plane.ply"
    yield e
    s.close()


def edited(s: Session) -> None:
    """Support, handle and one committed edit (G Z 0.2): unsaved work."""
    r = np.linalg.norm(s.cloud.positions[:, :2], axis=1)
    s.brush_target = SUPPORT
    s.end_stroke(s.paint(np.flatnonzero(r < 0.8)))
    s.brush_target = HANDLE
    s.end_stroke(s.paint(np.flatnonzero(r < 0.15)))
    assert s.wait_fit()
    assert s.begin(GRAB, view(), (100, 100))
    s.manip.set_axis(2)
    for ch in "0.2":
        s.manip.type_char(ch)
    assert s.finish() == "commit" and s.dirty


def key_event(k):
    return types.SimpleNamespace(kind="key", key=k, mods=0, action=glfw.PRESS, scancode=0)


def assert_recovered(ed, s, what):
    """The error box names ``what``; the recovery entry holds the document and its script."""
    assert ed.error_box is not None and f"internal error while {what}" in ed.error_box, ed.error_box
    assert "The document is kept" in ed.error_box
    got = recovery.entries()
    assert len(got) == 1, got
    e = got[0]
    assert e.edits == len(s.edits) == 1 and e.source == str(ed.path)
    back = read(str(e.model))
    assert np.array_equal(back.positions, s.cloud.positions) and np.array_equal(back.u, s.cloud.u)
    assert len(load_script(e.script).edits) == 1
    return e


def test_an_exception_in_a_key_handler_is_shown_the_document_kept_and_a_recovery_copy_written(ed, capsys):
    s = ed.session
    edited(s)
    cloud, edits = s.cloud, s.edits

    def broken():
        raise RuntimeError("boom in a handler")
    ed.actions[Action.COLOUR_MODE] = broken
    ed.window.events = [key_event(glfw.KEY_M), key_event(glfw.KEY_2)]
    ed.loop_once()
    assert s.cloud is cloud and s.edits == edits                     # the document is kept
    assert s.brush_target == HANDLE                                 # the next event was handled
    assert_recovered(ed, s, "running 'colour_mode'")
    assert "RuntimeError: boom in a handler" in capsys.readouterr().err    # the traceback on stderr
    assert ed.frames.drawn == 1                                     # the loop went on to draw
    # the same error again: no second recovery copy of the same state, the window stays
    ed.window.events = [key_event(glfw.KEY_M)]
    ed.loop_once()
    assert len(recovery.entries()) == 1 and ed.crash_guard.internal_errors == 2


def test_an_exception_in_an_event_handler_outside_the_actions_is_caught(ed):
    s = ed.session
    edited(s)

    def broken(e):
        raise ValueError("bad scroll")
    ed.routing.on_scroll = broken
    ed.window.events = [types.SimpleNamespace(kind="scroll", dx=0.0, dy=1.0, mods=0, x=1.0, y=1.0),
                        key_event(glfw.KEY_2)]
    ed.loop_once()
    assert_recovered(ed, s, "handling a scroll event")
    assert s.brush_target == HANDLE


def test_an_exception_in_a_commit_cancels_the_move_and_keeps_the_document(ed, monkeypatch):
    """The issue's crash: the commit of a typed move raised (AttributeError in
    the Gaussian transport); now the move is cancelled, the edits stay."""
    s = ed.session
    edited(s)
    cloud, edits = s.cloud, s.edits
    import splatedit.app.document.commit_job as cj

    def broken(*a, **k):
        raise AttributeError("'DetailBasis' object has no attribute 'displacements'")
    monkeypatch.setattr(cj, "commit_cloud", broken)
    assert s.wait_fit()
    ed.window.events = [key_event(k) for k in (glfw.KEY_G, glfw.KEY_X, glfw.KEY_1, glfw.KEY_ENTER)]
    ed.loop_once()
    assert s.manip is None and s.cloud is cloud and s.edits == edits
    assert_recovered(ed, s, "running '")


def test_exceptions_landing_a_job_polling_the_session_and_drawing_are_caught(ed, monkeypatch):
    s = ed.session
    edited(s)
    cloud = s.cloud
    # a finished job whose landing fails (the viewport cannot take its result)
    job = Job("levels of detail", lambda progress: object(), None, sync=True)
    ed.jobs["lod"] = job
    ed.loop_once()
    assert "lod" not in ed.jobs and ed.frames.drawn == 1
    e = assert_recovered(ed, s, "collecting a finished job")
    # the session's poll (fits and background commits landing)
    with monkeypatch.context() as m:
        m.setattr(s, "poll", lambda: 1 / 0)
        ed.dismiss_error()
        ed.loop_once()
    assert "internal error while landing a fit or an edit" in ed.error_box and ed.frames.drawn == 2
    # a frame
    ed.dismiss_error()
    ed.frames.fail = KeyError("frame")
    ed.loop_once()
    assert "internal error while drawing a frame" in ed.error_box
    assert ed.frames.scene_key == "scene"         # the failed scene is not redrawn at once
    assert s.cloud is cloud and recovery.entries() == [e]   # one copy per document state
    # another edit, another error: its copy replaces this run's older one
    ed.dismiss_error()
    ed.frames.fail = None
    assert s.begin(GRAB, view(), (100, 100))
    s.manip.type_char("1")
    assert s.finish() == "commit"
    ed.actions[Action.COLOUR_MODE] = lambda: [][0]
    ed.window.events = [key_event(glfw.KEY_M)]
    ed.loop_once()
    (e2,) = recovery.entries()
    assert e2 != e and e2.edits == 2 and not e.model.exists()


def test_sigterm_or_ctrl_c_with_unsaved_edits_writes_a_recovery_copy(ed):
    s = ed.session
    edited(s)

    def interrupted(timeout):
        raise KeyboardInterrupt
    ed.window.poll = interrupted
    ed.file_actions.start_load = lambda: None
    with pytest.raises(KeyboardInterrupt):
        ed.run()
    (e,) = recovery.entries()
    assert e.edits == 1 and "SIGTERM" in e.reason


def test_nothing_unsaved_writes_no_recovery_copy(ed):
    ed.actions[Action.COLOUR_MODE] = lambda: [][0]
    ed.window.events = [key_event(glfw.KEY_M)]
    ed.loop_once()
    assert "internal error" in ed.error_box and recovery.entries() == []


def test_the_next_start_offers_the_copy_restore_adopts_its_edits_discard_removes_it(ed, tmp_path):
    s = ed.session
    edited(s)
    e = ed.crash_guard.write_recovery("test")
    other = StubEditor(Session(plane_cloud(), fit_sync=True))
    try:
        assert other.crash_guard.offer_recovery() and other.crash_guard.confirm_restore == e and other.modal()
        # Esc: asked again next time (kept)
        other.routing.on_key(key_event(glfw.KEY_ESCAPE))
        assert other.crash_guard.confirm_restore is None and recovery.entries() == [e]
        # Y: restore -- the recovered model opens (a load job), its edits become the document's
        opened = []
        other.file_actions.open_path = lambda p, confirmed=False: opened.append(p) or True
        assert other.crash_guard.offer_recovery()
        other.routing.on_key(key_event(glfw.KEY_Y))
        assert opened == [e.model] and other.crash_guard.restoring == e
        other.session = Session(read(str(e.model)), fit_sync=True)       # what the load job lands
        other.crash_guard.on_restored()
        r = other.session
        assert len(r.edits) == 1 and r.dirty and other.path == ed.path and other.crash_guard.restored == e
        assert r.edit_script().edits == load_script(e.script).edits
        other.crash_guard.restored_saved(r)       # saving it removes the entry
        assert recovery.entries() == []
        # N: discard
        e2 = ed.crash_guard.write_recovery("again") or recovery.write_recovery(s, ed.path)
        assert other.crash_guard.offer_recovery()
        other.routing.on_key(key_event(glfw.KEY_N))
        assert recovery.entries() == [] and not e2.model.exists()
    finally:
        other.session.close()


def test_recovery_folder_follows_the_xdg_state_home(monkeypatch, tmp_path):
    monkeypatch.delenv(recovery.RECOVERY_DIR_ENV, raising=False)
    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path / "st"))
    assert recovery.recovery_dir() == tmp_path / "st" / "splatedit" / "recovery"
    monkeypatch.delenv("XDG_STATE_HOME")
    assert str(recovery.recovery_dir()).endswith(".local/state/splatedit/recovery")
