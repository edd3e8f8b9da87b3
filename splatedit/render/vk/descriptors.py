"""Descriptor-set layouts, pipeline layouts and descriptor sets.

Layouts are described by frozen dataclasses (:class:`Binding`,
:class:`LayoutDesc`) so that a :class:`~splatedit.render.vk.pipelines.PipelineCache`
can key them by description; :class:`DescriptorSet` binds buffers and images
to a set layout's bindings.
"""

from __future__ import annotations

from dataclasses import dataclass

import vulkan as vk

from splatedit.render.vk.core import Device
from splatedit.render.vk.handles import call, flag_bits, release, track

_STAGE_BITS = {
    "vert": vk.VK_SHADER_STAGE_VERTEX_BIT,
    "frag": vk.VK_SHADER_STAGE_FRAGMENT_BIT,
    "comp": vk.VK_SHADER_STAGE_COMPUTE_BIT,
}

_DESC_TYPES = {
    "uniform": vk.VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER,
    "storage": vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    "sampled": vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
    "storage_image": vk.VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
}


def shader_stages(names: str) -> int:
    """VkShaderStageFlags of ``names``, e.g. ``"vert|frag"``."""
    return flag_bits(_STAGE_BITS, names, "shader stage")


@dataclass(frozen=True)
class Binding:
    """One descriptor binding: its number, type (``uniform``, ``storage``, ``sampled``, ``storage_image``)
    and the shader stages that see it (e.g. ``"vert|frag"``)."""
    binding: int
    type: str       # "uniform" | "storage" | "sampled" | "storage_image"
    stages: str     # "vert|frag"


@dataclass(frozen=True)
class LayoutDesc:
    """A pipeline layout by description: descriptor sets (tuples of :class:`Binding`), push-constant
    bytes and stages; pipelines and layouts are cached by this value."""
    sets: tuple[tuple[Binding, ...], ...] = ()
    push_bytes: int = 0
    push_stages: str = "vert"


class SetLayout:
    """A VkDescriptorSetLayout for ``bindings`` on ``device``."""
    def __init__(self, device: Device, bindings: tuple[Binding, ...]):
        self.dev = device
        self.bindings = bindings
        bs = [vk.VkDescriptorSetLayoutBinding(binding=b.binding, descriptorType=_DESC_TYPES[b.type],
                                              descriptorCount=1, stageFlags=shader_stages(b.stages))
              for b in bindings]
        info = vk.VkDescriptorSetLayoutCreateInfo(bindingCount=len(bs), pBindings=bs)
        self.handle = call(vk.vkCreateDescriptorSetLayout, device.device, info, None)
        track("descriptor_set_layout", 1)

    def destroy(self):
        release(self, "handle", vk.vkDestroyDescriptorSetLayout, "descriptor_set_layout")


class PipelineLayout:
    """A VkPipelineLayout made from a :class:`LayoutDesc` and its set layouts."""
    def __init__(self, device: Device, desc: LayoutDesc, set_layouts: list[SetLayout]):
        self.dev = device
        self.desc = desc
        self.set_layouts = set_layouts
        self.push_stages = shader_stages(desc.push_stages)
        ranges = ([vk.VkPushConstantRange(stageFlags=self.push_stages, offset=0, size=desc.push_bytes)]
                  if desc.push_bytes else None)
        handles = [s.handle for s in set_layouts]
        info = vk.VkPipelineLayoutCreateInfo(setLayoutCount=len(handles), pSetLayouts=handles or None,
                                             pushConstantRangeCount=1 if ranges else 0,
                                             pPushConstantRanges=ranges)
        self.handle = call(vk.vkCreatePipelineLayout, device.device, info, None)
        track("pipeline_layout", 1)

    def destroy(self):
        release(self, "handle", vk.vkDestroyPipelineLayout, "pipeline_layout")


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
            info = {}
            if t in ("uniform", "storage"):
                buf, off, rng = res if isinstance(res, tuple) else (res, 0, res.size)
                info["pBufferInfo"] = [vk.VkDescriptorBufferInfo(buffer=buf.handle, offset=int(off),
                                                                 range=int(rng))]
            else:
                img, sampler = res
                layout = (vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL if t == "sampled"
                          else vk.VK_IMAGE_LAYOUT_GENERAL)
                info["pImageInfo"] = [vk.VkDescriptorImageInfo(sampler=sampler.handle if sampler else None,
                                                               imageView=img.view, imageLayout=layout)]
            keep.append(info)
            writes.append(vk.VkWriteDescriptorSet(dstSet=self.handle, dstBinding=binding, dstArrayElement=0,
                                                  descriptorCount=1, descriptorType=_DESC_TYPES[t], **info))
        vk.vkUpdateDescriptorSets(self.dev.device, len(writes), writes, 0, None)
        del keep

    def destroy(self):
        self.handle = None                  # freed with its pool
        release(self, "pool", vk.vkDestroyDescriptorPool, "descriptor_pool")
