"""Panel placement and the F1 help window: the help fits any window size
(pages through every line), never covers the panel, and the panel never
covers the gizmo."""

from __future__ import annotations

import pytest

from splatedit.app.ui.keymap import help_lines
from splatedit.app.ui.panel import Box, HelpView, place_panel

#: the panel's size at the default window (measured: 598 x 206 px with a fitted handle)
PANEL = (598, 206)


def _visible_lines(win, panel):
    """Every help line index shown while paging from the top to the bottom."""
    hv = HelpView()
    hv.toggle()
    shown, tops = set(), []
    for _ in range(50):
        p = hv.patch(win, panel)
        assert p is not None
        tops.append(hv.top)
        shown.update(range(hv.top, hv.top + hv.rows))
        hv.page(1)
        if hv.top == tops[-1]:
            break
    return hv, shown, p


@pytest.mark.parametrize("win", [(1280, 720), (960, 600), (800, 560), (640, 400), (1920, 1080)])
def test_help_fits_the_window_pages_through_every_line_and_keeps_off_the_panel(win):
    w, h = win
    panel = place_panel(win, PANEL, None)
    hv, shown, patch = _visible_lines(win, panel)
    ph, pw = patch.rgba.shape[:2]
    assert 0 <= patch.x and patch.x + pw <= w and 0 <= patch.y and patch.y + ph <= h
    assert shown == set(range(len(help_lines())))          # "File and history" included
    if not hv.covers_panel:
        assert not panel.overlaps((patch.x, patch.y, patch.x + pw, patch.y + ph))
    else:                                                   # only when nothing else fits
        assert w < 700 or h < 450


def test_default_window_shows_the_help_beside_or_below_the_panel():
    hv, _, patch = _visible_lines((1280, 720), place_panel((1280, 720), PANEL, None))
    assert not hv.covers_panel and hv.rows >= 20


def test_page_and_scroll_stay_in_range():
    hv = HelpView()
    hv.toggle()
    hv.patch((1280, 720), None)
    hv.page(-1)
    assert hv.top == 0
    for _ in range(100):
        hv.scroll(3)
    assert hv.top == hv.total - hv.rows
    hv.toggle()
    hv.toggle()
    assert hv.top == 0


def test_panel_moves_off_the_gizmo():
    win = (1280, 720)
    assert place_panel(win, PANEL, None) == Box(8, 8, *PANEL)
    gizmo = (300.0, 100.0, 500.0, 300.0)                   # under the top-left panel
    b = place_panel(win, PANEL, gizmo)
    assert not b.overlaps(gizmo) and b.right <= win[0] and b.bottom <= win[1]
    assert place_panel(win, PANEL, (900.0, 500.0, 1000.0, 600.0)) == Box(8, 8, *PANEL)
