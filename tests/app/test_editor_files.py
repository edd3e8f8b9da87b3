"""Opening another model in the editor without a window: Ctrl+O shows the
browser, a picked file loads in the background and replaces the model, with
unsaved changes the editor asks first (Y opens, N keeps), a file that cannot
be read shows an error box and the old model stays, a dropped file opens
the same way, and a loaded model goes first in the recent files."""

from __future__ import annotations

import types

import numpy as np
import pytest

from splatedit.app.view.camera_control import OrbitCamera
from splatedit.app.editor import Editor
from splatedit.app.document.session import Session
from splatedit.io import write
from splatedit.app.document.manipulation import GRAB
from tests.app.sessions import plane_cloud, view
from tests.app.document.test_session import paint_regions

glfw = pytest.importorskip("glfw")
W, H = 800, 600


class _Viewport(types.SimpleNamespace):
    def set_cloud(self, cloud):
        self.cloud = cloud

    def set_pyramid(self, p):
        self.pyramid = p

    def set_gaussian_lod(self, lod):
        self.gs_lod = lod


class StubEditor(Editor):
    size = (W, H)

    def __init__(self, session, path):
        self.path, self.bundled, self.use_lod = path, False, False
        self.method, self.tol, self.max_centers = "auto", 1e-6, None
        self.save_as = None
        self._init_state(OrbitCamera(np.zeros(3), 4.0, yaw=0.6, pitch=0.5, scene_radius=1.5), glfw)
        self.window = types.SimpleNamespace(set_title=lambda t: setattr(self, "title", t),
                                            post_empty_event=lambda: None)
        self.session = session
        self.viewport = _Viewport(grey=False, splat_scale=1.0, distortion_map=False, dc=None, cloud=None,
                                  ms_per_splat=None, pyramid="old levels")
        self.messages = []

    def say(self, text):
        self.messages.append(text)

    def settle(self):
        """Wait for the jobs (load, graph) and collect them."""
        for j in list(self.jobs.values()):
            assert j.wait(30)
        self.file_actions.poll_jobs()


def key(ed, k, mods=0):
    ed.routing.on_key(types.SimpleNamespace(key=k, mods=mods, action=glfw.PRESS))


@pytest.fixture
def models(tmp_path):
    """A folder with two models of different sizes, a sub-folder, a text file and a hidden model."""
    d = tmp_path / "scans"
    (d / "sub").mkdir(parents=True)
    write(str(d / "a_plane.ply"), plane_cloud(20))
    write(str(d / "b_plane.ply"), plane_cloud(12))
    write(str(d / ".hidden.ply"), plane_cloud(5))
    (d / "notes.md").write_text("not a model")
    (d / "broken.ply").write_text("ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n")
    return d


@pytest.fixture
def ed(models):
    s = Session(plane_cloud(20), fit_sync=True)
    e = StubEditor(s, models / "a_plane.ply")
    yield e
    if e.session is not None:
        e.session.close()


def test_ctrl_o_lists_only_models_and_folders_and_enter_opens_one(ed, models):
    key(ed, glfw.KEY_O, glfw.MOD_CONTROL)
    b = ed.browser
    assert b.shown and b.folder == models
    names = [(e.kind.value, e.name) for e in b.entries]
    assert names == [("parent", ".."), ("folder", "sub"), ("file", "a_plane.ply"), ("file", "b_plane.ply"),
                     ("file", "broken.ply")]
    assert b.selected.name == "a_plane.ply"      # the first model, not ".."
    key(ed, glfw.KEY_DOWN)
    assert b.selected.name == "b_plane.ply"
    old = ed.session
    key(ed, glfw.KEY_ENTER)
    assert not b.shown and "load" in ed.jobs
    ed.settle()
    assert ed.session is not old and ed.session.cloud.n == 12 * 12
    assert ed.path == models / "b_plane.ply" and ed.cloud_name == "b_plane.ply"
    assert ed.viewport.cloud is ed.session.cloud and ed.viewport.pyramid is None
    assert ed.file_actions.recent_files() == [models / "b_plane.ply"]
    assert ed.title.endswith("b_plane.ply")


def test_typing_jumps_backspace_goes_up_and_enter_enters_folders(ed, models):
    ed.file_actions.open_dialog()
    b = ed.browser
    for ch in "B_":
        ed.routing.on_char(types.SimpleNamespace(char=ch))
    assert b.selected.name == "b_plane.ply" and b.typed == "B_"
    key(ed, glfw.KEY_BACKSPACE)
    key(ed, glfw.KEY_BACKSPACE)          # deletes the typed text first ...
    assert b.typed == "" and b.folder == models
    key(ed, glfw.KEY_BACKSPACE)          # ... then goes up, with the folder left selected
    assert b.folder == models.parent and b.selected.path == models
    key(ed, glfw.KEY_ENTER)
    assert b.folder == models
    for ch in "sub":
        ed.routing.on_char(types.SimpleNamespace(char=ch))
    key(ed, glfw.KEY_ENTER)
    assert b.folder == models / "sub" and [e.name for e in b.entries] == [".."]
    key(ed, glfw.KEY_ESCAPE)
    assert not b.shown and "load" not in ed.jobs


