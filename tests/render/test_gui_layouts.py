"""The GUI pass and the pipeline code pack their GPU data through declared
layouts, with the bytes the hand packing they replaced wrote: the gui.vert
push constants (GUI_PUSH) as pushed while recording a real GUI frame, Dear
ImGui's own ImDrawVert memory read as GUI_VERTEX (the vertex attributes'
offsets come from it), and the specialization constants of a pipeline.  The
``_legacy_*`` functions are the previous packing code, kept as the reference."""

from __future__ import annotations

import ctypes
import struct

import numpy as np
import pytest
import vulkan as vk

from splatedit.render import vk as V
from splatedit.render.uniforms import GUI_PUSH, GUI_VERTEX
from splatedit.render.vk.commands import CommandBuffer
from splatedit.render.gui.painter import _VERTEX_ATTRIBUTES, VERTEX_BYTES, GuiDraw, GuiPainter, gui_push
from splatedit.render.vk.shaders import specialization

pytestmark = pytest.mark.gpu


def _legacy_gui_push(scale, translate) -> bytes:
    return np.array([scale[0], scale[1], translate[0], translate[1]], np.float32).tobytes()


def _legacy_specialization(spec) -> bytes:
    return struct.pack(f"<{len(spec)}i", *[v for _, v in spec])


def _transforms():
    """(scale, translate) as Gui.render makes them: 2 / display size and
    -1 - display_pos * scale, for display sizes and offsets of real windows."""
    out = []
    for (w, h), (ox, oy) in (((480, 360), (0, 0)), ((1920, 1080), (0, 0)), ((1366, 768), (-40.5, 12.25)),
                             ((1, 1), (3000.0, -2000.0))):
        s = (2.0 / w, 2.0 / h)
        out.append((s, (-1.0 - ox * s[0], -1.0 - oy * s[1])))
    return out + [((0.0, 0.0), (0.0, 0.0))]


def test_gui_push_bytes_equal_the_hand_packing():
    for scale, translate in _transforms():
        rec = gui_push(scale, translate)
        assert rec.dtype == GUI_PUSH and rec.nbytes == 16
        assert rec.tobytes() == _legacy_gui_push(scale, translate)


def test_recorded_gui_pass_pushes_the_hand_packed_bytes(monkeypatch):
    """Record the GUI pass of a small frame (one triangle) on the device and
    compare the bytes handed to vkCmdPushConstants."""
    pushed = []
    real = CommandBuffer.push_constants

    def spy(self, pipeline, data):
        pushed.append(np.ascontiguousarray(data).tobytes())
        return real(self, pipeline, data)
    monkeypatch.setattr(CommandBuffer, "push_constants", spy)
    dev = V.Device()
    painter = GuiPainter(dev)
    img = V.Image(dev, 64, 48, "rgba8", ("color", "transfer_src"))
    fb = V.Framebuffer(dev, painter.render_pass("rgba8"), [img], 64, 48)
    try:
        tex = painter.create_texture(np.full((2, 2, 4), 255, np.uint8))
        verts = np.zeros(3, GUI_VERTEX)
        verts["pos"] = [(4, 4), (60, 4), (4, 44)]
        verts["col"] = (255, 0, 0, 255)
        painter.upload_arrays(verts, np.arange(3, dtype=np.uint32))
        scale, translate = (2.0 / 64, 2.0 / 48), (-1.0, -1.0)
        draw = GuiDraw(texture=tex, clip=(0, 0, 64, 48), index_count=3, first_index=0, vertex_offset=0)
        dev.submit(lambda cb: painter.record(cb, fb, [draw], scale=scale, translate=translate, fmt="rgba8",
                                             clear=(0, 0, 0, 1)))
        assert pushed == [_legacy_gui_push(scale, translate)]
    finally:
        fb.destroy()
        img.destroy()
        painter.destroy()
        dev.close()


def test_gui_vertex_dtype_reads_imgui_draw_vertices():
    imgui = pytest.importorskip("imgui_bundle").imgui
    vec = imgui.ImVector_ImDrawVert()
    want = []
    for i in range(4):
        v = imgui.ImDrawVert()
        v.pos, v.uv = imgui.ImVec2(1.5 + i, -2.25 * i), imgui.ImVec2(0.125 * i, 0.75)
        v.col = 0x80402010 + i                    # IM_COL32(0x10 + i, 0x20, 0x40, 0x80): R in the low byte
        vec.push_back(v)
        want.append(((1.5 + i, -2.25 * i), (0.125 * i, 0.75), (0x10 + i, 0x20, 0x40, 0x80)))
    raw = ctypes.string_at(vec.data_address(), vec.size() * GUI_VERTEX.itemsize)
    got = np.frombuffer(raw, GUI_VERTEX)
    assert VERTEX_BYTES == GUI_VERTEX.itemsize == 20
    for g, (pos, uv, col) in zip(got, want):
        assert tuple(g["pos"]) == pos and tuple(g["uv"]) == uv and tuple(g["col"]) == col
    # the vertex attributes read those fields: pos, uv at 0 and 8, col at 16 (the hand offsets)
    assert [(a.location, a.format, a.offset) for a in _VERTEX_ATTRIBUTES] == [
        (0, "vec2", 0), (1, "vec2", 8), (2, "unorm8x4", 16)]


def test_specialization_data_equals_the_hand_packing():
    assert specialization(()) == (None, None)
    for spec in (((0, 7),), ((0, 16), (1, -3), (5, 2**31 - 1)), ((2, -2**31), (0, 0))):
        info, keep = specialization(spec)
        data = bytes(vk.ffi.buffer(vk.ffi.cast("char *", info.pData), info.dataSize))
        assert data == _legacy_specialization(spec)
        assert [(e.constantID, e.offset, e.size) for e in keep[0]] == [(c, 4 * i, 4) for i, (c, _) in enumerate(spec)]
