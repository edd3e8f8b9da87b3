"""The editor's centred questions in the Dear ImGui interface: restoring a
recovery copy at start (:mod:`splatedit.app.crash_guard`), unsaved changes
before opening another model or quitting, and the save-as path.

Each has its keys (Y / N / Esc, Enter / Esc; :mod:`splatedit.app.ui.routing`)
and clickable buttons that call the same handlers
(:meth:`~splatedit.app.file_actions.FileActions.answer_open`,
:meth:`~splatedit.app.file_actions.FileActions.answer_quit`,
:meth:`~splatedit.app.file_actions.FileActions.prompt_key`).  The buttons'
rectangles are recorded as ``question_yes`` / ``question_no`` (window tests
click them)."""

from __future__ import annotations

from imgui_bundle import imgui

from splatedit.app.ui.panel import Box, open_question, restore_question, save_prompt_lines

YELLOW = imgui.ImVec4(1.0, 0.9, 0.47, 1.0)


def _buttons(ed) -> tuple | None:
    """(rows, (yes label, yes callback), (no label, no callback)) of the open question, or None."""
    g = ed.g
    restore = restore_question(ed)
    if restore is not None:
        return (restore, ("Restore (Y)", lambda: ed.crash_guard.answer_restore(True)),
                ("Discard (N)", lambda: ed.crash_guard.answer_restore(False)))
    if ed.confirm_open is not None:
        name = ed.confirm_open.name
        return (open_question(ed), (f"Open {name} without saving (Y)", lambda: ed.file_actions.answer_open(True)),
                ("Keep editing (N / Esc)", lambda: ed.file_actions.answer_open(False)))
    if ed.confirm_quit:
        return (("Unsaved changes.", "Y / Q: quit without saving     N / Esc: keep editing", "(Ctrl+S saves)"),
                ("Quit without saving (Y)", lambda: ed.file_actions.answer_quit(True)),
                ("Keep editing (N / Esc)", lambda: ed.file_actions.answer_quit(False)))
    if ed.prompt is not None:
        return (save_prompt_lines(ed), ("Save (Enter)", lambda: ed.file_actions.prompt_key(g.KEY_ENTER)),
                ("Cancel (Esc)", lambda: ed.file_actions.prompt_key(g.KEY_ESCAPE)))
    return None


def draw_question(gui, w: int, h: int) -> None:
    """Draw the open question (if any) in the window's centre; its window
    takes the clicks over it (``gui.windows``), its buttons answer it."""
    q = _buttons(gui.ed)
    if q is None:
        return
    rows, yes, no = q
    imgui.set_next_window_pos(imgui.ImVec2(w / 2, h / 2), imgui.Cond_.always, imgui.ImVec2(0.5, 0.5))
    imgui.set_next_window_bg_alpha(0.95)
    imgui.begin("##question", None, imgui.WindowFlags_.no_decoration.value
                | imgui.WindowFlags_.always_auto_resize.value | imgui.WindowFlags_.no_saved_settings.value)
    imgui.text_colored(YELLOW, rows[0])
    for t in rows[1:]:
        imgui.text(t)
    clicked = None
    if imgui.button(yes[0]):
        clicked = yes[1]
    gui.rect("question_yes")
    imgui.same_line()
    if imgui.button(no[0]):
        clicked = no[1]
    gui.rect("question_no")
    p, s = imgui.get_window_pos(), imgui.get_window_size()
    gui.windows.append(Box(int(p.x), int(p.y), int(s.x), int(s.y)))
    imgui.end()
    if clicked is not None:
        clicked()
