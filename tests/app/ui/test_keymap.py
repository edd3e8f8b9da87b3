"""The one keymap: the manual's controls list (docs/editor.md) is generated from it, every bound
action has a handler in the editor, no chord is bound twice, and the help
the window shows comes from the same table."""

from __future__ import annotations

import types
from pathlib import Path

import pytest

from splatedit.app.ui import keymap
from splatedit.app.ui.keymap import KEYMAP, Action, Chord, Context, Section

README = Path(__file__).resolve().parents[3] / "docs" / "editor.md"


def test_readme_controls_are_the_generated_block():
    block = keymap.readme_controls(README.read_text())
    assert block is not None, "README lacks the controls markers"
    assert block == keymap.readme_block(), \
        "docs/editor.md's controls list is out of date: run `python -m splatedit.app.ui.keymap --write-readme`"


def test_write_readme_fixes_a_stale_list(tmp_path):
    text = README.read_text()
    stale = "".join(line for line in text.splitlines(True) if not line.startswith("  Home    "))
    assert stale != text
    p = tmp_path / "README.md"
    p.write_text(stale)
    assert keymap.write_readme(p) and keymap.readme_controls(p.read_text()) == keymap.readme_block()
    assert not keymap.write_readme(p)               # a second run changes nothing


def _stub_editor():
    from splatedit.app.view.camera_control import OrbitCamera
    from splatedit.app.editor import Editor

    class Stub(Editor):
        size = (640, 480)

        def __init__(self):
            self.path, self.window = None, None
            self._init_state(OrbitCamera(), types.SimpleNamespace())
    return Stub()


def test_every_bound_action_has_a_handler():
    ed = _stub_editor()
    handled = set(ed.actions) | set(ed.manip_actions) | {Action.TYPE_VALUE}
    bound = {b.action for b in KEYMAP if b.keys}
    assert bound - handled == set()
    manip_bound = {b.action for b in KEYMAP if b.keys and b.context is Context.MANIP}
    assert manip_bound - set(ed.manip_actions) - {Action.TYPE_VALUE, Action.DISTORTION_MAP} == set()


def test_no_chord_is_bound_twice_in_one_context():
    seen = {}
    for b in KEYMAP:
        for ch in b.chords:
            key = (ch, b.context)
            assert seen.get(key, b.action) is b.action, f"{ch} in {b.context}: {seen[key]} and {b.action}"
            seen[key] = b.action
    pytest.importorskip("glfw")
    keymap._TABLE = None
    assert len(keymap._table()) == len(seen)        # every key name resolves to a glfw key


def test_lookup_respects_modifiers_and_context_order():
    g = pytest.importorskip("glfw")
    idle, manip = [Context.IDLE, Context.ANY], [Context.MANIP, Context.ANY]
    assert keymap.lookup(g.KEY_Z, True, False, idle) is Action.UNDO
    assert keymap.lookup(g.KEY_Z, True, True, idle) is Action.REDO
    assert keymap.lookup(g.KEY_Z, False, False, manip) is Action.AXIS_Z
    assert keymap.lookup(g.KEY_Z, False, False, idle) is None
    assert keymap.lookup(g.KEY_1, False, False, idle) is Action.BRUSH_SUPPORT
    assert keymap.lookup(g.KEY_1, False, False, manip) is Action.TYPE_VALUE
    assert keymap.lookup(g.KEY_ESCAPE, False, False, [Context.HELP] + idle) is Action.HELP_CLOSE
    assert keymap.lookup(g.KEY_ESCAPE, False, False, idle) is Action.CANCEL
    assert keymap.lookup(g.KEY_KP_1, True, False, idle) is Action.VIEW_BACK
    assert keymap.lookup(g.KEY_Q, False, False, [Context.ANY]) is Action.QUIT
    assert keymap.typed_char(g.KEY_KP_5) == "5" and keymap.typed_char(g.KEY_COMMA) == "."


def test_help_has_every_section_and_each_tool_documents_itself():
    lines = keymap.help_lines()
    titles = [t for t, is_title in lines if is_title]
    for s in Section:
        assert s.value.split("\n")[0] in titles
    text = keymap.help_text()
    for needle in ("Numpad 1 / 3 / 7", "PageDown", "P                      hide / show the panel",
                   "M ", "Shift+[ / Shift+]", "distance / angle / factor", "Esc never quits"):
        assert needle in text, needle
    ed = _stub_editor()
    for tool in ed.tools:
        entries = tool.help_entries()
        assert entries and all(b.section is tool.section for b in entries)


def test_chord_parsing():
    assert Chord.parse("ctrl+shift+z") == Chord("Z", True, True)
    assert Chord.parse("kp_1") == Chord("KP_1")
    with pytest.raises(ValueError):
        Chord.parse("hyper+z")
