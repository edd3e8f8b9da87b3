"""Shader modules, render passes, framebuffers, descriptors and pipelines.

Pipelines, pipeline layouts, descriptor-set layouts and render passes are
described by frozen dataclasses and cached by their description in a
:class:`PipelineCache`, which owns and destroys them.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from pathlib import Path

import vulkan as vk

from splatedit.render.vk.commands import _LAYOUTS
from splatedit.render.vk.core import Device, VulkanError, call, track
from splatedit.render.vk.resources import FORMATS

#: where compiled shaders are looked up, in order: the package copy (package
#: data, present in an installed wheel) and the repository's top-level spirv/
SPIRV_DIRS = (Path(__file__).resolve().parents[2] / "spirv",
              Path(__file__).resolve().parents[3] / "spirv")


def spirv_path(name: str) -> Path:
    """Path of the compiled shader ``name`` (e.g. ``splat.vert``) -> ``.../splat.vert.spv``."""
    for d in SPIRV_DIRS:
        p = d / f"{name}.spv"
        if p.is_file():
            return p
    raise VulkanError("load shader", "VK_ERROR_INITIALIZATION_FAILED",
                      f"compiled shader {name}.spv not found in {[str(d) for d in SPIRV_DIRS]}; "
                      "run python data_tools/compile_shaders.py")


_STAGE_BITS = {
    "vert": vk.VK_SHADER_STAGE_VERTEX_BIT,
    "frag": vk.VK_SHADER_STAGE_FRAGMENT_BIT,
    "comp": vk.VK_SHADER_STAGE_COMPUTE_BIT,
}


def _stages(names: str) -> int:
    out = 0
    for n in names.split("|"):
        out |= _STAGE_BITS[n]
    return out


_DESC_TYPES = {
    "uniform": vk.VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER,
    "storage": vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    "sampled": vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
    "storage_image": vk.VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
}

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


# ------------------------------------------------------------ descriptions
@dataclass(frozen=True)
class Attachment:
    format: str                     # key of resources.FORMATS
    load: str = "clear"             # "clear" | "load" | "dont_care"
    initial: str = "undefined"      # layout name (commands._LAYOUTS) when load == "load"
    final: str = "color"            # layout after the pass
    store: bool = True


@dataclass(frozen=True)
class RenderPassDesc:
    colors: tuple[Attachment, ...] = ()
    depth: Attachment | None = None
    depth_read_only: bool = False


@dataclass(frozen=True)
class Binding:
    binding: int
    type: str       # "uniform" | "storage" | "sampled" | "storage_image"
    stages: str     # "vert|frag"


@dataclass(frozen=True)
class LayoutDesc:
    sets: tuple[tuple[Binding, ...], ...] = ()
    push_bytes: int = 0
    push_stages: str = "vert"


@dataclass(frozen=True)
class VertexBinding:
    binding: int
    stride: int
    per_instance: bool = True


@dataclass(frozen=True)
class VertexAttribute:
    location: int
    binding: int
    format: str     # key of _VERTEX_FORMATS
    offset: int


@dataclass(frozen=True)
class GraphicsDesc:
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


@dataclass(frozen=True)
class ComputeDesc:
    comp: str
    layout: LayoutDesc
    spec: tuple[tuple[int, int], ...] = ()


# ------------------------------------------------------------- objects
class RenderPass:
    def __init__(self, device: Device, desc: RenderPassDesc):
        self.dev = device
        self.desc = desc
        atts, self.final_layouts = [], []
        all_atts = list(desc.colors) + ([desc.depth] if desc.depth else [])
        for a in all_atts:
            load = {"clear": vk.VK_ATTACHMENT_LOAD_OP_CLEAR, "load": vk.VK_ATTACHMENT_LOAD_OP_LOAD,
                    "dont_care": vk.VK_ATTACHMENT_LOAD_OP_DONT_CARE}[a.load]
            atts.append(vk.VkAttachmentDescription(
                format=FORMATS[a.format], samples=vk.VK_SAMPLE_COUNT_1_BIT, loadOp=load,
                storeOp=vk.VK_ATTACHMENT_STORE_OP_STORE if a.store else vk.VK_ATTACHMENT_STORE_OP_DONT_CARE,
                stencilLoadOp=vk.VK_ATTACHMENT_LOAD_OP_DONT_CARE,
                stencilStoreOp=vk.VK_ATTACHMENT_STORE_OP_DONT_CARE,
                initialLayout=_LAYOUTS[a.initial if a.load == "load" else "undefined"],
                finalLayout=_LAYOUTS[a.final]))
            self.final_layouts.append(_LAYOUTS[a.final])
        color_refs = [vk.VkAttachmentReference(attachment=i, layout=vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL)
                      for i in range(len(desc.colors))]
        depth_ref = None
        if desc.depth:
            depth_ref = vk.VkAttachmentReference(
                attachment=len(desc.colors),
                layout=(vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL if desc.depth_read_only
                        else vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL))
        subpass = vk.VkSubpassDescription(
            pipelineBindPoint=vk.VK_PIPELINE_BIND_POINT_GRAPHICS,
            colorAttachmentCount=len(color_refs), pColorAttachments=color_refs or None,
            pDepthStencilAttachment=depth_ref)
        gfx = (vk.VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | vk.VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT
               | vk.VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT)
        att_rw = (vk.VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | vk.VK_ACCESS_COLOR_ATTACHMENT_READ_BIT
                  | vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT
                  | vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT)
        outside = (vk.VK_PIPELINE_STAGE_TRANSFER_BIT | vk.VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT
                   | vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | gfx)
        outside_acc = (vk.VK_ACCESS_TRANSFER_READ_BIT | vk.VK_ACCESS_TRANSFER_WRITE_BIT
                       | vk.VK_ACCESS_SHADER_READ_BIT | vk.VK_ACCESS_SHADER_WRITE_BIT | att_rw)
        deps = [
            # earlier passes / copies / compute -> this pass (the subpass side names graphics stages only)
            vk.VkSubpassDependency(srcSubpass=vk.VK_SUBPASS_EXTERNAL, dstSubpass=0,
                                   srcStageMask=outside, dstStageMask=gfx | vk.VK_PIPELINE_STAGE_VERTEX_SHADER_BIT
                                   | vk.VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT | vk.VK_PIPELINE_STAGE_VERTEX_INPUT_BIT
                                   | vk.VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT,
                                   srcAccessMask=outside_acc,
                                   dstAccessMask=att_rw | vk.VK_ACCESS_SHADER_READ_BIT
                                   | vk.VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT | vk.VK_ACCESS_INDIRECT_COMMAND_READ_BIT
                                   | vk.VK_ACCESS_UNIFORM_READ_BIT),
            # this pass -> later passes, samplers, copies
            vk.VkSubpassDependency(srcSubpass=0, dstSubpass=vk.VK_SUBPASS_EXTERNAL,
                                   srcStageMask=gfx, dstStageMask=outside,
                                   srcAccessMask=att_rw, dstAccessMask=outside_acc),
        ]
        info = vk.VkRenderPassCreateInfo(attachmentCount=len(atts), pAttachments=atts, subpassCount=1,
                                         pSubpasses=[subpass], dependencyCount=len(deps), pDependencies=deps)
        self.handle = call(vk.vkCreateRenderPass, device.device, info, None)
        track("render_pass", 1)

    def destroy(self):
        if self.handle is not None:
            vk.vkDestroyRenderPass(self.dev.device, self.handle, None)
            track("render_pass", -1)
            self.handle = None


class Framebuffer:
    def __init__(self, device: Device, render_pass: RenderPass, attachments, width: int, height: int):
        """``attachments``: objects with ``.view`` and ``.layout`` (Image or a swapchain image wrapper)."""
        self.dev = device
        self.width, self.height = width, height
        self.attachments = list(attachments)
        views = [a.view for a in self.attachments]
        info = vk.VkFramebufferCreateInfo(renderPass=render_pass.handle, attachmentCount=len(views),
                                          pAttachments=views, width=width, height=height, layers=1)
        self.handle = call(vk.vkCreateFramebuffer, device.device, info, None)
        track("framebuffer", 1)

    def destroy(self):
        if self.handle is not None:
            vk.vkDestroyFramebuffer(self.dev.device, self.handle, None)
            track("framebuffer", -1)
            self.handle = None


class Sampler:
    """Clamp-to-edge sampler: nearest-neighbour (the resolve pass uses texelFetch)
    or, with ``linear=True``, bilinear (GUI textures)."""

    def __init__(self, device: Device, linear: bool = False):
        self.dev = device
        filt = vk.VK_FILTER_LINEAR if linear else vk.VK_FILTER_NEAREST
        info = vk.VkSamplerCreateInfo(
            magFilter=filt, minFilter=filt,
            mipmapMode=vk.VK_SAMPLER_MIPMAP_MODE_NEAREST,
            addressModeU=vk.VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE,
            addressModeV=vk.VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE,
            addressModeW=vk.VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE,
            maxLod=0.0, borderColor=vk.VK_BORDER_COLOR_FLOAT_TRANSPARENT_BLACK)
        self.handle = call(vk.vkCreateSampler, device.device, info, None)
        track("sampler", 1)

    def destroy(self):
        if self.handle is not None:
            vk.vkDestroySampler(self.dev.device, self.handle, None)
            track("sampler", -1)
            self.handle = None


class SetLayout:
    def __init__(self, device: Device, bindings: tuple[Binding, ...]):
        self.dev = device
        self.bindings = bindings
        bs = [vk.VkDescriptorSetLayoutBinding(binding=b.binding, descriptorType=_DESC_TYPES[b.type],
                                              descriptorCount=1, stageFlags=_stages(b.stages))
              for b in bindings]
        info = vk.VkDescriptorSetLayoutCreateInfo(bindingCount=len(bs), pBindings=bs)
        self.handle = call(vk.vkCreateDescriptorSetLayout, device.device, info, None)
        track("descriptor_set_layout", 1)

    def destroy(self):
        if self.handle is not None:
            vk.vkDestroyDescriptorSetLayout(self.dev.device, self.handle, None)
            track("descriptor_set_layout", -1)
            self.handle = None


class PipelineLayout:
    def __init__(self, device: Device, desc: LayoutDesc, set_layouts: list[SetLayout]):
        self.dev = device
        self.desc = desc
        self.set_layouts = set_layouts
        self.push_stages = _stages(desc.push_stages)
        ranges = ([vk.VkPushConstantRange(stageFlags=self.push_stages, offset=0, size=desc.push_bytes)]
                  if desc.push_bytes else None)
        handles = [s.handle for s in set_layouts]
        info = vk.VkPipelineLayoutCreateInfo(setLayoutCount=len(handles), pSetLayouts=handles or None,
                                             pushConstantRangeCount=1 if ranges else 0,
                                             pPushConstantRanges=ranges)
        self.handle = call(vk.vkCreatePipelineLayout, device.device, info, None)
        track("pipeline_layout", 1)

    def destroy(self):
        if self.handle is not None:
            vk.vkDestroyPipelineLayout(self.dev.device, self.handle, None)
            track("pipeline_layout", -1)
            self.handle = None


class DescriptorSet:
    """One descriptor set from its own small pool (a handful per renderer)."""

    def __init__(self, device: Device, layout: SetLayout):
        self.dev = device
        self.layout = layout
        counts = {}
        for b in layout.bindings:
            counts[b.type] = counts.get(b.type, 0) + 1
        sizes = [vk.VkDescriptorPoolSize(type=_DESC_TYPES[t], descriptorCount=c) for t, c in counts.items()]
        pinfo = vk.VkDescriptorPoolCreateInfo(maxSets=1, poolSizeCount=len(sizes), pPoolSizes=sizes)
        self.pool = call(vk.vkCreateDescriptorPool, device.device, pinfo, None)
        track("descriptor_pool", 1)
        layouts = [layout.handle]
        ainfo = vk.VkDescriptorSetAllocateInfo(descriptorPool=self.pool, descriptorSetCount=1,
                                               pSetLayouts=layouts)
        self.handle = None
        try:
            self.handle = call(vk.vkAllocateDescriptorSets, device.device, ainfo)[0]
        except BaseException:
            self.destroy()
            raise

    def write(self, entries: dict):
        """``entries``: binding -> Buffer or (Buffer, offset, range) (uniform/storage;
        offset must be a multiple of the device's min offset alignment) or
        (Image, Sampler) (sampled)."""
        writes, keep = [], []
        types = {b.binding: b.type for b in self.layout.bindings}
        for binding, res in entries.items():
            t = types[binding]
            if t in ("uniform", "storage"):
                buf, off, rng = res if isinstance(res, tuple) else (res, 0, res.size)
                bi = vk.VkDescriptorBufferInfo(buffer=buf.handle, offset=int(off), range=int(rng))
                keep.append(bi)
                writes.append(vk.VkWriteDescriptorSet(dstSet=self.handle, dstBinding=binding, dstArrayElement=0,
                                                      descriptorCount=1, descriptorType=_DESC_TYPES[t],
                                                      pBufferInfo=[bi]))
            else:
                img, sampler = res
                layout = (vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL if t == "sampled"
                          else vk.VK_IMAGE_LAYOUT_GENERAL)
                ii = vk.VkDescriptorImageInfo(sampler=sampler.handle if sampler else None,
                                              imageView=img.view, imageLayout=layout)
                keep.append(ii)
                writes.append(vk.VkWriteDescriptorSet(dstSet=self.handle, dstBinding=binding, dstArrayElement=0,
                                                      descriptorCount=1, descriptorType=_DESC_TYPES[t],
                                                      pImageInfo=[ii]))
        vk.vkUpdateDescriptorSets(self.dev.device, len(writes), writes, 0, None)
        del keep

    def destroy(self):
        if self.pool is not None:
            vk.vkDestroyDescriptorPool(self.dev.device, self.pool, None)  # frees the set
            track("descriptor_pool", -1)
            self.pool = None
            self.handle = None


def _specialization(spec):
    if not spec:
        return None, None
    entries = [vk.VkSpecializationMapEntry(constantID=cid, offset=4 * i, size=4) for i, (cid, _) in enumerate(spec)]
    data = vk.ffi.new("char[]", struct.pack(f"<{len(spec)}i", *[v for _, v in spec]))
    info = vk.VkSpecializationInfo(mapEntryCount=len(entries), pMapEntries=entries,
                                   dataSize=4 * len(spec), pData=data)
    return info, (entries, data)


class ShaderModule:
    def __init__(self, device: Device, name: str):
        self.dev = device
        self.name = name
        code = spirv_path(name).read_bytes()
        info = vk.VkShaderModuleCreateInfo(codeSize=len(code), pCode=code)
        self.handle = call(vk.vkCreateShaderModule, device.device, info, None)
        track("shader_module", 1)

    def destroy(self):
        if self.handle is not None:
            vk.vkDestroyShaderModule(self.dev.device, self.handle, None)
            track("shader_module", -1)
            self.handle = None


class Pipeline:
    def __init__(self, handle, layout: PipelineLayout, compute: bool):
        self.handle = handle
        self.layout = layout
        self.compute = compute


class PipelineCache:
    """Creates and owns render passes, layouts, shader modules and pipelines,
    each cached by its description; :meth:`destroy` frees everything."""

    def __init__(self, device: Device):
        self.dev = device
        self._render_passes: dict = {}
        self._set_layouts: dict = {}
        self._layouts: dict = {}
        self._modules: dict = {}
        self._pipelines: dict = {}

    def render_pass(self, desc: RenderPassDesc) -> RenderPass:
        rp = self._render_passes.get(desc)
        if rp is None:
            rp = self._render_passes[desc] = RenderPass(self.dev, desc)
        return rp

    def set_layout(self, bindings: tuple[Binding, ...]) -> SetLayout:
        sl = self._set_layouts.get(bindings)
        if sl is None:
            sl = self._set_layouts[bindings] = SetLayout(self.dev, bindings)
        return sl

    def layout(self, desc: LayoutDesc) -> PipelineLayout:
        pl = self._layouts.get(desc)
        if pl is None:
            pl = self._layouts[desc] = PipelineLayout(self.dev, desc, [self.set_layout(s) for s in desc.sets])
        return pl

    def module(self, name: str) -> ShaderModule:
        m = self._modules.get(name)
        if m is None:
            m = self._modules[name] = ShaderModule(self.dev, name)
        return m

    def pipeline(self, desc) -> Pipeline:
        p = self._pipelines.get(desc)
        if p is None:
            p = self._pipelines[desc] = (self._compute(desc) if isinstance(desc, ComputeDesc)
                                         else self._graphics(desc))
        return p

    def __len__(self):
        return len(self._pipelines)

    def _compute(self, desc: ComputeDesc) -> Pipeline:
        layout = self.layout(desc.layout)
        spec, keep = _specialization(desc.spec)
        stage = vk.VkPipelineShaderStageCreateInfo(stage=vk.VK_SHADER_STAGE_COMPUTE_BIT,
                                                   module=self.module(desc.comp).handle, pName="main",
                                                   pSpecializationInfo=spec)
        info = vk.VkComputePipelineCreateInfo(stage=stage, layout=layout.handle, basePipelineIndex=-1)
        handle = call(vk.vkCreateComputePipelines, self.dev.device, None, 1, [info], None)[0]
        del keep
        track("pipeline", 1)
        return Pipeline(handle, layout, compute=True)

    def _graphics(self, d: GraphicsDesc) -> Pipeline:
        layout = self.layout(d.layout)
        rp = self.render_pass(d.render_pass)
        spec, keep_spec = _specialization(d.spec)
        stages = [
            vk.VkPipelineShaderStageCreateInfo(stage=vk.VK_SHADER_STAGE_VERTEX_BIT,
                                               module=self.module(d.vert).handle, pName="main",
                                               pSpecializationInfo=spec),
            vk.VkPipelineShaderStageCreateInfo(stage=vk.VK_SHADER_STAGE_FRAGMENT_BIT,
                                               module=self.module(d.frag).handle, pName="main",
                                               pSpecializationInfo=spec),
        ]
        vb = [vk.VkVertexInputBindingDescription(
            binding=b.binding, stride=b.stride,
            inputRate=vk.VK_VERTEX_INPUT_RATE_INSTANCE if b.per_instance else vk.VK_VERTEX_INPUT_RATE_VERTEX)
            for b in d.bindings]
        va = [vk.VkVertexInputAttributeDescription(location=a.location, binding=a.binding,
                                                   format=_VERTEX_FORMATS[a.format], offset=a.offset)
              for a in d.attributes]
        vinput = vk.VkPipelineVertexInputStateCreateInfo(
            vertexBindingDescriptionCount=len(vb), pVertexBindingDescriptions=vb or None,
            vertexAttributeDescriptionCount=len(va), pVertexAttributeDescriptions=va or None)
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
        rgba = (vk.VK_COLOR_COMPONENT_R_BIT | vk.VK_COLOR_COMPONENT_G_BIT | vk.VK_COLOR_COMPONENT_B_BIT
                | vk.VK_COLOR_COMPONENT_A_BIT)
        blends = []
        for i in range(len(d.render_pass.colors)):
            add = d.blend_add[i] if i < len(d.blend_add) else False
            under = d.blend_under[i] if i < len(d.blend_under) else False
            one, inv = vk.VK_BLEND_FACTOR_ONE, vk.VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA
            # three modes: additive (ONE, ONE), "over" (SRC_ALPHA, 1 - SRC_ALPHA: the GUI),
            # "under" (1 - DST_ALPHA, ONE: front-to-back Gaussians, premultiplied colour)
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
        cb = vk.VkPipelineColorBlendStateCreateInfo(attachmentCount=len(blends), pAttachments=blends or None)
        dyn_states = [vk.VK_DYNAMIC_STATE_VIEWPORT, vk.VK_DYNAMIC_STATE_SCISSOR]
        dyn = vk.VkPipelineDynamicStateCreateInfo(dynamicStateCount=2, pDynamicStates=dyn_states)
        info = vk.VkGraphicsPipelineCreateInfo(
            stageCount=2, pStages=stages, pVertexInputState=vinput, pInputAssemblyState=ia,
            pViewportState=vps, pRasterizationState=rs, pMultisampleState=ms, pDepthStencilState=ds,
            pColorBlendState=cb, pDynamicState=dyn, layout=layout.handle, renderPass=rp.handle,
            subpass=0, basePipelineIndex=-1)
        handle = call(vk.vkCreateGraphicsPipelines, self.dev.device, None, 1, [info], None)[0]
        del keep_spec, stages, vb, va, blends
        track("pipeline", 1)
        return Pipeline(handle, layout, compute=False)

    def destroy(self):
        d = self.dev.device
        for p in self._pipelines.values():
            vk.vkDestroyPipeline(d, p.handle, None)
            track("pipeline", -1)
        self._pipelines.clear()
        for m in self._modules.values():
            m.destroy()
        self._modules.clear()
        for pl in self._layouts.values():
            pl.destroy()
        self._layouts.clear()
        for sl in self._set_layouts.values():
            sl.destroy()
        self._set_layouts.clear()
        for rp in self._render_passes.values():
            rp.destroy()
        self._render_passes.clear()
