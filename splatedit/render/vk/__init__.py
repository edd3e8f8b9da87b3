"""splatedit.render.vk: a thin, safe layer over the ``vulkan`` python bindings.

Raw ``vk*`` calls live only in this package.  It provides

* :class:`Device` - instance + device selection (env var ``SPLATEDIT_DEVICE``
  picks a device by name substring; :class:`DeviceNotFoundError` lists the
  devices), ``VK_LAYER_KHRONOS_validation`` with a debug messenger when
  ``SPLATEDIT_VALIDATION=1`` (messages are collected; read them with
  :func:`drain_validation_messages`), one graphics+compute queue;
* VkResult -> :class:`VulkanError` (a :class:`splatedit.errors.SplatEditError`),
  including success codes such as ``VK_TIMEOUT`` that the bindings raise;
* :class:`Buffer` / :class:`Image` with staging uploads and readback;
* render passes and framebuffers (``passes``), descriptor sets and layouts
  (``descriptors``), shaders (``shaders``), graphics pipelines
  (``graphics``), all cached by their description in a
  :class:`PipelineCache` (``pipelines``, which also builds compute pipelines);
* :func:`live_handles` - a count of every live Vulkan object by kind, for leak
  tests; :func:`devices_created` - devices created so far in this process.  Everything is destroyed explicitly, in reverse order of creation.
"""

from splatedit.render.vk.core import WHOLE_SIZE, Device, drain_validation_messages, list_devices, validation_enabled
from splatedit.render.vk.handles import DeviceNotFoundError, VulkanError, devices_created, live_handles
from splatedit.render.vk.resources import Buffer, Image, Sampler, readback_array
from splatedit.render.vk.commands import CommandBuffer, QueryPool
from splatedit.render.vk.descriptors import Binding, DescriptorSet, LayoutDesc
from splatedit.render.vk.passes import Attachment, Framebuffer, RenderPassDesc
from splatedit.render.vk.shaders import spirv_path
from splatedit.render.vk.graphics import GraphicsDesc, VertexAttribute, VertexBinding
from splatedit.render.vk.pipelines import ComputeDesc, PipelineCache
from splatedit.render.vk.capabilities import SubgroupProperties, is_cpu_device, subgroup_properties

__all__ = [
    "WHOLE_SIZE", "Device", "DeviceNotFoundError", "VulkanError", "devices_created", "drain_validation_messages",
    "list_devices", "live_handles", "validation_enabled", "Buffer", "Image", "readback_array",
    "CommandBuffer", "QueryPool", "Attachment", "Binding", "ComputeDesc", "DescriptorSet", "Framebuffer",
    "GraphicsDesc", "LayoutDesc", "PipelineCache", "RenderPassDesc", "Sampler", "VertexAttribute",
    "VertexBinding", "spirv_path", "SubgroupProperties", "is_cpu_device", "subgroup_properties",
]
