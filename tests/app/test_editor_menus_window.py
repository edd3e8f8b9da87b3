"""The menu bar and the questions in the real window (Xvfb + xdotool): a
menu closed with Esc hands the next stroke to the brush (the first stroke
paints); File > Open recent opens a model through the same path as Ctrl+O
(the unsaved-changes question first), File > Open... shows the browser, and
the questions (open without saving, quit) answer to clicks on their buttons."""

from __future__ import annotations

import pytest

from tests.app.sessions import plane_cloud
from tests.app.test_editor_files_window import _edit_bunny
from tests.app.window_harness import EditorProcess, _foreground_centre

pytestmark = [pytest.mark.window, pytest.mark.gpu, pytest.mark.slow]
pytest.importorskip("imgui_bundle")


def _stroke(ed, cx, cy):
    ed.xdo("mousemove", cx - 30, cy, "mousedown", "1", "mousemove", cx - 10, cy, "mousemove", cx + 10, cy,
           "mousemove", cx + 30, cy, "sleep", "0.1", "mouseup", "1")


def test_the_first_stroke_after_a_menu_closed_with_esc_paints(xvfb, tmp_path):
    ed = EditorProcess(xvfb, tmp_path)
    try:
        s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0 and "menu_file" in s["gui_rects"],
                    "model loaded", 90)
        cx, cy = _foreground_centre(ed.screenshot(), s["panel_box"])
        for menu in ("menu_file", "menu_edit"):
            x, y, w, h = s["gui_rects"][menu]
            ed.xdo("mousemove", x + w // 2, y + h // 2, "click", "1")
            s = ed.idle(lambda s: s["gui_menu_open"], f"{menu} opened")
            before = s["support"]
            ed.xdo("key", "Escape")
            s = ed.idle(lambda s: not s["gui_menu_open"], "Esc closes the menu")
            _stroke(ed, cx, cy)
            s = ed.idle(lambda s: s["support"] > before, "the first stroke paints", 20)
            cy += 25
        assert s["validation_messages"] == 0
    finally:
        ed.close()


def _click_rect(ed, name: str, what: str) -> dict:
    s = ed.wait(lambda s: name in s.get("gui_rects", {}), what)
    x, y, w, h = s["gui_rects"][name]
    ed.xdo("mousemove", x + w // 2, y + h // 2, "sleep", "0.2", "click", "1")
    return s


def _open_recent_0(ed) -> None:
    _click_rect(ed, "menu_file", "menu bar")
    _click_rect(ed, "menu_recent", "File menu open")
    s = _click_rect(ed, "recent_0", "Open recent submenu open")
    assert "recent_clear" in s["gui_rects"]


def test_file_menu_open_recent_asks_first_and_the_questions_have_buttons(xvfb, tmp_path):
    from splatedit.app.ui.recent import RecentFiles
    from splatedit.io import write
    plane = tmp_path / "plane.ply"
    write(str(plane), plane_cloud(40))
    RecentFiles().add(plane)                 # the test's private config (XDG_CONFIG_HOME)
    ed = EditorProcess(xvfb, tmp_path)
    try:
        ed.wait(lambda s: s["loaded"] and s["browser"] is not None, "recent files offered", 90)
        ed.xdo("key", "Escape")                  # the bunny instead
        s = ed.idle(lambda s: s["browser"] is None and s["frames_presented"] > 0, "bunny shown")
        bunny_n = s["n"]
        s = _edit_bunny(ed, s)
        # --- File > Open recent > plane.ply: the unsaved-changes question; its "keep editing" button
        _open_recent_0(ed)
        s = ed.wait(lambda s: s["confirm_open"] == str(plane), "asks about unsaved changes")
        _click_rect(ed, "question_no", "question's buttons")
        s = ed.idle(lambda s: s["confirm_open"] is None, "kept editing")
        assert s["n"] == bunny_n and s["dirty"] and s["edits"] == 1
        # --- the quit question's buttons: keep editing
        ed.xdo("key", "q")
        ed.wait(lambda s: s["confirm_quit"], "asks before quitting")
        _click_rect(ed, "question_no", "quit question's buttons")
        s = ed.idle(lambda s: not s["confirm_quit"], "quit cancelled")
        assert s["running"] and s["dirty"]
        # --- again, and "open without saving"
        _open_recent_0(ed)
        ed.wait(lambda s: s["confirm_open"] == str(plane), "asks again")
        _click_rect(ed, "question_yes", "question's buttons")
        s = ed.idle(lambda s: s["n"] == 1600 and s["path"] == str(plane), "plane opened", 60)
        assert not s["dirty"] and s["edits"] == 0
        # --- File > Open...: the browser, in the model's folder
        _click_rect(ed, "menu_file", "menu bar")
        _click_rect(ed, "menu_open", "File menu open")
        s = ed.wait(lambda s: s["browser"] is not None, "browser shown")
        assert s["browser"]["folder"] == str(tmp_path)
        ed.xdo("key", "Escape")
        s = ed.idle(lambda s: s["browser"] is None, "browser closed")
        assert s["validation_messages"] == 0
    finally:
        ed.close()


def test_the_panel_footer_stays_visible_when_the_panel_is_taller_than_the_window(xvfb, tmp_path):
    """All sections open with a support and a handle (the panel's full height
    is more than the 600-pixel window): the panel ends inside the window, its
    footer (status line, frame time, hint) is at its bottom, fully shown, and
    the sections above scroll."""
    ed = EditorProcess(xvfb, tmp_path)
    try:
        s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0, "model loaded", 90)
        s = _edit_bunny(ed, s)
        ed.xdo("key", "ctrl+s")
        s = ed.idle(lambda s: s["saved"] and "panel_footer" in s["gui_rects"] and s["message"].startswith("saved"),
                    "saved")

        def footer_inside(s):
            px, py, pw, ph = s["panel_box"]
            fx, fy, fw, fh = s["gui_rects"]["panel_footer"]
            return fy + fh <= py + ph
        # a longer status line (the saved path wraps) grows the footer: the next frame lays it out
        s = ed.wait(footer_inside, "the footer laid out inside the panel", 10)
        w, h = s["window"]
        px, py, pw, ph = s["panel_box"]
        fx, fy, fw, fh = s["gui_rects"]["panel_footer"]
        assert py + ph <= h                                # nothing below the window's edge
        assert py < fy and fy + fh <= py + ph and fh >= 3 * 12     # message, frame time and hint
        assert fx >= px and fx + fw <= px + pw
        assert s["gui_panel_scrolls"]                      # the sections are taller than the room left
        assert s["validation_messages"] == 0
    finally:
        ed.close()
