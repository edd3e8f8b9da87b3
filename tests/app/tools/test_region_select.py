"""Box / lasso selection, select all and mirror through the editor's keys and
mouse (no window: the editor's routing on a flat grid of splats seen from
an oblique camera), and the region geometry on its own."""

from __future__ import annotations

import types

import numpy as np
import pytest

from splatedit.app.tools.pick_brush import BrushPicker
from splatedit.app.document.session import Session
from splatedit.app.tools.region import box_polygon, polygon_mask, splats_through, splats_visible
from splatedit.select.selection import HANDLE, SUPPORT
from tests.app.sessions import plane_cloud
from tests.app.ui.test_editor_routing import StubEditor, key, press

glfw = pytest.importorskip("glfw")


@pytest.fixture
def ed():
    s = Session(plane_cloud(), fit_sync=True)
    yield StubEditor(s)
    s.close()


def drag(ed, pts, mods=0):
    press(ed, glfw.MOUSE_BUTTON_LEFT, mods, *pts[0])
    for x, y in pts[1:]:
        ed.routing.on_move(types.SimpleNamespace(x=float(x), y=float(y)))
    press(ed, glfw.MOUSE_BUTTON_LEFT, mods, *pts[-1], action=glfw.RELEASE)


def inside(ed, poly):
    w, h = ed.size
    px, depth = ed.cam.project(ed.session.cloud.positions, w, h)
    return splats_through(polygon_mask(poly, w, h), px, depth)


def test_polygon_mask_is_the_even_odd_interior_of_pixel_centres():
    m = polygon_mask(box_polygon((2, 3), (6, 5)), 10, 8)
    assert m.sum() == 4 * 2 and m[3:5, 2:6].all()
    tri = polygon_mask(np.array([[0, 0], [100, 0], [0, 100]]), 100, 100)
    assert abs(int(tri.sum()) - 5000) <= 100            # half the square
    # a loop crossing itself (a bow tie) keeps both lobes, not the crossing's outside
    bow = polygon_mask(np.array([[0, 0], [40, 40], [40, 0], [0, 40]]), 50, 50)
    assert bow[20, 5] and bow[20, 35] and not bow[5, 20]
    assert not polygon_mask(np.array([[0, 0], [5, 5]]), 10, 10).any()


def test_visible_region_takes_the_pick_map_and_visible_sub_pixel_centres_only():
    pick = np.full((20, 20), -1)
    pick[5:10, 5:10] = 7
    centers = np.array([[12.5, 12.5], [3.5, 3.5]], float)
    pick[12, 12] = 0                                     # splat 0 is drawn on its own pixel
    bp = BrushPicker(pick, np.vstack([centers, np.zeros((6, 2)) - 50]), np.ones(8), np.zeros(8))
    mask = polygon_mask(box_polygon((0, 0), (15, 15)), 20, 20)
    # splat 1's centre is on background (no front surface): not visible; splat 7 from the pick map
    assert splats_visible(mask, bp).tolist() == [0, 7]
    assert splats_visible(polygon_mask(box_polygon((0, 0), (8, 8)), 20, 20), bp).tolist() == [7]


def test_box_select_adds_every_centre_inside_through_and_is_one_undo_step(ed):
    s = ed.session
    steps = s.history.position
    key(ed, glfw.KEY_B, glfw.MOD_CONTROL)
    assert ed.region.armed == "box"
    drag(ed, [(250, 180), (300, 220), (390, 300)])
    want = inside(ed, box_polygon((250, 180), (390, 300)))
    assert len(want) > 20
    assert s.selection.support[want].all()
    # closure may round the region off (holes, back sides) but takes nothing far outside
    assert s.selection.support.sum() <= 1.2 * len(want)
    assert ed.region.armed is None
    assert s.history.position == steps + 1 and s.history.labels[-1] == "box select support"
    key(ed, glfw.KEY_Z, glfw.MOD_CONTROL)
    assert not s.selection.support.any()


def test_ctrl_lasso_erases_from_the_support_and_erased_splats_stay_out(ed):
    s = ed.session
    key(ed, glfw.KEY_A)                                  # select all
    assert s.selection.support.all()
    key(ed, glfw.KEY_B, glfw.MOD_CONTROL | glfw.MOD_SHIFT)
    assert ed.region.armed == "lasso"
    loop = [(260, 200), (380, 210), (370, 300), (280, 290), (260, 200)]
    drag(ed, loop, glfw.MOD_CONTROL)
    gone = inside(ed, np.array(loop, float))
    assert len(gone) > 10
    assert not s.selection.support[gone].any()
    assert s.selection.support.sum() == s.cloud.n - len(gone)


