"""A swapchain image seen as a render target (GPU path of the presenter).

:class:`SwapchainTarget` gives an image owned by the swapchain what the
render passes need from an :class:`~splatedit.render.vk.resources.Image`:
``handle``, ``view``, ``aspect``, ``layout`` (kept up to date by render passes
and barriers), ``width``/``height`` and ``format`` (a key of
``resources.FORMATS``).  It also keeps the framebuffers made for it, one per
render pass, so a caller can ask ``target.framebuffer(render_pass)`` every
frame; they are destroyed with the target when the swapchain is re-created.
"""

from __future__ import annotations

import vulkan as vk

from splatedit.render.vk.core import Device
from splatedit.render.vk.handles import call, track
from splatedit.render.vk.passes import Framebuffer

#: swapchain VkFormat -> name in resources.FORMATS
FORMAT_NAMES = {vk.VK_FORMAT_B8G8R8A8_UNORM: "bgra8", vk.VK_FORMAT_R8G8B8A8_UNORM: "rgba8"}


class SwapchainTarget:
    """One swapchain image with an image view (the image itself is the swapchain's)."""

    def __init__(self, device: Device, image, vk_format: int, width: int, height: int, index: int):
        self.dev = device
        self.handle = image
        self.index = index
        self.width, self.height = int(width), int(height)
        self.vk_format = vk_format
        self.format = FORMAT_NAMES[vk_format]
        self.aspect = vk.VK_IMAGE_ASPECT_COLOR_BIT
        self.layout = vk.VK_IMAGE_LAYOUT_UNDEFINED
        self._framebuffers: dict = {}
        sub = vk.VkImageSubresourceRange(aspectMask=self.aspect, baseMipLevel=0, levelCount=1,
                                         baseArrayLayer=0, layerCount=1)
        info = vk.VkImageViewCreateInfo(image=image, viewType=vk.VK_IMAGE_VIEW_TYPE_2D, format=vk_format,
                                        subresourceRange=sub)
        self.view = call(vk.vkCreateImageView, device.device, info, None)
        track("image_view", 1)

    def framebuffer(self, render_pass) -> Framebuffer:
        """The framebuffer of this image for ``render_pass`` (created once, kept)."""
        fb = self._framebuffers.get(render_pass)
        if fb is None:
            fb = self._framebuffers[render_pass] = Framebuffer(self.dev, render_pass, [self], self.width,
                                                               self.height)
        return fb

    def destroy(self) -> None:
        for fb in self._framebuffers.values():
            fb.destroy()
        self._framebuffers.clear()
        if self.view is not None:
            vk.vkDestroyImageView(self.dev.device, self.view, None)
            track("image_view", -1)
            self.view = None
