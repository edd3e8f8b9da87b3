"""Graphics pipelines: their description (:class:`GraphicsDesc`, with the
vertex input of :class:`VertexBinding` / :class:`VertexAttribute`) and
:func:`create_graphics_pipeline`, which builds one from its render pass,
layout and shader modules (the
:class:`~splatedit.render.vk.pipelines.PipelineCache` owns the result)."""

from __future__ import annotations

from dataclasses import dataclass

import vulkan as vk

from splatedit.render.vk.core import Device
from splatedit.render.vk.handles import call
from splatedit.render.vk.descriptors import LayoutDesc, PipelineLayout
from splatedit.render.vk.passes import RenderPass, RenderPassDesc
from splatedit.render.vk.shaders import ShaderModule, specialization, stage_info

_VERTEX_FORMATS = {
    "float": vk.VK_FORMAT_R32_SFLOAT,
    "vec2": vk.VK_FORMAT_R32G32_SFLOAT,
    "vec3": vk.VK_FORMAT_R32G32B32_SFLOAT,
    "vec4": vk.VK_FORMAT_R32G32B32A32_SFLOAT,
    "uint": vk.VK_FORMAT_R32_UINT,
    "unorm8x4": vk.VK_FORMAT_R8G8B8A8_UNORM,
}

_TOPOLOGY = {
    "triangle_strip": vk.VK_PRIMITIVE_TOPOLOGY_TRIANGLE_STRIP,
    "triangle_list": vk.VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST,
    "point_list": vk.VK_PRIMITIVE_TOPOLOGY_POINT_LIST,
}

_COMPARE = {
    "less": vk.VK_COMPARE_OP_LESS,
    "less_equal": vk.VK_COMPARE_OP_LESS_OR_EQUAL,
    "always": vk.VK_COMPARE_OP_ALWAYS,
}


@dataclass(frozen=True)
class VertexBinding:
    """A vertex buffer binding: number, stride (bytes) and whether it advances per instance."""
    binding: int
    stride: int
    per_instance: bool = True


@dataclass(frozen=True)
class VertexAttribute:
    """A vertex attribute: shader location, binding, format name and byte offset in the record."""
    location: int
    binding: int
    format: str     # key of _VERTEX_FORMATS
    offset: int


@dataclass(frozen=True)
class GraphicsDesc:
    """A graphics pipeline by description (shaders by SPIR-V name, render pass, layout, vertex input,
    fixed-function state); the pipeline cache keys on this value."""
    vert: str                                   # spirv name, e.g. "splat.vert"
    frag: str
    render_pass: RenderPassDesc
    layout: LayoutDesc
    topology: str = "triangle_strip"
    bindings: tuple[VertexBinding, ...] = ()
    attributes: tuple[VertexAttribute, ...] = ()
    depth_test: bool = False
    depth_write: bool = False
    depth_compare: str = "less"
    blend_add: tuple[bool, ...] = ()            # per colour attachment: additive (ONE, ONE)
    blend_alpha: bool = False                   # all colour attachments: "over" (SRC_ALPHA, 1-SRC_ALPHA)
    #: per colour attachment: front-to-back "under" of premultiplied colour
    #: (src ONE_MINUS_DST_ALPHA, dst ONE; Gaussian splatting)
    blend_under: tuple[bool, ...] = ()
    color_write: bool = True
    spec: tuple[tuple[int, int], ...] = ()      # (constant_id, int32 value), both stages


def _vertex_input(d: GraphicsDesc):
    vb = [vk.VkVertexInputBindingDescription(
        binding=b.binding, stride=b.stride,
        inputRate=vk.VK_VERTEX_INPUT_RATE_INSTANCE if b.per_instance else vk.VK_VERTEX_INPUT_RATE_VERTEX)
        for b in d.bindings]
    va = [vk.VkVertexInputAttributeDescription(location=a.location, binding=a.binding,
                                               format=_VERTEX_FORMATS[a.format], offset=a.offset)
          for a in d.attributes]
    info = vk.VkPipelineVertexInputStateCreateInfo(
        vertexBindingDescriptionCount=len(vb), pVertexBindingDescriptions=vb or None,
        vertexAttributeDescriptionCount=len(va), pVertexAttributeDescriptions=va or None)
    return info, (vb, va)


