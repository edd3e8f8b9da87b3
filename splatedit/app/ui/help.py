"""The editor's help window in Dear ImGui (F1): the keymap's help lines
(:func:`splatedit.app.ui.keymap.help_lines`) in a window sized to the space
beside the side panel, or to the whole window when that is too narrow (the
panel steps aside until the help closes).  The :class:`~splatedit.app.ui.panel.HelpView`
keeps the scroll position in lines, so PageDown / PageUp and the arrows
(keymap actions) and the wheel or the scroll bar (ImGui) move the same view."""

from __future__ import annotations

from imgui_bundle import imgui

from splatedit.app.ui.panel import PANEL_MARGIN, Box
from splatedit.tolerances import EDITOR_GUI_HELP_MIN_WIDTH

BLUE = imgui.ImVec4(0.55, 0.75, 1.0, 1.0)
YELLOW = imgui.ImVec4(1.0, 0.9, 0.47, 1.0)


def help_area(g, w: int, h: int) -> tuple[Box, bool]:
    """(where the help goes, whether it covers the panel's place) in a ``w`` x
    ``h`` pixel window; ``g``: the :class:`~splatedit.app.ui.gui_panels.EditorGui`."""
    m = PANEL_MARGIN
    top = int(g.menu_height) + m
    pb = g.panel_box
    if g.ed.panel_visible and pb is not None:
        if pb.x <= m:                                   # panel on the left: the help to its right
            area = Box(pb.right + m, top, w - pb.right - 2 * m, h - top - m)
        else:
            area = Box(m, top, pb.x - 2 * m, h - top - m)
        if area.w >= EDITOR_GUI_HELP_MIN_WIDTH:
            return area, False
    return Box(m, top, w - 2 * m, h - top - m), g.ed.panel_visible


def draw_help(g, w: int, h: int) -> None:
    """The help window of ``g`` (an EditorGui) when it is shown; keeps
    ``g.help_box`` and the HelpView's rows / top / box up to date."""
    hv = g.ed.help
    if not hv.shown:
        g.help_box = None
        return
    area, covers = help_area(g, w, h)
    hv.covers_panel = covers
    imgui.set_next_window_pos(imgui.ImVec2(area.x, area.y), imgui.Cond_.always)
    imgui.set_next_window_size(imgui.ImVec2(max(area.w, 100), max(area.h, 80)), imgui.Cond_.always)
    flags = (imgui.WindowFlags_.no_move.value | imgui.WindowFlags_.no_resize.value
             | imgui.WindowFlags_.no_collapse.value | imgui.WindowFlags_.no_scrollbar.value)
    imgui.begin("Help (F1 / Esc: close)###help", None, flags)
    lh = imgui.get_text_line_height_with_spacing()
    foot = imgui.get_frame_height_with_spacing()
    avail = imgui.get_content_region_avail()
    # lines wider than the window get a horizontal scroll bar, inside the lines' child window:
    # room for it below the rows, or it would hide the last row (the help's last line at the end)
    bar = imgui.get_style().scrollbar_size
    if g.help_width is None:
        g.help_width = max(imgui.calc_text_size(text).x for text, _ in hv.lines)
    wide = g.help_width > avail.x - bar          # (the vertical bar takes its width when paged)
    hv.rows = max(int((avail.y - foot - (bar if wide else 0.0)) // lh), 1)
    child_h = hv.rows * lh + (bar if wide else 0.0)
    imgui.begin_child("help_lines", imgui.ImVec2(-1, child_h), 0,
                      imgui.WindowFlags_.horizontal_scrollbar.value)
    # what the rows' area really shows (status and tests: every paged row is visible)
    shown_h = child_h - (bar if imgui.get_scroll_max_x() > 0 else 0.0)
    g.help_visible_rows = int((shown_h + 0.5) // lh)
    sy = imgui.get_scroll_y()
    if g.help_scroll_set is not None and abs(sy - g.help_scroll_set) > 0.5:
        hv.top = int(round(sy / lh))            # the wheel or the scroll bar moved it
    hv.scroll(0)
    target = hv.top * lh
    if abs(sy - target) > 0.5:
        imgui.set_scroll_y(target)
    g.help_scroll_set = target
    for text, title in hv.lines:
        if title:
            imgui.text_colored(BLUE, text)
        else:
            imgui.text(text)
    imgui.end_child()
    end = min(hv.top + hv.rows, hv.total)
    more = "PageDown / PageUp, arrows or wheel: scroll   " if hv.rows < hv.total else ""
    imgui.text_colored(YELLOW, f"lines {hv.top + 1}-{end} of {hv.total}   {more}")
    pos, size = imgui.get_window_pos(), imgui.get_window_size()
    g.help_box = Box(int(pos.x), int(pos.y), int(size.x), int(size.y))
    hv.box = g.help_box
    g.windows.append(g.help_box)
    imgui.end()
