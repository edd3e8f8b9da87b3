"""Dear ImGui drawn by our Vulkan GUI pipeline (splatedit.render.gui.gui), headless on lavapipe.

A frame with a window, text, a button, a slider and a clipped fill is drawn
over a known background in an offscreen RGBA8 target and read back: flat
areas have the style's colours, glyph pixels exist inside the text item,
nothing outside the window changes, scissor rectangles cut draws exactly.
Validation messages fail tests through tests/conftest.py.
"""

from __future__ import annotations

import numpy as np
import pytest

imgui = pytest.importorskip("imgui_bundle").imgui

from splatedit import tolerances as tol  # noqa: E402
from splatedit.render import vk as V  # noqa: E402
from splatedit.render.gui.gui import Gui  # noqa: E402
from splatedit.render.vk.resources import Buffer, readback_array  # noqa: E402
from splatedit.render.vk.window import InputEvent  # noqa: E402

pytestmark = pytest.mark.gpu

W, H = 480, 360
BACKGROUND = (0.2, 0.4, 0.6, 1.0)
BG8 = np.array([51, 102, 153])          # BACKGROUND in 8-bit UNORM


class Target:
    """An offscreen RGBA8 target with a GUI, rendered and read back per frame."""

    def __init__(self, dev):
        self.dev = dev
        self.img = V.Image(dev, W, H, "rgba8", ("color", "transfer_src"))
        self.gui = Gui(dev)
        self.fb = V.Framebuffer(dev, self.gui.painter.render_pass("rgba8"), [self.img], W, H)
        self.buf = Buffer(dev, W * H * 4, ("transfer_dst",), host_visible=True)

    def frame(self, build, events=()):
        """Feed ``events``, build widgets with ``build()``, draw over the background; (pixels, stats)."""
        for ev in events:
            self.gui.feed(ev)
        self.gui.new_frame(W, H, 1 / 60)
        info = build()
        out = {}

        def rec(cb):
            # the background as the splat passes would leave it, then the GUI pass loads it
            self.gui.painter.record(cb, self.fb, [], scale=(0, 0), translate=(0, 0), fmt="rgba8",
                                    clear=BACKGROUND, final="color")
            out["stats"] = self.gui.render(cb, self.fb, fmt="rgba8", final="transfer_src")
            cb.copy_image_to_buffer(self.img, self.buf)
            cb.host_read_barrier()
        self.dev.submit(rec)
        px = readback_array(self.buf.read(), "rgba8", W, H)[..., :3].astype(int)
        return px, out["stats"], info

    def close(self):
        self.buf.destroy()
        self.fb.destroy()
        self.gui.close()
        self.img.destroy()


@pytest.fixture(scope="module")
def device():
    dev = V.Device()
    yield dev
    dev.close()


@pytest.fixture
def target(device):
    t = Target(device)
    yield t
    t.close()


CLIP = (300, 200, 40, 30)      # x, y, w, h of the scissor test (inside the window)


def panel():
    """Window at (40, 30) 400x280: text, button, slider, then a red fill larger than its clip rect."""
    imgui.set_next_window_pos((40, 30))
    imgui.set_next_window_size((400, 280))
    imgui.begin("Panel")
    imgui.text("Hello splats")
    text = imgui.get_item_rect_min(), imgui.get_item_rect_max()
    imgui.button("Click me")
    button = imgui.get_item_rect_min(), imgui.get_item_rect_max()
    imgui.slider_float("size", 0.25, 0.0, 1.0)
    last = imgui.get_item_rect_max()
    x, y, w, h = CLIP
    dl = imgui.get_window_draw_list()
    dl.push_clip_rect((x, y), (x + w, y + h), True)
    dl.add_rect_filled((x - 50, y - 50), (x + w + 50, y + h + 50), imgui.get_color_u32(imgui.ImVec4(1, 0, 0, 1)))
    dl.pop_clip_rect()
    pos, size = imgui.get_window_pos(), imgui.get_window_size()
    imgui.end()
    rect = lambda a, b: (int(a.x), int(a.y), int(b.x), int(b.y))  # noqa: E731
    return {"window": (int(pos.x), int(pos.y), int(pos.x + size.x), int(pos.y + size.y)),
            "text": rect(*text), "button": rect(*button), "last_y": int(last.y)}


