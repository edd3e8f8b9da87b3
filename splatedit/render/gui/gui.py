"""Dear ImGui drawn by our own Vulkan pipeline (no platform window of ImGui's own).

Why imgui-bundle: it is the maintained Python binding of Dear ImGui (immediate-
mode widgets: windows, buttons, sliders, text fields, tables, file dialogs)
with manylinux wheels; we use only its core ``imgui`` module and none of its
renderer/platform backends (they need OpenGL), because splatedit draws with
its own Vulkan device.  The API we rely on (imgui-bundle 1.93, Dear ImGui 1.92):

* ``imgui.create_context`` / ``set_current_context`` / ``destroy_context``;
  ``io.display_size``, ``io.delta_time``, the ``io.add_*_event`` input calls
  (see :mod:`splatedit.render.gui.input`), ``io.want_capture_mouse`` /
  ``want_capture_keyboard``;
* ``imgui.render()`` then ``imgui.get_draw_data()``: each draw list's
  ``vtx_buffer`` / ``idx_buffer`` expose ``data_address()`` and ``size()``
  (ImDrawVert = 20 bytes; ImDrawIdx is 32-bit in imgui-bundle, told apart by
  the vector's class, ``ImVector_uint``), each ``cmd_buffer`` entry its
  ``clip_rect``, ``elem_count``, ``idx_offset``, ``vtx_offset`` and
  ``get_tex_id()``;
* the ``renderer_has_textures`` backend flag: ImGui asks the renderer to
  create / update / destroy textures (the font atlas, which grows as new glyphs
  are used) through ``draw_data.textures[i]`` (``status``, ``width``,
  ``height``, ``format``, ``get_pixels_array()``, ``updates``,
  ``unused_frames``, ``set_tex_id``, ``set_status``).  Those requests are
  carried out here on a :class:`~splatedit.render.gui.painter.GuiPainter`
  before the frame's draws are recorded; ``renderer_has_vtx_offset`` lets a
  frame exceed 65536 vertices with 16-bit indices.

Use (one frame)::

    gui = Gui(device)                      # any core.Device (the renderer's, the presenter's)
    for ev in window.poll():
        captured = gui.feed(ev)            # True: the editor ignores ev
    gui.new_frame(width, height, dt)       # framebuffer pixels, seconds
    imgui.begin("Panel"); imgui.button("OK"); imgui.end()
    gui.render(cmd, framebuffer, fmt="bgra8", final="present")   # after the splat passes

``render`` records into a command buffer (the frame's own, so the GUI is drawn
on the GPU into the image that is presented); ``framebuffer`` must be made with
``gui.painter.render_pass(fmt)`` (or any pass of the same format).  Each
:class:`Gui` owns its ImGui context; every method makes it current first.

``python -m splatedit.render.gui.demo --demo`` opens a window with a small panel
(:mod:`splatedit.render.gui.demo`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from imgui_bundle import imgui

from splatedit.render.gui import input as gui_input
from splatedit.render.gui.painter import GuiDraw, GuiPainter


@dataclass(frozen=True)
class GuiFrameStats:
    """What the last :meth:`Gui.render` recorded."""
    vertices: int
    indices: int
    draws: int                  # vkCmdDrawIndexed calls (after scissor culling)
    textures_created: int
    textures_updated: int
    textures_destroyed: int


class Gui:
    """An ImGui context drawn with a :class:`GuiPainter` on ``device``.

    Args:
        device: a :class:`splatedit.render.vk.Device`.
        cache: a PipelineCache to share (default: the painter's own).
        ini_path: where ImGui keeps window positions (default: nowhere, so
            tests and the demo do not write ``imgui.ini`` into the working dir).
        font_scale: global font scale (``style.font_scale_main``).
    """

    def __init__(self, device, cache=None, *, ini_path: str | None = None, font_scale: float = 1.0):
        self.painter = GuiPainter(device, cache)
        self._closed = False
        self._in_frame = False
        try:
            self.ctx = imgui.create_context()
            imgui.set_current_context(self.ctx)
            io = imgui.get_io()
            io.set_ini_filename(ini_path)
            io.backend_flags |= (imgui.BackendFlags_.renderer_has_textures.value
                                 | imgui.BackendFlags_.renderer_has_vtx_offset.value)
            if font_scale != 1.0:
                imgui.get_style().font_scale_main = float(font_scale)
        except BaseException:
            self.painter.destroy()
            raise
        self.io = io
        self.last_stats = GuiFrameStats(0, 0, 0, 0, 0, 0)

    # ---------------------------------------------------------------- input
    def make_current(self):
        """Make this GUI's ImGui context the current one (several GUIs may
        exist); returns its ImGui IO."""
        if self._closed:
            raise RuntimeError("the GUI has been closed")
        imgui.set_current_context(self.ctx)
        return self.io

    def feed(self, ev) -> bool:
        """Give ImGui one window event; True when ImGui claims it (see :mod:`gui_input`)."""
        io = self.make_current()
        gui_input.feed_event(io, ev)
        return gui_input.wants_event(io, ev)

    @property
    def wants_mouse(self) -> bool:
        """The pointer is over a GUI window or ImGui is dragging: mouse events are ImGui's."""
        return bool(self.make_current().want_capture_mouse)

    @property
    def wants_keyboard(self) -> bool:
        """A GUI widget has keyboard focus (e.g. a text field): keys are ImGui's."""
        return bool(self.make_current().want_capture_keyboard)

    # ---------------------------------------------------------------- frame
    def new_frame(self, width: int, height: int, dt: float) -> None:
        """Start a frame for a ``width`` x ``height`` pixel target; ``dt`` seconds since the last."""
        io = self.make_current()
        if self._in_frame:
            self.discard_frame()
        io.display_size = (float(width), float(height))
        io.delta_time = float(dt) if dt > 0 else 1e-4       # ImGui asserts delta_time > 0
        imgui.new_frame()
        self._in_frame = True

    def discard_frame(self) -> None:
        """End a frame that will not be drawn (e.g. the window is minimized)."""
        self.make_current()
        if self._in_frame:
            imgui.end_frame()
            self._in_frame = False

    def recover_frame(self) -> None:
        """End a frame left unbalanced by an exception in the middle of its
        layout (a window's ``begin`` without ``end``): ImGui's own error
        recovery closes what was left open (logged, not asserted), so the
        next :meth:`new_frame` starts clean."""
        io = self.make_current()
        if not self._in_frame:
            return
        assert_on = io.config_error_recovery_enable_assert
        tooltip_on = io.config_error_recovery_enable_tooltip
        io.config_error_recovery_enable_assert = False
        io.config_error_recovery_enable_tooltip = False
        try:
            imgui.end_frame()
        finally:
            io.config_error_recovery_enable_assert = assert_on
            io.config_error_recovery_enable_tooltip = tooltip_on
            self._in_frame = False

    def render(self, cmd, framebuffer, *, fmt: str, clear=None, final: str = "color") -> GuiFrameStats:
        """End the frame (``imgui.render``), apply ImGui's texture requests,
        upload the geometry and record the GUI pass into ``cmd`` (see
        :meth:`GuiPainter.record` for ``clear``/``final``)."""
        self.make_current()
        if not self._in_frame:
            raise RuntimeError("Gui.render() without Gui.new_frame()")
        imgui.render()
        self._in_frame = False
        dd = imgui.get_draw_data()
        created, updated, destroyed = self._apply_texture_requests(dd)
        lists, draws, index_bytes = _geometry(dd, framebuffer.width, framebuffer.height)
        self.painter.upload(lists, index_bytes)
        dw, dh = dd.display_size.x, dd.display_size.y
        scale = (2.0 / dw if dw > 0 else 0.0, 2.0 / dh if dh > 0 else 0.0)
        translate = (-1.0 - dd.display_pos.x * scale[0], -1.0 - dd.display_pos.y * scale[1])
        n = self.painter.record(cmd, framebuffer, draws, scale=scale, translate=translate, fmt=fmt,
                                clear=clear, final=final)
        self.last_stats = GuiFrameStats(int(dd.total_vtx_count), int(dd.total_idx_count), n,
                                        created, updated, destroyed)
        return self.last_stats

    def render_into(self, cmd, target, *, clear=None, final: str = "present") -> GuiFrameStats:
        """:meth:`render` into ``target``, an image-like render target with a
        ``framebuffer(render_pass)`` method and a ``format`` name (a swapchain
        image in :meth:`SwapchainPresenter.render_frame`)."""
        fb = target.framebuffer(self.painter.render_pass(target.format))
        return self.render(cmd, fb, fmt=target.format, clear=clear, final=final)

    def _apply_texture_requests(self, dd) -> tuple[int, int, int]:
        S = imgui.ImTextureStatus
        created = updated = destroyed = 0
        for i in range(len(dd.textures)):
            tex = dd.textures[i]
            st = tex.status
            if st == S.want_create:
                tid = self.painter.create_texture(_texels(tex))
                tex.set_tex_id(tid)
                tex.set_status(S.ok)
                created += 1
            elif st == S.want_updates:
                pixels = _texels(tex)
                rects = [tex.updates[k] for k in range(len(tex.updates))] or [tex.update_rect]
                for r in rects:
                    x, y, w, h = int(r.x), int(r.y), int(r.w), int(r.h)
                    self.painter.update_texture(int(tex.tex_id), x, y, pixels[y:y + h, x:x + w])
                tex.set_status(S.ok)
                updated += 1
            elif st == S.want_destroy and tex.unused_frames > 0:
                # unused by the previous frame, which has finished (frame contract of GuiPainter)
                self.painter.destroy_texture(int(tex.tex_id))
                tex.set_tex_id(0)
                tex.set_status(S.destroyed)
                destroyed += 1
        return created, updated, destroyed

    # ---------------------------------------------------------------- teardown
    def close(self) -> None:
        """Destroy the textures ImGui holds, the painter and the context (idempotent).
        The device must be idle (no frame using the GUI in flight)."""
        if self._closed:
            return
        imgui.set_current_context(self.ctx)
        if self._in_frame:
            imgui.end_frame()
            self._in_frame = False
        pio = imgui.get_platform_io()
        for i in range(len(pio.textures)):
            tex = pio.textures[i]
            if tex.tex_id:
                tex.set_tex_id(0)
                tex.set_status(imgui.ImTextureStatus.destroyed)
        self.painter.destroy()
        imgui.destroy_context(self.ctx)
        self._closed = True

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _texels(tex) -> np.ndarray:
    """(h, w, 4) uint8 RGBA texels of an ImTextureData (alpha8 -> white with alpha)."""
    px = np.asarray(tex.get_pixels_array(), dtype=np.uint8)
    h, w = int(tex.height), int(tex.width)
    if tex.format == imgui.ImTextureFormat.alpha8:
        out = np.empty((h, w, 4), np.uint8)
        out[..., :3] = 255
        out[..., 3] = px.reshape(h, w)
        return out
    return px.reshape(h, w, 4)


