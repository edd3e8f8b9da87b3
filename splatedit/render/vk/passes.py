"""Render passes (described by :class:`RenderPassDesc`, cached by
:class:`~splatedit.render.vk.pipelines.PipelineCache`) and framebuffers."""

from __future__ import annotations

from dataclasses import dataclass

import vulkan as vk

from splatedit.render.vk.commands import IMAGE_LAYOUTS
from splatedit.render.vk.core import Device
from splatedit.render.vk.handles import call, release, track
from splatedit.render.vk.resources import FORMATS

_LOAD_OPS = {"clear": vk.VK_ATTACHMENT_LOAD_OP_CLEAR, "load": vk.VK_ATTACHMENT_LOAD_OP_LOAD,
             "dont_care": vk.VK_ATTACHMENT_LOAD_OP_DONT_CARE}


@dataclass(frozen=True)
class Attachment:
    """One render-pass attachment: format name, load op, initial and final layout names, store."""
    format: str                     # key of resources.FORMATS
    load: str = "clear"             # "clear" | "load" | "dont_care"
    initial: str = "undefined"      # layout name (commands.IMAGE_LAYOUTS) when load == "load"
    final: str = "color"            # layout after the pass
    store: bool = True


@dataclass(frozen=True)
class RenderPassDesc:
    """A render pass by description: colour attachments, an optional depth attachment (read-only or not)."""
    colors: tuple[Attachment, ...] = ()
    depth: Attachment | None = None
    depth_read_only: bool = False


def _dependencies() -> list:
    """Subpass dependencies: everything earlier (passes, copies, compute)
    before this pass, and this pass before everything later (passes,
    samplers, copies)."""
    gfx = (vk.VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | vk.VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT
           | vk.VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT)
    att_rw = (vk.VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | vk.VK_ACCESS_COLOR_ATTACHMENT_READ_BIT
              | vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT
              | vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT)
    outside = (vk.VK_PIPELINE_STAGE_TRANSFER_BIT | vk.VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT
               | vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | gfx)
    outside_acc = (vk.VK_ACCESS_TRANSFER_READ_BIT | vk.VK_ACCESS_TRANSFER_WRITE_BIT
                   | vk.VK_ACCESS_SHADER_READ_BIT | vk.VK_ACCESS_SHADER_WRITE_BIT | att_rw)
    return [
        # the subpass side names graphics stages only
        vk.VkSubpassDependency(srcSubpass=vk.VK_SUBPASS_EXTERNAL, dstSubpass=0,
                               srcStageMask=outside, dstStageMask=gfx | vk.VK_PIPELINE_STAGE_VERTEX_SHADER_BIT
                               | vk.VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT | vk.VK_PIPELINE_STAGE_VERTEX_INPUT_BIT
                               | vk.VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT,
                               srcAccessMask=outside_acc,
                               dstAccessMask=att_rw | vk.VK_ACCESS_SHADER_READ_BIT
                               | vk.VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT | vk.VK_ACCESS_INDIRECT_COMMAND_READ_BIT
                               | vk.VK_ACCESS_UNIFORM_READ_BIT),
        vk.VkSubpassDependency(srcSubpass=0, dstSubpass=vk.VK_SUBPASS_EXTERNAL,
                               srcStageMask=gfx, dstStageMask=outside,
                               srcAccessMask=att_rw, dstAccessMask=outside_acc),
    ]


class RenderPass:
    """A VkRenderPass made from a :class:`RenderPassDesc` (one subpass, full dependencies before and after)."""
    def __init__(self, device: Device, desc: RenderPassDesc):
        self.dev = device
        self.desc = desc
        atts, self.final_layouts = [], []
        all_atts = list(desc.colors) + ([desc.depth] if desc.depth else [])
        for a in all_atts:
            atts.append(vk.VkAttachmentDescription(
                format=FORMATS[a.format], samples=vk.VK_SAMPLE_COUNT_1_BIT, loadOp=_LOAD_OPS[a.load],
                storeOp=vk.VK_ATTACHMENT_STORE_OP_STORE if a.store else vk.VK_ATTACHMENT_STORE_OP_DONT_CARE,
                stencilLoadOp=vk.VK_ATTACHMENT_LOAD_OP_DONT_CARE,
                stencilStoreOp=vk.VK_ATTACHMENT_STORE_OP_DONT_CARE,
                initialLayout=IMAGE_LAYOUTS[a.initial if a.load == "load" else "undefined"],
                finalLayout=IMAGE_LAYOUTS[a.final]))
            self.final_layouts.append(IMAGE_LAYOUTS[a.final])
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
        deps = _dependencies()
        info = vk.VkRenderPassCreateInfo(attachmentCount=len(atts), pAttachments=atts, subpassCount=1,
                                         pSubpasses=[subpass], dependencyCount=len(deps), pDependencies=deps)
        self.handle = call(vk.vkCreateRenderPass, device.device, info, None)
        track("render_pass", 1)

    def destroy(self):
        release(self, "handle", vk.vkDestroyRenderPass, "render_pass")


class Framebuffer:
    """A VkFramebuffer of ``attachments`` (objects with ``.view`` and ``.layout``) for a render pass, in pixels."""
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
        release(self, "handle", vk.vkDestroyFramebuffer, "framebuffer")
