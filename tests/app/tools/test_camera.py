"""The camera tool's framing area: the window minus the side panel's column
and the menu bar (Home / F frame into it)."""

from __future__ import annotations

import pytest

from splatedit.app.tools.camera import free_area
from splatedit.tolerances import EDITOR_FRAME_MIN_FREE_FRACTION, EDITOR_GUI_PANEL_WIDTH

W, H = 960, 600


def test_left_panel_leaves_the_window_right_of_its_column_below_the_menu():
    x0, y0, x1, y1 = free_area(W, H, (8, 27, EDITOR_GUI_PANEL_WIDTH, 120), top=19)
    assert (x0 * W, y0 * H, x1 * W, y1 * H) == pytest.approx((8 + EDITOR_GUI_PANEL_WIDTH, 19, W, H))


def test_right_panel_leaves_the_window_left_of_it():
    px = W - 8 - EDITOR_GUI_PANEL_WIDTH
    x0, y0, x1, y1 = free_area(W, H, (px, 27, EDITOR_GUI_PANEL_WIDTH, 500))
    assert (x0 * W, y0, x1 * W, y1) == pytest.approx((0, 0, px, 1))


def test_no_panel_or_a_panel_leaving_too_little_is_the_whole_window():
    assert free_area(W, H, None) == (0.0, 0.0, 1.0, 1.0)
    narrow = int(W * (1 - EDITOR_FRAME_MIN_FREE_FRACTION)) + 4      # leaves under the minimum
    assert free_area(W, H, (0, 20, narrow, 300))[::2] == (0.0, 1.0)
