"""GPU layout of the splat renderer (:mod:`splatedit.render.splat.renderer`): flag
bits, buffer strides, descriptor-set layouts and render passes shared by its
vertex path, compute pre-pass (:mod:`splatedit.render.splat.prepass`), per-size
targets (:mod:`splatedit.render.targets`) and progressive frames.

Only :mod:`splatedit.render.vk` calls Vulkan.
"""

from __future__ import annotations

from dataclasses import replace

from splatedit.render import vk as V
from splatedit.render.uniforms import FRAME_UBO, SPLAT_GEOM, SPLAT_REC_A, SPLAT_REC_B

FLAG_SUPPORT = 1
FLAG_HANDLE = 2
FLAG_DEFORMED = 4
FLAG_INACTIVE = 8            # an inactive handle (the editor's several handles): darker

UBO_BYTES = FRAME_UBO.itemsize   # splatedit/render/uniforms.py, checked against frame.glsl
GEOM_STRIDE = SPLAT_GEOM.itemsize   # centre, u, v as float32

#: vertex path: frame UBO, deformation UBO
SPLAT_SET = (V.Binding(0, "uniform", "vert|frag"), V.Binding(1, "uniform", "vert"))
#: compute pre-pass + prepared draws: frame UBO, cloud (geometry, colours,
#: flags, basis), records A/B, indirect draw commands, deformation UBO
PREP_SET = (V.Binding(0, "uniform", "vert|frag|comp"), V.Binding(1, "storage", "comp"),
             V.Binding(2, "storage", "comp"), V.Binding(3, "storage", "comp"), V.Binding(4, "storage", "comp"),
             V.Binding(5, "storage", "vert|comp"), V.Binding(6, "storage", "vert|comp"),
             V.Binding(7, "storage", "comp"), V.Binding(8, "uniform", "comp"))
#: the detail mode's pre-pass adds (n_b, lambda) per splat (shaders_glsl/detail.glsl)
PREP_SET_DETAIL = PREP_SET + (V.Binding(9, "storage", "comp"),)
REC_A_BYTES = SPLAT_REC_A.itemsize
REC_B_BYTES = SPLAT_REC_B.itemsize
WORKGROUP = 64
#: the pre-pass packs quad bounds as 12.4 fixed-point pixels
PREP_MAX_SIZE = 4095
RESOLVE_SET = (V.Binding(0, "uniform", "frag"), V.Binding(1, "sampled", "frag"),
                V.Binding(2, "sampled", "frag"))

#: the pick pass (of both renderers): splat / Gaussian index + 1 (0 background) and depth, both read back
RP_PICK = V.RenderPassDesc(colors=(V.Attachment("r32ui", "clear", final="transfer_src"),),
                           depth=V.Attachment("d32f", "clear", final="transfer_src"))
RP_DEPTH = V.RenderPassDesc(depth=V.Attachment("d32f", "clear", final="depth"))
RP_POINTS = V.RenderPassDesc(colors=(V.Attachment("rgba8", "clear", final="color"),),
                              depth=V.Attachment("d32f", "clear", final="depth"))


def rp_window(desc: V.RenderPassDesc, first: bool, last: bool) -> V.RenderPassDesc:
    """``desc`` for one splat window of a windowed pre-pass frame: windows after
    the first load what the previous one left instead of clearing it, and all
    but the last leave the attachments in attachment layouts."""
    def att(a: V.Attachment, layout: str) -> V.Attachment:
        if not first and a.load == "clear":
            a = replace(a, load="load", initial=layout)
        return a if last else replace(a, final=layout)
    return replace(desc, colors=tuple(att(a, "color") for a in desc.colors),
                   depth=None if desc.depth is None else att(desc.depth, "depth"))


def rp_attr(fmt: str, final: str) -> V.RenderPassDesc:
    """The attribute render pass: two colour targets of format ``fmt`` (cleared; layout ``final`` after the
    pass) and the visibility pass's depth, loaded read-only."""
    return V.RenderPassDesc(colors=(V.Attachment(fmt, "clear", final=final),
                                    V.Attachment(fmt, "clear", final=final)),
                            depth=V.Attachment("d32f", "load", initial="depth", final="depth"))


def splat_desc(vert: str, kind: str, accum_format: str, layout: V.LayoutDesc, **common) -> V.GraphicsDesc:
    """The pipeline of splat pass ``kind`` (``"depth"``: visibility, ``"attr"``:
    attribute accumulation into ``accum_format``, else pick) with vertex
    shader ``vert``; ``common``: the vertex input, topology and specialisation."""
    if kind == "depth":
        return V.GraphicsDesc(vert, "splat_depth.frag", RP_DEPTH, layout, depth_write=True, depth_compare="less",
                              depth_test=True, **common)
    if kind == "attr":
        return V.GraphicsDesc(vert, "splat_attr.frag", rp_attr(accum_format, "shader_read"), layout,
                              depth_write=False, depth_compare="less_equal", blend_add=(True, True),
                              depth_test=True, **common)
    return V.GraphicsDesc(vert, "splat_pick.frag", RP_PICK, layout, depth_write=True, depth_compare="less",
                          depth_test=True, **common)