def _over(col: imgui.ImVec4, under: np.ndarray) -> np.ndarray:
    """An ImGui style colour (converted to 8 bits as ImGui does) blended over ``under``."""
    c8 = np.array([int(v * 255 + 0.5) for v in (col.x, col.y, col.z, col.w)])
    a = c8[3] / 255.0
    return a * c8[:3] + (1 - a) * under


def test_panel_colours_text_background_and_scissor(target):
    target.frame(panel)                           # first frame: fonts uploaded, window laid out
    px, stats, info = target.frame(panel)
    assert stats.draws >= 2 and stats.vertices > 100
    x0, y0, x1, y1 = info["window"]
    assert (x0, y0, x1, y1) == (40, 30, 440, 310)
    style = imgui.get_style()
    # the window background below the widgets (border, resize grip and the red fill left out)
    win_bg = _over(style.color_(imgui.Col_.window_bg), BG8)
    body = px[info["last_y"] + 6: CLIP[1] - 4, x0 + 5: x1 - 5]
    assert body.size > 3 * 5000
    assert np.abs(body - win_bg).max() <= tol.GUI_COLOUR_TOL, (body.reshape(-1, 3).min(0), win_bg)
    # the button's face has the button colour (over the window background)
    bx0, by0, bx1, by1 = info["button"]
    face = px[by0 + 1: by1 - 1, bx0 + 1: bx0 + 3]           # the frame padding left of the label
    assert np.abs(face - _over(style.color_(imgui.Col_.button), win_bg)).max() <= tol.GUI_COLOUR_TOL
    # glyphs inside the text item: bright pixels, a real word's worth of them
    tx0, ty0, tx1, ty1 = info["text"]
    text = px[ty0:ty1, tx0:tx1].mean(axis=2)
    glyph = text > win_bg.mean() + tol.GUI_TEXT_CONTRAST
    assert glyph.sum() >= 60 and text.max() >= 200, glyph.sum()
    # ... and none in the blank window area right of the text
    right = px[ty0:ty1, tx1 + 4: x1 - 5].mean(axis=2)
    assert (right > win_bg.mean() + tol.GUI_TEXT_CONTRAST).sum() == 0
    # nothing outside the window's rectangle changed
    outside = np.ones((H, W), bool)
    outside[y0:y1, x0:x1] = False
    assert (px[outside] == BG8).all()
    # the red fill, 50 px larger than its clip rectangle all round, covers the clip rectangle exactly
    red = (px[..., 0] == 255) & (px[..., 1] == 0) & (px[..., 2] == 0)
    ys, xs = np.nonzero(red)
    cx, cy, cw, ch = CLIP
    assert (xs.min(), ys.min(), xs.max() + 1, ys.max() + 1) == (cx, cy, cx + cw, cy + ch)
    assert red.sum() == cw * ch


def test_gui_over_partly_offscreen_window_is_clipped_to_target(target):
    """A window hanging off the right/bottom edge: scissors clamp to the target, no errors."""
    def build():
        imgui.set_next_window_pos((W - 100, H - 60))
        imgui.set_next_window_size((300, 200))
        imgui.begin("Off")
        imgui.text("partly outside")
        imgui.end()
    target.frame(build)
    px, stats, _ = target.frame(build)
    assert stats.draws >= 1
    assert (px[: H - 60, : W - 100] == BG8).all()
    assert (px[H - 50:, W - 95:] != BG8).any(axis=2).mean() > 0.9


def test_texture_requests_create_update_destroy(target):
    """Text at new sizes grows the font atlas: ImGui asks for new textures,
    updates and destroys of the old ones; the painter follows them exactly."""
    seen = {"created": 0, "updated": 0, "destroyed": 0}
    for size in (13, 13, 60, 60, 120, 120, 13):
        def build(size=size):
            imgui.set_next_window_pos((10, 10))
            imgui.begin("Fonts")
            imgui.push_font(None, float(size))
            imgui.text("Splats 0123456789")
            imgui.pop_font()
            imgui.end()
        _, stats, _ = target.frame(build)
        seen["created"] += stats.textures_created
        seen["updated"] += stats.textures_updated
        seen["destroyed"] += stats.textures_destroyed
        live = {tid for tid in target.gui.painter.textures}
        pio = imgui.get_platform_io()
        wanted = {int(pio.textures[i].tex_id) for i in range(len(pio.textures))
                  if pio.textures[i].status != imgui.ImTextureStatus.destroyed and pio.textures[i].tex_id}
        assert wanted <= live
    assert seen["created"] >= 2 and seen["updated"] >= 1 and seen["destroyed"] >= 1, seen
    assert len(target.gui.painter.textures) == seen["created"] - seen["destroyed"]
    # the last frame's text (size 13 again) is drawn with the grown atlas
    px, _, _ = target.frame(build)
    assert (px[10:60, 10:200] != BG8).any(axis=2).sum() > 500