def test_box_select_paints_the_active_handle_inside_the_support_only(ed):
    s = ed.session
    n = s.cloud.n
    left = s.cloud.positions[:, 0] < 0
    s.set_selection(left, np.zeros(n, bool))
    key(ed, glfw.KEY_2)
    assert s.brush_target == HANDLE
    key(ed, glfw.KEY_B, glfw.MOD_CONTROL)
    drag(ed, [(0, 0), (640, 480)])
    assert (s.selection.handle == left).all()          # every support splat on screen, nothing else
    assert s.selection.support[left].all() and not (s.selection.handle & ~s.selection.support).any()


def test_right_click_cancels_an_armed_box_and_the_brush_paints_again(ed):
    key(ed, glfw.KEY_B, glfw.MOD_CONTROL)
    press(ed, glfw.MOUSE_BUTTON_RIGHT)
    assert ed.region.armed is None and ed.drag_tool is None
    key(ed, glfw.KEY_B, glfw.MOD_CONTROL)
    key(ed, glfw.KEY_B, glfw.MOD_CONTROL)                 # the key again disarms
    assert ed.region.armed is None
    ed.session.curve_mode = True
    key(ed, glfw.KEY_B, glfw.MOD_CONTROL | glfw.MOD_SHIFT)
    key(ed, glfw.KEY_ESCAPE)                              # Esc cancels the lasso, not the curve tool
    assert ed.region.armed is None and ed.session.curve_mode
    key(ed, glfw.KEY_ESCAPE)
    assert not ed.session.curve_mode


def test_the_region_outline_is_a_closed_shape_while_dragging(ed):
    key(ed, glfw.KEY_B, glfw.MOD_CONTROL)
    press(ed, glfw.MOUSE_BUTTON_LEFT, 0, 100, 100)
    ed.routing.on_move(types.SimpleNamespace(x=200.0, y=150.0))
    (shape,) = ed.region.shapes(640, 480)
    assert shape.closed and shape.strip().shape == (5, 2)
    from splatedit.app.tools.shapes import to_patches
    (patch,) = to_patches([shape], (640, 480))
    assert patch.rgba[..., 3].max() == 255 and patch.x <= 100 and patch.y <= 100
    press(ed, glfw.MOUSE_BUTTON_LEFT, 0, 200, 150, action=glfw.RELEASE)
    assert ed.region.shapes(640, 480) == []


def land_jobs(ed) -> None:
    """Wait for the editor's background jobs and collect them (as its loop does)."""
    for job in list(ed.jobs.values()):
        assert job.wait(60)
    ed.file_actions.poll_jobs()


def test_mirror_adds_the_mirror_image_across_the_middle_plane(ed):
    s = ed.session
    p = s.cloud.positions
    right = (p[:, 0] > 0.5) & (p[:, 1] > 0)
    s.set_selection(right, np.zeros(s.cloud.n, bool))
    key(ed, glfw.KEY_M, glfw.MOD_CONTROL)
    assert "mirror" in ed.jobs                      # a background job (the window keeps drawing)
    land_jobs(ed)
    left = (p[:, 0] < -0.5) & (p[:, 1] > 0)
    assert (s.selection.support == (right | left)).all()
    assert s.history.labels[-1] == "mirror support"
    key(ed, glfw.KEY_Z, glfw.MOD_CONTROL)
    assert (s.selection.support == right).all()


def test_symmetric_painting_paints_each_dab_and_its_mirror(ed):
    s = ed.session
    key(ed, glfw.KEY_M, glfw.MOD_SHIFT)
    assert ed.mirror.painting
    idx = np.flatnonzero(s.cloud.positions[:, 0] > 0.8)
    both = ed.mirror.with_mirror(idx)
    p = s.cloud.positions
    assert np.array_equal(both, np.flatnonzero(np.abs(p[:, 0]) > 0.8))
    key(ed, glfw.KEY_M, glfw.MOD_CONTROL | glfw.MOD_SHIFT)   # the plane's normal: Y
    assert ed.mirror.axis == 1