def _blend_states(d: GraphicsDesc) -> list:
    """One blend state per colour attachment, in three modes: additive (ONE,
    ONE), "over" (SRC_ALPHA, 1 - SRC_ALPHA: the GUI), "under" (1 - DST_ALPHA,
    ONE: front-to-back Gaussians, premultiplied colour); none: replace."""
    rgba = (vk.VK_COLOR_COMPONENT_R_BIT | vk.VK_COLOR_COMPONENT_G_BIT | vk.VK_COLOR_COMPONENT_B_BIT
            | vk.VK_COLOR_COMPONENT_A_BIT)
    one, inv = vk.VK_BLEND_FACTOR_ONE, vk.VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA
    blends = []
    for i in range(len(d.render_pass.colors)):
        add = d.blend_add[i] if i < len(d.blend_add) else False
        under = d.blend_under[i] if i < len(d.blend_under) else False
        src = vk.VK_BLEND_FACTOR_ONE_MINUS_DST_ALPHA if under else (
            vk.VK_BLEND_FACTOR_SRC_ALPHA if d.blend_alpha else one)
        blends.append(vk.VkPipelineColorBlendAttachmentState(
            blendEnable=vk.VK_TRUE if (add or d.blend_alpha or under) else vk.VK_FALSE,
            srcColorBlendFactor=src,
            dstColorBlendFactor=inv if (d.blend_alpha and not under) else one,
            colorBlendOp=vk.VK_BLEND_OP_ADD,
            srcAlphaBlendFactor=vk.VK_BLEND_FACTOR_ONE_MINUS_DST_ALPHA if under else one,
            dstAlphaBlendFactor=inv if (d.blend_alpha and not under) else one,
            alphaBlendOp=vk.VK_BLEND_OP_ADD, colorWriteMask=rgba if d.color_write else 0))
    return blends


def create_graphics_pipeline(device: Device, d: GraphicsDesc, layout: PipelineLayout, render_pass: RenderPass,
                             vert: ShaderModule, frag: ShaderModule):
    """A VkPipeline handle for ``d`` (viewport and scissor dynamic, no culling,
    one sample); the caller destroys it."""
    spec, keep_spec = specialization(d.spec)
    stages = [stage_info(vk.VK_SHADER_STAGE_VERTEX_BIT, vert, spec),
              stage_info(vk.VK_SHADER_STAGE_FRAGMENT_BIT, frag, spec)]
    vinput, keep_vertex = _vertex_input(d)
    ia = vk.VkPipelineInputAssemblyStateCreateInfo(topology=_TOPOLOGY[d.topology])
    vps = vk.VkPipelineViewportStateCreateInfo(viewportCount=1, scissorCount=1)
    rs = vk.VkPipelineRasterizationStateCreateInfo(
        polygonMode=vk.VK_POLYGON_MODE_FILL, cullMode=vk.VK_CULL_MODE_NONE,
        frontFace=vk.VK_FRONT_FACE_COUNTER_CLOCKWISE, lineWidth=1.0)
    ms = vk.VkPipelineMultisampleStateCreateInfo(rasterizationSamples=vk.VK_SAMPLE_COUNT_1_BIT)
    ds = vk.VkPipelineDepthStencilStateCreateInfo(
        depthTestEnable=vk.VK_TRUE if d.depth_test else vk.VK_FALSE,
        depthWriteEnable=vk.VK_TRUE if d.depth_write else vk.VK_FALSE,
        depthCompareOp=_COMPARE[d.depth_compare], maxDepthBounds=1.0)
    blends = _blend_states(d)
    cb = vk.VkPipelineColorBlendStateCreateInfo(attachmentCount=len(blends), pAttachments=blends or None)
    dyn_states = [vk.VK_DYNAMIC_STATE_VIEWPORT, vk.VK_DYNAMIC_STATE_SCISSOR]
    dyn = vk.VkPipelineDynamicStateCreateInfo(dynamicStateCount=2, pDynamicStates=dyn_states)
    info = vk.VkGraphicsPipelineCreateInfo(
        stageCount=2, pStages=stages, pVertexInputState=vinput, pInputAssemblyState=ia,
        pViewportState=vps, pRasterizationState=rs, pMultisampleState=ms, pDepthStencilState=ds,
        pColorBlendState=cb, pDynamicState=dyn, layout=layout.handle, renderPass=render_pass.handle,
        subpass=0, basePipelineIndex=-1)
    handle = call(vk.vkCreateGraphicsPipelines, device.device, None, 1, [info], None)[0]
    del keep_spec, keep_vertex, stages, blends
    return handle