def test_no_leaks_and_buffers_reused(device):
    base = V.live_handles()
    for _ in range(3):
        t = Target(device)
        for _ in range(3):
            t.frame(panel)
        t.close()
        assert V.live_handles() == base
    t = Target(device)
    try:
        t.frame(panel)
        t.frame(panel)
        handles, allocs = V.live_handles(), t.gui.painter.buffer_allocations
        for _ in range(10):
            t.frame(panel)
        assert V.live_handles() == handles
        assert t.gui.painter.buffer_allocations == allocs == 2     # one vertex + one index buffer
    finally:
        t.close()
    assert V.live_handles() == base


def test_input_events_click_button_and_type(target):
    """glfw-style events fed through Gui.feed click a button and type into a
    field; wants_mouse / wants_keyboard follow the pointer and the focus."""
    state = {"clicks": 0, "text": ""}

    def build():
        imgui.set_next_window_pos((40, 30))
        imgui.set_next_window_size((300, 150))
        imgui.begin("Input")
        if imgui.button("Press"):
            state["clicks"] += 1
        mn, mx = imgui.get_item_rect_min(), imgui.get_item_rect_max()
        _, state["text"] = imgui.input_text("note", state["text"])
        fmn, fmx = imgui.get_item_rect_min(), imgui.get_item_rect_max()
        imgui.end()
        return ((mn.x + mx.x) / 2, (mn.y + mx.y) / 2), ((fmn.x + fmx.x) / 2 - 40, (fmn.y + fmx.y) / 2)

    _, _, (btn, field) = target.frame(build)
    _, _, _ = target.frame(build, [InputEvent("move", x=btn[0], y=btn[1])])
    assert target.gui.wants_mouse
    target.frame(build, [InputEvent("button", button=0, action=1, x=btn[0], y=btn[1])])
    target.frame(build, [InputEvent("button", button=0, action=0, x=btn[0], y=btn[1])])
    assert state["clicks"] == 1
    # outside every window: the mouse is the editor's
    target.frame(build, [InputEvent("move", x=W - 5, y=H - 5)])
    target.frame(build)
    assert not target.gui.wants_mouse and not target.gui.wants_keyboard
    captured = target.gui.feed(InputEvent("button", button=0, action=1, x=W - 5, y=H - 5))
    assert not captured
    target.frame(build, [InputEvent("button", button=0, action=0, x=W - 5, y=H - 5)])
    # click the text field, type "abc", backspace: "ab"; the keyboard is ImGui's meanwhile
    target.frame(build, [InputEvent("move", x=field[0], y=field[1]),
                         InputEvent("button", button=0, action=1, x=field[0], y=field[1])])
    target.frame(build, [InputEvent("button", button=0, action=0, x=field[0], y=field[1])])
    target.frame(build, [InputEvent("char", char=c) for c in "abc"])
    assert target.gui.wants_keyboard
    assert target.gui.feed(InputEvent("key", key=259, action=1))       # GLFW_KEY_BACKSPACE
    target.frame(build)
    target.frame(build, [InputEvent("key", key=259, action=0)])
    assert state["text"] == "ab"
    assert state["clicks"] == 1


def test_key_table_covers_editor_keys():
    from splatedit.render.gui.input import imgui_key
    K = imgui.Key
    assert imgui_key(65) == K.a and imgui_key(90) == K.z and imgui_key(48) == K._0
    assert imgui_key(256) == K.escape and imgui_key(257) == K.enter and imgui_key(335) == K.keypad_enter
    assert imgui_key(321) == K.keypad1 and imgui_key(290) == K.f1 and imgui_key(301) == K.f12
    assert imgui_key(-1) == K.none and imgui_key(999) == K.none