def test_a_click_on_a_row_picks_it(ed, models):
    ed.file_actions.open_dialog()
    b = ed.browser
    b.overlay(W, H)                      # the layout of the drawn list
    i = [e.name for e in b.entries].index("b_plane.ply")
    x = b.box[0] + 20
    y = b.row0 + (i - b.top) * b.line_h + b.line_h / 2
    assert b.row_at(x, y) == i and b.row_at(b.box[0] - 5, y) is None
    ed.routing.on_button(types.SimpleNamespace(x=x, y=y, button=glfw.MOUSE_BUTTON_LEFT, mods=0, action=glfw.PRESS))
    assert not b.shown and ed.jobs["load"].key == models / "b_plane.ply"
    ed.settle()


def test_unsaved_changes_ask_first(ed, models):
    s = ed.session
    paint_regions(s)
    assert s.wait_fit() and s.begin(GRAB, view(), (100, 100))
    s.manip.set_axis(2)
    for ch in "0.3":
        s.manip.type_char(ch)
    assert s.commit() and s.dirty
    target = models / "b_plane.ply"
    assert not ed.file_actions.open_path(target)
    assert ed.confirm_open == target and "load" not in ed.jobs and ed.modal()
    key(ed, glfw.KEY_N)
    assert ed.confirm_open is None and ed.session is s and "load" not in ed.jobs
    ed.file_actions.open_path(target)
    key(ed, glfw.KEY_Y)
    ed.settle()
    assert ed.session is not s and ed.session.cloud.n == 144


@pytest.mark.parametrize("name,needle", [("broken.ply", "broken.ply"), ("missing.ply", "no such file"),
                                         ("notes.md", "unsupported file extension")])
def test_an_unreadable_file_shows_an_error_box_and_keeps_the_model(ed, models, name, needle, capsys):
    s = ed.session
    ed.file_actions.open_path(models / name)
    ed.settle()
    assert ed.session is s and ed.path == models / "a_plane.ply"
    assert ed.error_box is not None and needle in ed.error_box
    assert f"splatedit: error: " in capsys.readouterr().err
    assert ed.file_actions.recent_files() == []
    key(ed, glfw.KEY_ESCAPE)               # Esc closes the box first
    assert ed.error_box is None


def test_a_dropped_file_opens_and_a_dropped_folder_is_browsed(ed, models):
    ed.routing.on_drop(types.SimpleNamespace(paths=(str(models / "sub"),)))
    assert ed.browser.shown and ed.browser.folder == models / "sub"
    ed.routing.on_drop(types.SimpleNamespace(paths=(str(models / "b_plane.ply"), str(models / "a_plane.ply"))))
    assert not ed.browser.shown
    ed.settle()
    assert ed.session.cloud.n == 144 and any("only b_plane.ply" in m for m in ed.messages)


def test_recent_files_come_first_in_the_browser(ed, models):
    ed.file_actions.open_path(models / "b_plane.ply")
    ed.settle()
    ed.file_actions.open_dialog(models / "sub")
    b = ed.browser
    assert [(e.kind.value, e.name) for e in b.entries[:2]] == [("recent", "b_plane.ply"), ("parent", "..")]
    key(ed, glfw.KEY_ENTER)              # the recent file is selected first
    assert ed.jobs["load"].key == models / "b_plane.ply"
    ed.settle()


def test_a_failed_save_shows_an_error_box(ed, tmp_path, capsys):
    ed.file_actions.save(tmp_path / "no-such-folder" / "out.ply")
    ed.settle()
    assert ed.error_box is not None and "saving failed" in ed.error_box and "no-such-folder" in ed.error_box
    assert "splatedit: error: saving failed" in capsys.readouterr().err
    assert ed.error_rect is None
    from splatedit.app.ui.panel import error_box
    (patch,) = error_box(ed, W, H, 8)          # drawn: a click inside it closes it
    assert ed.error_rect == patch.box
    x, y, bw, bh = ed.error_rect
    ed.routing.on_button(types.SimpleNamespace(x=x + bw / 2, y=y + bh / 2, button=glfw.MOUSE_BUTTON_LEFT, mods=0,
                                       action=glfw.PRESS))
    assert ed.error_box is None


def test_ctrl_o_during_a_move_cancels_the_move(ed):
    s = ed.session
    paint_regions(s)
    assert s.wait_fit() and s.begin(GRAB, view(), (100, 100))
    key(ed, glfw.KEY_O, glfw.MOD_CONTROL)
    assert ed.browser.shown and s.manip is None and not s.dirty


def test_a_typed_path_that_matches_no_entry_is_opened_as_typed(ed, models):
    ed.file_actions.open_dialog(models / "sub")
    for ch in "../b_plane.ply":
        ed.routing.on_char(types.SimpleNamespace(char=ch))
    key(ed, glfw.KEY_ENTER)
    assert not ed.browser.shown and ed.jobs["load"].key == models / "b_plane.ply"
    ed.settle()
    assert ed.session.cloud.n == 144
    ed.file_actions.open_dialog(models / "sub")
    for ch in "../nothing.ply":
        ed.routing.on_char(types.SimpleNamespace(char=ch))
    key(ed, glfw.KEY_KP_ENTER)
    assert "load" not in ed.jobs and "no such file" in ed.error_box