def _geometry(dd, fb_w: int, fb_h: int):
    """Draw lists' buffers as (address, count) pairs and the frame's GuiDraws
    (scissor rectangles in framebuffer pixels, clamped to the target)."""
    ox, oy = dd.display_pos.x, dd.display_pos.y
    sx, sy = dd.framebuffer_scale.x, dd.framebuffer_scale.y
    lists, draws = [], []
    vbase = ibase = 0
    index_bytes = 4
    for li in range(len(dd.cmd_lists)):
        cl = dd.cmd_lists[li]
        index_bytes = _index_bytes(cl.idx_buffer)
        nv, ni = cl.vtx_buffer.size(), cl.idx_buffer.size()
        lists.append((cl.vtx_buffer.data_address(), nv, cl.idx_buffer.data_address(), ni))
        for ci in range(len(cl.cmd_buffer)):
            c = cl.cmd_buffer[ci]
            if c.elem_count == 0:
                continue
            r = c.clip_rect
            x0 = max(0.0, (r.x - ox) * sx)
            y0 = max(0.0, (r.y - oy) * sy)
            x1 = min(float(fb_w), (r.z - ox) * sx)
            y1 = min(float(fb_h), (r.w - oy) * sy)
            if x1 <= x0 or y1 <= y0:
                continue
            xi, yi = int(x0), int(y0)
            clip = (xi, yi, int(np.ceil(x1)) - xi, int(np.ceil(y1)) - yi)
            draws.append(GuiDraw(texture=int(c.get_tex_id()), clip=clip, index_count=int(c.elem_count),
                                 first_index=ibase + int(c.idx_offset), vertex_offset=vbase + int(c.vtx_offset)))
        vbase += nv
        ibase += ni
    return lists, draws, index_bytes


#: ImDrawIdx width by the class of the binding's index vector
_INDEX_VECTORS = {"ImVector_uint": 4, "ImVector_ImU32": 4, "ImVector_ushort": 2, "ImVector_ImU16": 2}


def _index_bytes(vec) -> int:
    name = type(vec).__name__
    try:
        return _INDEX_VECTORS[name]
    except KeyError:
        raise TypeError(f"unknown ImDrawIdx vector type {name} (imgui-bundle built with another "
                        "index type?)") from None
