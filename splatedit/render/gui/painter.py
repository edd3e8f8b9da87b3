"""The GUI's draw pass: textured, alpha-blended 2D triangles with a
scissor per draw, drawn into an existing colour target.

:class:`GuiPainter` knows nothing about Dear ImGui (that is
:mod:`splatedit.render.gui.gui`); it draws indexed triangles whose vertices have
ImGui's ``ImDrawVert`` layout (:data:`~splatedit.render.uniforms.GUI_VERTEX`,
20 bytes: ``pos`` 2 x float32 in framebuffer pixels, ``uv`` 2 x float32,
``col`` RGBA8 unorm) and 16- or 32-bit indices
(``ImDrawIdx`` is a compile-time choice; imgui-bundle 1.93 uses 32 bits):

* textures (:meth:`~GuiPainter.create_texture`, :meth:`~GuiPainter.update_texture`,
  :meth:`~GuiPainter.destroy_texture`) are RGBA8 UNORM sampled images with a
  bilinear clamp-to-edge sampler, one descriptor set each, named by small
  integer ids handed out here (never ``id()``).  Uploads go through a
  temporary staging buffer in their own fenced submission: they are rare
  (font atlas creation, atlas growth);
* vertex and index buffers are host-visible, persistently mapped, reused
  from frame to frame and grown (to the next power of two) when a frame needs
  more; :meth:`~GuiPainter.upload` copies draw lists straight from their
  memory addresses (no per-vertex python work);
* :meth:`~GuiPainter.record` begins a render pass on a given framebuffer
  (loading its contents, or clearing them), binds the pipeline (one per
  target format, cached in a :class:`PipelineCache`), pushes
  ``scale``/``translate`` (push constants
  :data:`~splatedit.render.uniforms.GUI_PUSH`), and issues one
  ``vkCmdDrawIndexed`` per :class:`GuiDraw` with its scissor rectangle.

Frame contract: :meth:`~GuiPainter.upload` rewrites the buffers the previous
frame drew from, so call it only once that frame has finished on the GPU
(``Device.submit`` waits; the swapchain presenter waits for its fence before
it records a new frame).
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass

import numpy as np

from splatedit.render.uniforms import GUI_PUSH, GUI_VERTEX
from splatedit.render.vk.commands import IMAGE_LAYOUTS, CommandBuffer
from splatedit.render.vk.core import Device
from splatedit.render.vk.descriptors import Binding, DescriptorSet, LayoutDesc
from splatedit.render.vk.graphics import GraphicsDesc, VertexAttribute, VertexBinding
from splatedit.render.vk.passes import Attachment, Framebuffer, RenderPass, RenderPassDesc
from splatedit.render.vk.pipelines import PipelineCache
from splatedit.render.vk.resources import Buffer, Image, Sampler

#: bytes of one ImDrawVert (pos 8, uv 8, col 4)
VERTEX_BYTES = GUI_VERTEX.itemsize
#: smallest vertex/index buffer allocated (bytes); later growth doubles
MIN_BUFFER_BYTES = 64 * 1024

_SET = (Binding(0, "sampled", "frag"),)
_LAYOUT = LayoutDesc(sets=(_SET,), push_bytes=GUI_PUSH.itemsize, push_stages="vert")
_VERTEX_BINDINGS = (VertexBinding(0, VERTEX_BYTES, per_instance=False),)
_VERTEX_ATTRIBUTES = tuple(VertexAttribute(location, 0, fmt, GUI_VERTEX.fields[name][1])
                           for location, (name, fmt) in enumerate((("pos", "vec2"), ("uv", "vec2"),
                                                                   ("col", "unorm8x4"))))
_LAYOUT_NAMES = {v: k for k, v in IMAGE_LAYOUTS.items()}


@dataclass(frozen=True)
class GuiDraw:
    """One indexed draw: ``index_count`` indices from ``first_index`` (in the
    uploaded index array), added to ``vertex_offset`` (in the uploaded vertex
    array), sampling texture ``texture``, clipped to ``clip`` = (x, y, w, h)
    framebuffer pixels."""
    texture: int
    clip: tuple[int, int, int, int]
    index_count: int
    first_index: int
    vertex_offset: int


class GuiTexture:
    """An RGBA8 sampled image with its descriptor set (owned by a :class:`GuiPainter`)."""

    def __init__(self, painter: "GuiPainter", width: int, height: int):
        self.width, self.height = int(width), int(height)
        self.image = Image(painter.dev, self.width, self.height, "rgba8", ("sampled", "transfer_dst"))
        try:
            self.dset = DescriptorSet(painter.dev, painter.cache.set_layout(_SET))
        except BaseException:
            self.image.destroy()
            raise
        # the set is written once the image has content (shader-read layout)

    def destroy(self) -> None:
        self.dset.destroy()
        self.image.destroy()


class _GrowingBuffer:
    """A host-visible buffer reused while large enough, replaced by a bigger one when not."""

    def __init__(self, dev: Device, usage: str):
        self.dev, self.usage = dev, usage
        self.buffer: Buffer | None = None
        self.allocations = 0            # how many times a buffer was (re)allocated

    def ensure(self, nbytes: int) -> Buffer:
        if self.buffer is None or self.buffer.size < nbytes:
            size = MIN_BUFFER_BYTES
            while size < nbytes:
                size *= 2
            self.destroy()
            self.buffer = Buffer(self.dev, size, (self.usage,), host_visible=True)
            self._address = self.buffer.view().ctypes.data
            self.allocations += 1
        return self.buffer

    @property
    def address(self) -> int:
        return self._address

    def destroy(self) -> None:
        if self.buffer is not None:
            self.buffer.destroy()
            self.buffer = None


class GuiPainter:
    """Draws textured 2D triangles (ImGui's vertex format) into colour targets.

    Args:
        device: the Vulkan device the targets belong to.
        cache: a pipeline cache to share (not destroyed here); default: an own one.
    """

    def __init__(self, device: Device, cache: PipelineCache | None = None):
        self.dev = device
        self._own_cache = cache is None
        self.cache = cache if cache is not None else PipelineCache(device)
        self.sampler = Sampler(device, linear=True)
        self.textures: dict[int, GuiTexture] = {}
        self._next_id = 1
        self._vertices = _GrowingBuffer(device, "vertex")
        self._indices = _GrowingBuffer(device, "index")
        self._vertex_count = 0
        self._index_count = 0
        self._index_bytes = 4

    # ------------------------------------------------------------ textures
    def create_texture(self, rgba: np.ndarray) -> int:
        """Upload ``rgba`` ((h, w, 4) uint8) to a new sampled image; returns its id (> 0)."""
        rgba = _check_rgba(rgba)
        tex = GuiTexture(self, rgba.shape[1], rgba.shape[0])
        tid = self._next_id
        self._next_id += 1
        self.textures[tid] = tex
        try:
            self._upload(tex, 0, 0, rgba, first=True)
            tex.dset.write({0: (tex.image, self.sampler)})
        except BaseException:
            self.destroy_texture(tid)
            raise
        return tid

    def update_texture(self, tid: int, x: int, y: int, rgba: np.ndarray) -> None:
        """Replace the texels of texture ``tid`` at (x, y) with ``rgba`` ((h, w, 4) uint8)."""
        rgba = _check_rgba(rgba)
        tex = self.textures[tid]
        h, w = rgba.shape[:2]
        if x < 0 or y < 0 or x + w > tex.width or y + h > tex.height:
            raise ValueError(f"update {w}x{h} at ({x}, {y}) is outside the {tex.width}x{tex.height} texture")
        if w and h:
            self._upload(tex, x, y, rgba, first=False)

    def destroy_texture(self, tid: int) -> None:
        tex = self.textures.pop(tid, None)
        if tex is not None:
            tex.destroy()

    def _upload(self, tex: GuiTexture, x: int, y: int, rgba: np.ndarray, first: bool) -> None:
        h, w = rgba.shape[:2]
        staging = Buffer(self.dev, rgba.nbytes, ("transfer_src",), host_visible=True)
        try:
            staging.view()[:] = rgba.reshape(-1)

            def rec(cb: CommandBuffer):
                # earlier frames sampled the image in their fragment shaders (queue order)
                cb.image_barrier(tex.image, "transfer_dst", "fragment" if not first else "top", "none",
                                 "transfer", "transfer_write")
                cb.copy_buffer_to_image(staging, tex.image, (x, y, w, h))
                cb.image_barrier(tex.image, "shader_read", "transfer", "transfer_write",
                                 "fragment", "shader_read")
            self.dev.submit(rec)
        finally:
            staging.destroy()

    # ------------------------------------------------------------ geometry
    def upload(self, lists, index_bytes: int = 4) -> None:
        """Copy the frame's geometry: ``lists`` is a sequence of
        (vertex_address, vertex_count, index_address, index_count) of draw lists,
        concatenated in order (a list's draws use vertex_offset/first_index
        relative to the start of the concatenation); indices are ``index_bytes``
        (2 or 4) wide."""
        if index_bytes not in (2, 4):
            raise ValueError(f"indices must be 2 or 4 bytes wide, got {index_bytes}")
        self._index_bytes = index_bytes
        nv = sum(int(v) for _, v, _, _ in lists)
        ni = sum(int(i) for _, _, _, i in lists)
        self._vertex_count, self._index_count = nv, ni
        if nv == 0 or ni == 0:
            return
        self._vertices.ensure(nv * VERTEX_BYTES)
        self._indices.ensure(ni * index_bytes)
        vdst, idst = self._vertices.address, self._indices.address
        for vaddr, vn, iaddr, inn in lists:
            ctypes.memmove(vdst, int(vaddr), int(vn) * VERTEX_BYTES)
            ctypes.memmove(idst, int(iaddr), int(inn) * index_bytes)
            vdst += int(vn) * VERTEX_BYTES
            idst += int(inn) * index_bytes

    def upload_arrays(self, vertices: np.ndarray, indices: np.ndarray) -> None:
        """Copy one vertex array ((n, 20) uint8 or a structured array of 20-byte
        records) and one uint16 or uint32 index array."""
        v = np.ascontiguousarray(vertices)
        i = np.ascontiguousarray(indices)
        if i.dtype not in (np.uint16, np.uint32):
            raise ValueError(f"indices must be uint16 or uint32, got {i.dtype}")
        if v.nbytes % VERTEX_BYTES:
            raise ValueError(f"vertex data of {v.nbytes} bytes is not a multiple of {VERTEX_BYTES}")
        self.upload([(v.ctypes.data, v.nbytes // VERTEX_BYTES, i.ctypes.data, i.size)], i.itemsize)

    @property
    def buffer_allocations(self) -> int:
        """Vertex + index buffer allocations so far (growth events; reused otherwise)."""
        return self._vertices.allocations + self._indices.allocations

    # ------------------------------------------------------------ drawing
    def render_pass(self, fmt: str, *, clear: bool = False, initial: str = "color",
                    final: str = "color") -> RenderPass:
        """The (cached) render pass for a target of format ``fmt`` (key of
        resources.FORMATS): it loads the target (in layout ``initial``) or clears
        it, and leaves it in layout ``final``.  Framebuffers made with any of
        these are compatible with all of them."""
        att = Attachment(fmt, load="clear" if clear else "load", initial=initial, final=final)
        return self.cache.render_pass(RenderPassDesc(colors=(att,)))

    def pipeline(self, fmt: str):
        desc = GraphicsDesc(vert="gui.vert", frag="gui.frag",
                            render_pass=RenderPassDesc(colors=(Attachment(fmt, load="load", initial="color"),)),
                            layout=_LAYOUT, topology="triangle_list", bindings=_VERTEX_BINDINGS,
                            attributes=_VERTEX_ATTRIBUTES, blend_alpha=True)
        return self.cache.pipeline(desc)

    def record(self, cmd: CommandBuffer, framebuffer: Framebuffer, draws, *, scale, translate,
               fmt: str, clear=None, final: str = "color") -> int:
        """Record the GUI pass into ``cmd``: begin a render pass on
        ``framebuffer`` (its one attachment, format ``fmt``, is loaded from its
        current layout, or cleared to ``clear`` = RGBA floats when given), draw
        ``draws`` (:class:`GuiDraw`) from the last :meth:`upload`, end in layout
        ``final``.  ``scale``/``translate``: pixel -> clip transform (2 floats
        each).  Returns the number of draw calls issued."""
        target = framebuffer.attachments[0]
        if clear is None and target.layout == IMAGE_LAYOUTS["undefined"]:
            # nothing to load: transition so the "load" pass finds the layout it names
            cmd.image_barrier(target, "color", "top", "none", "color_output", "color_write")
        initial = "undefined" if clear is not None else _LAYOUT_NAMES.get(target.layout)
        if initial is None:
            raise ValueError(f"the GUI target is in an unknown layout {target.layout}")
        rp = self.render_pass(fmt, clear=clear is not None, initial=initial, final=final)
        cmd.begin_render_pass(rp, framebuffer, [tuple(float(c) for c in clear) if clear is not None else None])
        issued = 0
        fw, fh = framebuffer.width, framebuffer.height
        if draws and self._index_count and self._vertex_count:
            pipe = self.pipeline(fmt)
            cmd.bind_pipeline(pipe)
            cmd.bind_vertex_buffers(0, [self._vertices.buffer])
            cmd.bind_index_buffer(self._indices.buffer, uint32=self._index_bytes == 4)
            cmd.push_constants(pipe, gui_push(scale, translate))
            bound = None
            for d in draws:
                x, y, w, h = d.clip
                x0, y0 = max(0, int(x)), max(0, int(y))
                x1, y1 = min(fw, int(x) + int(w)), min(fh, int(y) + int(h))
                if x1 <= x0 or y1 <= y0 or d.index_count <= 0:
                    continue
                tex = self.textures.get(d.texture)
                if tex is None:
                    raise KeyError(f"GUI draw uses texture {d.texture}, which does not exist")
                if bound != d.texture:
                    cmd.bind_descriptor_set(pipe, tex.dset)
                    bound = d.texture
                cmd.set_scissor(x0, y0, x1 - x0, y1 - y0)
                cmd.draw_indexed(d.index_count, 1, d.first_index, d.vertex_offset, 0)
                issued += 1
        cmd.end_render_pass()
        return issued

    # ------------------------------------------------------------ teardown
    def destroy(self) -> None:
        """Destroy textures, buffers, the sampler and (if owned) the pipeline cache (idempotent)."""
        for tid in list(self.textures):
            self.destroy_texture(tid)
        self._vertices.destroy()
        self._indices.destroy()
        if self.sampler is not None:
            self.sampler.destroy()
            self.sampler = None
        if self._own_cache and self.cache is not None:
            self.cache.destroy()
        self.cache = None


def gui_push(scale, translate) -> np.ndarray:
    """The push constants of gui.vert: a () record of
    :data:`~splatedit.render.uniforms.GUI_PUSH` holding ``scale`` and
    ``translate`` (2 floats each: framebuffer pixels -> clip space)."""
    rec = np.zeros((), GUI_PUSH)
    rec["scale"] = scale
    rec["translate"] = translate
    return rec


def _check_rgba(rgba) -> np.ndarray:
    a = np.ascontiguousarray(rgba)
    if a.ndim != 3 or a.shape[2] != 4 or a.dtype != np.uint8:
        raise ValueError(f"a GUI texture needs (h, w, 4) uint8 texels, got {a.shape} {a.dtype}")
    return a