def test_a_newly_opened_model_gets_a_fresh_default_view_for_its_own_up_axis(ed, models):
    """The old model's orbit angle (yaw 0.6, pitch 0.5 here) is not inherited:
    a Z-up LAS opens at the first-open view about Z (yaw = pitch = 0), framed."""
    from splatedit.io import read
    las = models / "plane.las"
    cloud = read(str(models / "b_plane.ply"))
    # the plane is z = const: as a LAS (Z-up by format) it is a ground plane
    write(str(las), cloud)
    ed.cam.screen_offset = (0.3, -0.2)
    ed.file_actions.open_path(las)
    ed.settle()
    assert ed.path == las and ed.camera.up.label.endswith("Z")
    cam = ed.cam
    assert cam.yaw == 0.0 and cam.pitch == 0.0
    assert np.allclose(cam.up_axis, [0, 0, 1])
    # framed: the model's centre is on screen in the framed area and the camera looks along the ground
    lo, hi = ed.session.cloud.bounds()
    _, _, back = cam.basis()
    assert abs(back @ [0, 0, 1]) < 1e-9
    px, depth = cam.project((lo + hi) / 2, W, H)
    assert depth[0] > 0 and 0 < px[0, 0] < W and 0 < px[0, 1] < H


def _chars(ed, text):
    """Type ``text`` as a window does: each character's key press, then its character event."""
    for ch in text:
        code = getattr(glfw, f"KEY_{ch.upper()}", glfw.KEY_SLASH if ch == "/" else glfw.KEY_PERIOD)
        key(ed, code)
        ed.routing.on_char(types.SimpleNamespace(char=ch))


def test_save_as_prompt_backspace_deletes_one_character_and_typing_appends(ed, models, tmp_path):
    """The proposed path is edited, not replaced: Backspace x3 and "las" turn
    the suggested .ply into .las; Ctrl+A selects all (typing replaces it,
    Backspace clears it); Ctrl+U and Ctrl+Backspace clear; Esc cancels."""
    from splatedit.app.ui.panel import save_prompt_lines
    key(ed, glfw.KEY_S, glfw.MOD_CONTROL | glfw.MOD_SHIFT)
    proposed = ed.prompt
    assert proposed == str(models / "a_plane-edited.ply")
    key(ed, glfw.KEY_BACKSPACE)
    assert ed.prompt == proposed[:-1]
    key(ed, glfw.KEY_BACKSPACE)
    key(ed, glfw.KEY_BACKSPACE)
    _chars(ed, "las")
    assert ed.prompt == str(models / "a_plane-edited.las")
    rows = save_prompt_lines(ed)
    assert rows[1] == ed.prompt + "_" and "Ctrl+A" in rows[2] and "Ctrl+U" in rows[2]
    key(ed, glfw.KEY_A, glfw.MOD_CONTROL)                   # select all: typing replaces
    assert ed.prompt_selected and ed.prompt in save_prompt_lines(ed)[1]
    _chars(ed, "/tmp/x.ply")
    assert ed.prompt == "/tmp/x.ply" and not ed.prompt_selected
    key(ed, glfw.KEY_A, glfw.MOD_CONTROL)                   # select all, Backspace clears
    key(ed, glfw.KEY_BACKSPACE)
    assert ed.prompt == ""
    _chars(ed, "abc")
    key(ed, glfw.KEY_U, glfw.MOD_CONTROL)
    assert ed.prompt == ""
    _chars(ed, "abc")
    key(ed, glfw.KEY_BACKSPACE, glfw.MOD_CONTROL)
    assert ed.prompt == ""
    _chars(ed, "abc")
    key(ed, glfw.KEY_ESCAPE)
    assert ed.prompt is None and "save" not in ed.jobs


def test_ctrl_s_with_no_edits_says_so_instead_of_writing_a_copy(ed, models):
    paint_regions(ed.session)                       # a selection only: no edit
    key(ed, glfw.KEY_S, glfw.MOD_CONTROL)
    assert ed.messages[-1] == "nothing to save (no edits)"
    assert "save" not in ed.jobs and ed.save_as is None
    assert not (models / "a_plane-edited.ply").exists()
    s = ed.session
    assert s.wait_fit() and s.begin(GRAB, view(), (100, 100))
    s.manip.set_axis(2)
    for ch in "0.3":
        s.manip.type_char(ch)
    assert s.commit()
    key(ed, glfw.KEY_S, glfw.MOD_CONTROL)           # an edit: saved
    ed.settle()
    assert (models / "a_plane-edited.ply").exists() and not s.dirty
    key(ed, glfw.KEY_S, glfw.MOD_CONTROL)           # again, nothing new: not written twice
    assert ed.messages[-1].startswith("nothing to save (no changes since it was saved to a_plane-edited.ply")
    assert "save" not in ed.jobs
