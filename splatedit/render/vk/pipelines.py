"""The pipeline cache: render passes, descriptor-set layouts, pipeline
layouts, shader modules and pipelines, each created once per description and
owned by a :class:`PipelineCache`; compute pipelines are built here, graphics
pipelines in :mod:`splatedit.render.vk.graphics`.

The descriptions are frozen dataclasses: :class:`~.passes.RenderPassDesc`
(:mod:`~splatedit.render.vk.passes`), :class:`~.descriptors.LayoutDesc` /
:class:`~.descriptors.Binding` (:mod:`~splatedit.render.vk.descriptors`),
:class:`~.graphics.GraphicsDesc` and :class:`ComputeDesc`.
"""

from __future__ import annotations

from dataclasses import dataclass

import vulkan as vk

from splatedit.render.vk.core import Device
from splatedit.render.vk.handles import call, track
from splatedit.render.vk.descriptors import Binding, LayoutDesc, PipelineLayout, SetLayout
from splatedit.render.vk.graphics import GraphicsDesc, create_graphics_pipeline
from splatedit.render.vk.passes import RenderPass, RenderPassDesc
from splatedit.render.vk.shaders import ShaderModule, specialization, stage_info


@dataclass(frozen=True)
class ComputeDesc:
    """A compute pipeline by description: shader by SPIR-V name, layout and specialisation constants
    ((constant_id, int32 value) pairs)."""
    comp: str                                   # spirv name, e.g. "gs_sort.comp"
    layout: LayoutDesc
    spec: tuple[tuple[int, int], ...] = ()      # (constant_id, int32 value)


class Pipeline:
    """A VkPipeline (owned by the :class:`PipelineCache` that made it) with its layout."""

    def __init__(self, handle, layout: PipelineLayout, compute: bool):
        self.handle = handle
        self.layout = layout
        self.compute = compute


class PipelineCache:
    """Creates and owns render passes, layouts, shader modules and pipelines,
    each cached by its description; :meth:`destroy` frees everything."""

    def __init__(self, device: Device):
        self.dev = device
        self._render_passes: dict[RenderPassDesc, RenderPass] = {}
        self._set_layouts: dict[tuple[Binding, ...], SetLayout] = {}
        self._layouts: dict[LayoutDesc, PipelineLayout] = {}
        self._modules: dict[str, ShaderModule] = {}
        self._pipelines: dict[GraphicsDesc | ComputeDesc, Pipeline] = {}

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

    def pipeline(self, desc: GraphicsDesc | ComputeDesc) -> Pipeline:
        p = self._pipelines.get(desc)
        if p is None:
            layout = self.layout(desc.layout)
            if isinstance(desc, ComputeDesc):
                handle = self._compute(desc, layout)
            else:
                handle = create_graphics_pipeline(self.dev, desc, layout, self.render_pass(desc.render_pass),
                                                  self.module(desc.vert), self.module(desc.frag))
            track("pipeline", 1)
            p = self._pipelines[desc] = Pipeline(handle, layout, compute=isinstance(desc, ComputeDesc))
        return p

    def __len__(self):
        return len(self._pipelines)

    def _compute(self, desc: ComputeDesc, layout: PipelineLayout):
        spec, keep = specialization(desc.spec)
        stage = stage_info(vk.VK_SHADER_STAGE_COMPUTE_BIT, self.module(desc.comp), spec)
        info = vk.VkComputePipelineCreateInfo(stage=stage, layout=layout.handle, basePipelineIndex=-1)
        handle = call(vk.vkCreateComputePipelines, self.dev.device, None, 1, [info], None)[0]
        del keep
        return handle

    def destroy(self):
        """Destroy every pipeline, module, layout and render pass made here (idempotent)."""
        for p in self._pipelines.values():
            vk.vkDestroyPipeline(self.dev.device, p.handle, None)
            track("pipeline", -1)
        self._pipelines.clear()
        for objs in (self._modules, self._layouts, self._set_layouts, self._render_passes):
            for o in objs.values():
                o.destroy()
            objs.clear()