def test_the_select_menus_shortcuts_are_the_keymaps_keys():
    pytest.importorskip("imgui_bundle")
    from splatedit.app.ui.menus import _SELECT_ENTRIES
    from splatedit.app.ui.keymap import KEYMAP

    names = {"equal": "=", "minus": "-"}

    def shown(chord):
        key = names.get(chord.key.lower(), chord.key.capitalize() if len(chord.key) > 1 else chord.key)
        return ("Ctrl+" if chord.ctrl else "") + ("Shift+" if chord.shift else "") + key

    for entry in filter(None, _SELECT_ENTRIES):
        label, shortcut, action = entry
        keys = {shown(c) for b in KEYMAP if b.action is action for c in b.chords}
        assert shortcut in keys, (label, shortcut, keys)


def test_armed_tools_and_toggles_say_so_in_the_panel(ed):
    from splatedit.app.ui.panel import panel_lines
    ed.viewport.last_info = None

    def text():
        return " | ".join(x if isinstance(x, str) else x[0] for x in panel_lines(ed))
    assert "box select" not in text() and "symmetric" not in text() and "pivot:" not in text()
    key(ed, glfw.KEY_B, glfw.MOD_CONTROL)
    key(ed, glfw.KEY_M, glfw.MOD_SHIFT)
    key(ed, glfw.KEY_PERIOD)
    t = text()
    assert "box select: left drag (through" in t and "symmetric painting across X" in t
    assert "pivot: support rim" in t


def test_protocol_tools_register_themselves_and_use_only_their_context(ed):
    import inspect

    from splatedit.app.tools import protocol_tools
    names = [c.name for c in protocol_tools()]
    assert names == ["delete", "mirror", "pivot", "region"]
    for cls in protocol_tools():
        assert getattr(ed, cls.name).__class__ is cls and getattr(ed, cls.name) in ed.tools
        src = inspect.getsource(inspect.getmodule(cls))
        # on the protocol: the narrow context, no reach into the editor or its other tools
        assert "self.ed." not in src and "self.session" not in src, cls.__name__


def test_every_view_tool_is_on_the_protocol_and_draws_only_shapes(ed):
    """The built-in tools too (camera, curve, gizmo, brush): only the tool
    context (no ``ed.*`` reach-ins), and their overlays are shapes that one
    painter draws on both paths (no separate ``overlay`` / ``underlay``)."""
    import inspect

    from splatedit.app.tools.base import Tool
    for tool in ed.tools:
        src = inspect.getsource(inspect.getmodule(type(tool)))
        assert "self.ed" not in src and "self.session" not in src, type(tool).__name__
        assert not hasattr(tool, "overlay") and not hasattr(tool, "underlay"), type(tool).__name__
    assert not hasattr(Tool, "overlay") and not hasattr(Tool, "ed")


def test_a_mirror_whose_selection_changed_while_it_ran_changes_nothing(ed):
    """The mirror job works on a copy of the selection: when the selection
    changes before it lands (a stroke, an undo), its result is dropped and
    the status line says so; the selection is the changed one."""
    s = ed.session
    p = s.cloud.positions
    right = (p[:, 0] > 0.5) & (p[:, 1] > 0)
    s.set_selection(right, np.zeros(s.cloud.n, bool))
    key(ed, glfw.KEY_M, glfw.MOD_CONTROL)
    other = p[:, 1] < -0.5
    s.set_selection(other, np.zeros(s.cloud.n, bool))      # meanwhile
    positions = s.history.position
    land_jobs(ed)
    assert (s.selection.support == other).all() and s.history.position == positions
    assert "selection changed while it ran" in ed.messages[-1]


def test_a_mirror_landing_after_another_model_was_opened_touches_neither(ed):
    """The mirror job of the previous model lands after another model was
    opened: the new document's selection and history stay as they are, and
    nothing is recorded in the closed one."""
    s = ed.session
    p = s.cloud.positions
    s.set_selection((p[:, 0] > 0.5) & (p[:, 1] > 0), np.zeros(s.cloud.n, bool))
    old_len = len(s.history)
    key(ed, glfw.KEY_M, glfw.MOD_CONTROL)
    new = Session(plane_cloud(12), fit_sync=True)
    try:
        ed.session = new
        land_jobs(ed)
        assert not new.selection.support.any() and len(new.history) == 1
        assert len(s.history) == old_len
    finally:
        new.close()
