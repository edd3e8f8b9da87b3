"""Present CPU-side RGBA frames in a window through a Vulkan swapchain.

:class:`SwapchainPresenter` owns a small Vulkan context of its own: a
:class:`~splatedit.render.vk.core.Device` created with the surface
extensions glfw asks for and ``VK_KHR_swapchain`` (so device selection,
``SPLATEDIT_DEVICE``, ``SPLATEDIT_VALIDATION``, error mapping and handle
accounting are those of the renderer), a window surface whose presentation
support is checked on the device's queue, a swapchain and one persistently
mapped staging buffer.  Every :meth:`~SwapchainPresenter.present` copies an
``(h, w, 4)`` uint8 RGBA frame into the staging buffer, records
``vkCmdCopyBufferToImage`` into the acquired swapchain image (transfer-dst
layout, then present-src) and presents.

Why a copy from host memory rather than sharing the renderer's VkImage: the
renderer hands the editor its final frame as a numpy array anyway (it reads
back for pick maps and screenshots), lavapipe's "device memory" *is* host
memory, and keeping the presenter independent of the renderer's device lets
both evolve separately.  The cost is one 4-byte-per-pixel memcpy (~2-4 ms at
1280x720), small next to the splat passes.

Swapchain life cycle: ``VK_ERROR_OUT_OF_DATE_KHR`` and ``VK_SUBOPTIMAL_KHR``
(which the python bindings *raise* as :class:`vk.VkErrorOutOfDateKhr` /
:class:`vk.VkSuboptimalKhr`) mark the swapchain for re-creation; a window
with a zero-sized framebuffer (minimized) skips presenting.  FIFO (vsync) is
the default present mode; ``vsync=False`` asks for MAILBOX, then IMMEDIATE.

Validation: as for every :class:`~splatedit.render.vk.core.Device`
(``SPLATEDIT_VALIDATION=1``); messages are collected by
:func:`splatedit.render.vk.core.drain_validation_messages`.  Every handle is
counted in :func:`splatedit.render.vk.handles.live_handles`.
"""

from __future__ import annotations

import numpy as np
import vulkan as vk

from splatedit.errors import SplatEditError
from splatedit.render.vk.core import Device
from splatedit.render.vk.handles import VulkanError, result_name, call, track
from splatedit.render.vk.resources import Buffer
from splatedit.render.vk.swapchain_target import SwapchainTarget

_UINT64_MAX = 0xFFFFFFFFFFFFFFFF

_INSTANCE_FUNCTIONS = (
    "vkDestroySurfaceKHR", "vkGetPhysicalDeviceSurfaceSupportKHR",
    "vkGetPhysicalDeviceSurfaceCapabilitiesKHR", "vkGetPhysicalDeviceSurfaceFormatsKHR",
    "vkGetPhysicalDeviceSurfacePresentModesKHR")
_DEVICE_FUNCTIONS = (
    "vkCreateSwapchainKHR", "vkDestroySwapchainKHR", "vkGetSwapchainImagesKHR",
    "vkAcquireNextImageKHR", "vkQueuePresentKHR")


class PresentError(SplatEditError):
    """The window cannot be shown with Vulkan (no device, no surface...)."""


class SwapchainPresenter:
    """A Vulkan swapchain on a glfw window that shows numpy RGBA frames.

    Args:
        window: the glfw window (created with ``GLFW_CLIENT_API = GLFW_NO_API``).
        vsync: FIFO present mode when True (default), else MAILBOX/IMMEDIATE.
        validation: enable the validation layer (default: ``SPLATEDIT_VALIDATION``,
            as :class:`~splatedit.render.vk.core.Device`).
        device_name: substring of the device name (default: ``SPLATEDIT_DEVICE``,
            as :class:`~splatedit.render.vk.core.Device`).
    """

    def __init__(self, window, *, vsync: bool = True, validation: bool | None = None,
                 device_name: str | None = None):
        import glfw
        self._glfw = glfw
        self.window = window
        self.vsync = vsync
        self.dev: Device | None = None
        self.surface = None
        self.swapchain = None
        self.extent = (0, 0)
        self.needs_recreate = False
        self.frames_presented = 0
        self._images = []
        self.targets: list[SwapchainTarget] = []   # the images as render targets (GPU path)
        self.gpu_targets = False                   # True when the images can be colour attachments
        self.can_blit = False
        self._render_done = []
        self._acquired = None
        self._fence = None
        self._cmd = None
        self._staging: Buffer | None = None
        try:
            exts = list(glfw.get_required_instance_extensions() or [])
            if not exts:
                raise PresentError("glfw reports no Vulkan surface support (no Vulkan loader or display)")
            self.dev = Device(device_name=device_name, validation=validation, instance_extensions=exts,
                              device_extensions=[vk.VK_KHR_SWAPCHAIN_EXTENSION_NAME])
            self.validation = self.dev.validation
            self.device_name = self.dev.name
            self._fn_inst = {n: vk.vkGetInstanceProcAddr(self.dev.instance, n) for n in _INSTANCE_FUNCTIONS}
            self._fn = {n: vk.vkGetDeviceProcAddr(self.dev.device, n) for n in _DEVICE_FUNCTIONS}
            self._create_surface()
            self._check_present_support()
            self._create_sync()
            self._create_swapchain()
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------ accessors
    @property
    def instance(self):
        return None if self.dev is None else self.dev.instance

    @property
    def device(self):
        """The raw VkDevice (None once closed)."""
        return None if self.dev is None else self.dev.device

    @property
    def physical(self):
        return self.dev.physical

    @property
    def queue(self):
        return self.dev.queue

    @property
    def queue_family(self) -> int:
        return self.dev.queue_family

    # ------------------------------------------------------------ creation
    def _create_surface(self) -> None:
        ptr = vk.ffi.new("VkSurfaceKHR*")
        rc = self._glfw.create_window_surface(self.instance, self.window, None, ptr)
        if rc != 0:
            raise PresentError(f"glfwCreateWindowSurface failed (VkResult {rc})")
        self.surface = ptr[0]
        track("surface", 1)

    def _check_present_support(self) -> None:
        supported = call(self._fn_inst["vkGetPhysicalDeviceSurfaceSupportKHR"], self.physical,
                         self.queue_family, self.surface, name="vkGetPhysicalDeviceSurfaceSupportKHR")
        if not supported:
            raise PresentError(f"the Vulkan device {self.device_name!r} cannot present to this window "
                               f"from its queue family {self.queue_family} (choose another device "
                               "with SPLATEDIT_DEVICE)")

    def _create_sync(self) -> None:
        d = self.device
        self._cmd = call(vk.vkAllocateCommandBuffers, d, vk.VkCommandBufferAllocateInfo(
            commandPool=self.dev.command_pool, level=vk.VK_COMMAND_BUFFER_LEVEL_PRIMARY,
            commandBufferCount=1))[0]
        track("command_buffer", 1)
        self._fence = call(vk.vkCreateFence, d,
                           vk.VkFenceCreateInfo(flags=vk.VK_FENCE_CREATE_SIGNALED_BIT), None)
        track("fence", 1)
        self._acquired = self._new_semaphore()

    def _new_semaphore(self):
        s = call(vk.vkCreateSemaphore, self.device, vk.VkSemaphoreCreateInfo(), None)
        track("semaphore", 1)
        return s

    def _destroy_semaphore(self, s) -> None:
        vk.vkDestroySemaphore(self.device, s, None)
        track("semaphore", -1)

    def _surface_caps(self):
        return call(self._fn_inst["vkGetPhysicalDeviceSurfaceCapabilitiesKHR"], self.physical,
                    self.surface, name="vkGetPhysicalDeviceSurfaceCapabilitiesKHR")

    def _surface_extent(self, caps) -> tuple[int, int]:
        w, h = caps.currentExtent.width, caps.currentExtent.height
        if w == 0xFFFFFFFF:
            w, h = self._glfw.get_framebuffer_size(self.window)
            w = min(max(w, caps.minImageExtent.width), caps.maxImageExtent.width)
            h = min(max(h, caps.minImageExtent.height), caps.maxImageExtent.height)
        return int(w), int(h)

    def _create_swapchain(self) -> bool:
        """(Re)create the swapchain for the current surface size; False when minimized."""
        caps = self._surface_caps()
        w, h = self._surface_extent(caps)
        if w == 0 or h == 0:
            return False
        if not caps.supportedUsageFlags & vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT:
            raise PresentError("the window's swapchain images cannot be transfer destinations")
        formats = call(self._fn_inst["vkGetPhysicalDeviceSurfaceFormatsKHR"], self.physical, self.surface,
                       name="vkGetPhysicalDeviceSurfaceFormatsKHR")
        fmt = None
        for want in (vk.VK_FORMAT_B8G8R8A8_UNORM, vk.VK_FORMAT_R8G8B8A8_UNORM):
            fmt = next((f for f in formats if f.format == want), None)
            if fmt is not None:
                break
        if fmt is None:
            raise PresentError("the window offers no 8-bit UNORM RGBA/BGRA surface format")
        self.format = fmt.format
        self._bgra = fmt.format == vk.VK_FORMAT_B8G8R8A8_UNORM
        modes = list(call(self._fn_inst["vkGetPhysicalDeviceSurfacePresentModesKHR"], self.physical,
                          self.surface, name="vkGetPhysicalDeviceSurfacePresentModesKHR"))
        mode = vk.VK_PRESENT_MODE_FIFO_KHR
        if not self.vsync:
            mode = next((m for m in (vk.VK_PRESENT_MODE_MAILBOX_KHR, vk.VK_PRESENT_MODE_IMMEDIATE_KHR)
                         if m in modes), mode)
        self.present_mode = mode
        count = max(caps.minImageCount + 1, 2)
        if caps.maxImageCount:
            count = min(count, caps.maxImageCount)
        old = self.swapchain
        usage = vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT
        self.gpu_targets = bool(caps.supportedUsageFlags & vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT)
        if self.gpu_targets:
            usage |= vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT
        info = vk.VkSwapchainCreateInfoKHR(
            surface=self.surface, minImageCount=count, imageFormat=fmt.format,
            imageColorSpace=fmt.colorSpace, imageExtent=vk.VkExtent2D(width=w, height=h),
            imageArrayLayers=1, imageUsage=usage,
            imageSharingMode=vk.VK_SHARING_MODE_EXCLUSIVE,
            preTransform=caps.currentTransform,
            compositeAlpha=vk.VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR,
            presentMode=mode, clipped=vk.VK_TRUE,
            oldSwapchain=old if old is not None else vk.VK_NULL_HANDLE)
        new = call(self._fn["vkCreateSwapchainKHR"], self.device, info, None, name="vkCreateSwapchainKHR")
        track("swapchain", 1)
        self.swapchain = new
        self._destroy_targets()          # views of the old swapchain's images go before it
        if old is not None:
            self._fn["vkDestroySwapchainKHR"](self.device, old, None)
            track("swapchain", -1)
        self._images = list(call(self._fn["vkGetSwapchainImagesKHR"], self.device, self.swapchain,
                                 name="vkGetSwapchainImagesKHR"))
        for s in self._render_done:
            self._destroy_semaphore(s)
        self._render_done = []
        for _ in self._images:
            self._render_done.append(self._new_semaphore())
        props = vk.vkGetPhysicalDeviceFormatProperties(self.physical, fmt.format)
        src = vk.vkGetPhysicalDeviceFormatProperties(self.physical, vk.VK_FORMAT_R8G8B8A8_UNORM)
        #: a device-resident rgba8 frame can be blitted into the images (blit_into)
        self.can_blit = bool(props.optimalTilingFeatures & vk.VK_FORMAT_FEATURE_BLIT_DST_BIT
                             and src.optimalTilingFeatures & vk.VK_FORMAT_FEATURE_BLIT_SRC_BIT)
        if self.gpu_targets:
            self.targets = [SwapchainTarget(self.dev, img, fmt.format, w, h, i)
                            for i, img in enumerate(self._images)]
        self.extent = (w, h)
        self._ensure_staging(w * h * 4)
        self.needs_recreate = False
        return True

    def _ensure_staging(self, size: int) -> None:
        if self._staging is not None and self._staging.size >= size:
            return
        self._free_staging()
        self._staging = Buffer(self.dev, size, ("transfer_src",), host_visible=True)

    def _destroy_targets(self) -> None:
        for t in self.targets:
            t.destroy()
        self.targets = []

    def _free_staging(self) -> None:
        if self._staging is not None:
            self._staging.destroy()
            self._staging = None

    def _recreate(self) -> bool:
        self.dev.wait_idle()
        # a semaphore may hold a pending signal from an acquire whose index was lost
        self._destroy_semaphore(self._acquired)
        self._acquired = None
        self._acquired = self._new_semaphore()
        return self._create_swapchain()

    # ------------------------------------------------------------- frames
    def framebuffer_size(self) -> tuple[int, int]:
        """The size the next frame should have (the surface's current extent)."""
        w, h = self._glfw.get_framebuffer_size(self.window)
        return int(w), int(h)

    def _acquire(self):
        """Wait for the previous frame, acquire an image; its index, or None when
        nothing can be shown now (minimized, or the swapchain was re-created)."""
        fw, fh = self.framebuffer_size()
        if fw == 0 or fh == 0:
            return None
        if self.needs_recreate or self.swapchain is None or (fw, fh) != self.extent:
            if not self._recreate():
                return None
        d = self.device
        call(vk.vkWaitForFences, d, 1, [self._fence], vk.VK_TRUE, _UINT64_MAX)
        idx_ptr = vk.ffi.new("uint32_t*")
        try:
            self._fn["vkAcquireNextImageKHR"](d, self.swapchain, _UINT64_MAX, self._acquired,
                                              vk.VK_NULL_HANDLE, idx_ptr)
        except vk.VkErrorOutOfDateKhr:
            self._recreate()
            return None
        except vk.VkSuboptimalKhr:
            # the image *was* acquired (suboptimal is a success code): use it, recreate after
            self.needs_recreate = True
        except (vk.VkError, vk.VkException) as exc:
            raise VulkanError("vkAcquireNextImageKHR", result_name(exc)) from None
        return int(idx_ptr[0])

    def _begin_commands(self):
        cmd = self._cmd
        call(vk.vkResetCommandBuffer, cmd, 0)
        call(vk.vkBeginCommandBuffer, cmd, vk.VkCommandBufferBeginInfo(
            flags=vk.VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT))
        return cmd

    def _submit_and_present(self, index: int, wait_stage: int) -> None:
        cmd = self._cmd
        call(vk.vkEndCommandBuffer, cmd)
        call(vk.vkResetFences, self.device, 1, [self._fence])
        done = self._render_done[index]
        submit = vk.VkSubmitInfo(waitSemaphoreCount=1, pWaitSemaphores=[self._acquired],
                                 pWaitDstStageMask=[wait_stage],
                                 commandBufferCount=1, pCommandBuffers=[cmd],
                                 signalSemaphoreCount=1, pSignalSemaphores=[done])
        call(vk.vkQueueSubmit, self.queue, 1, [submit], self._fence)
        present = vk.VkPresentInfoKHR(waitSemaphoreCount=1, pWaitSemaphores=[done],
                                      swapchainCount=1, pSwapchains=[self.swapchain],
                                      pImageIndices=[index])
        try:
            self._fn["vkQueuePresentKHR"](self.queue, present)
        except (vk.VkErrorOutOfDateKhr, vk.VkSuboptimalKhr):
            self.needs_recreate = True
        except (vk.VkError, vk.VkException) as exc:
            raise VulkanError("vkQueuePresentKHR", result_name(exc)) from None
        self.frames_presented += 1

    def render_frame(self, record) -> bool:
        """GPU path: draw the frame on the device straight into the swapchain image.

        ``record(cmd, target)`` records commands into ``cmd`` (a
        :class:`~splatedit.render.vk.commands.CommandBuffer` wrapping the
        presenter's command buffer) that draw into ``target`` (a
        :class:`~splatedit.render.vk.swapchain_target.SwapchainTarget`, in
        UNDEFINED layout: clear it or draw over all of it; use
        ``target.framebuffer(render_pass)``).  Whatever layout it is left in,
        it is then transitioned to PRESENT_SRC and presented.  The previous
        frame has finished on the GPU when ``record`` runs, so buffers it used
        may be rewritten.  Returns False when nothing was shown (as :meth:`present`).
        """
        if self.device is None:
            return False
        if not self.gpu_targets and self.swapchain is not None:
            raise PresentError("the window's swapchain images cannot be colour attachments")
        index = self._acquire()
        if index is None:
            return False
        from splatedit.render.vk.commands import CommandBuffer
        target = self.targets[index]
        target.layout = vk.VK_IMAGE_LAYOUT_UNDEFINED
        cb = CommandBuffer(self.dev, handle=self._begin_commands())
        try:
            record(cb, target)
            if target.layout != vk.VK_IMAGE_LAYOUT_PRESENT_SRC_KHR:
                cb.image_barrier(target, "present", "color_output|transfer", "color_write|transfer_write",
                                 "bottom", "none")
        except BaseException:
            vk.vkResetCommandBuffer(self._cmd, 0)    # drop the partial recording; the fence stays signalled
            self._recreate()                          # the acquired image's semaphore is pending
            raise
        finally:
            cb.destroy()
        self._submit_and_present(index, vk.VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT
                                 | vk.VK_PIPELINE_STAGE_TRANSFER_BIT)
        return True

    def wait_previous(self) -> None:
        """Wait until the last submitted frame has finished on the device (before
        rewriting an image that frame reads, e.g. a resident scene frame)."""
        if self.device is not None and self._fence is not None:
            call(vk.vkWaitForFences, self.device, 1, [self._fence], vk.VK_TRUE, _UINT64_MAX)

    def upload_into(self, cb, target, rgba: np.ndarray) -> None:
        """Inside :meth:`render_frame`'s ``record``: copy an (h, w, 4) uint8 RGBA
        frame (row 0 at the top) into ``target`` through the staging buffer
        (the CPU path's pixels, e.g. a background-refined frame); a frame
        smaller than the target is padded with black.  ``target`` is left in
        TRANSFER_DST layout."""
        w, h = target.width, target.height
        self._ensure_staging(w * h * 4)
        self._fill_staging(np.asarray(rgba), w, h)
        cb.image_barrier(target, "transfer_dst", "transfer", "none", "transfer", "transfer_write")
        cb.copy_buffer_to_image(self._staging, target)

    def blit_into(self, cb, image, target, src_size=None) -> None:
        """Inside :meth:`render_frame`'s ``record``: scale the ``src_size`` =
        (w, h) top-left part of a device image (rgba8, TRANSFER_SRC layout, on
        this presenter's device) onto the whole ``target`` (nearest filter:
        a half-resolution frame is pixel-doubled, as the CPU path does),
        converting to the swapchain's format.  No host copy.  ``target`` is
        left in TRANSFER_DST layout.  Needs :attr:`can_blit`."""
        sw, sh = src_size if src_size is not None else (image.width, image.height)
        cb.memory_barrier("color_output", "color_write", "transfer", "transfer_read")   # the scene's passes
        cb.image_barrier(target, "transfer_dst", "transfer", "none", "transfer", "transfer_write")
        cb.blit_image(image, target, (0, 0, sw, sh), (0, 0, target.width, target.height))

    def _fill_staging(self, img: np.ndarray, w: int, h: int) -> None:
        if img.ndim != 3 or img.shape[2] != 4 or img.dtype != np.uint8:
            raise ValueError(f"present() needs an (h, w, 4) uint8 image, got {img.shape} {img.dtype}")
        dst = self._staging.view()[:w * h * 4].reshape(h, w, 4)
        ch, cw = min(h, img.shape[0]), min(w, img.shape[1])
        if (ch, cw) != (h, w):
            dst[:] = 0
        if self._bgra:
            dst[:ch, :cw, 0] = img[:ch, :cw, 2]
            dst[:ch, :cw, 1] = img[:ch, :cw, 1]
            dst[:ch, :cw, 2] = img[:ch, :cw, 0]
            dst[:ch, :cw, 3] = 255
        else:
            dst[:ch, :cw, :3] = img[:ch, :cw, :3]
            dst[:ch, :cw, 3] = 255

    def present(self, rgba: np.ndarray) -> bool:
        """Show ``rgba`` ((h, w, 4) uint8, row 0 at the top).

        A frame whose size differs from the swapchain's is copied at the
        top-left and the rest is cleared to black.  Returns False when nothing
        was shown (window minimized, or the swapchain was out of date and has
        been re-created: draw the next frame at :meth:`framebuffer_size`).
        """
        if self.device is None:
            return False
        img = np.asarray(rgba)
        if img.ndim != 3 or img.shape[2] != 4 or img.dtype != np.uint8:
            raise ValueError(f"present() needs an (h, w, 4) uint8 image, got {img.shape} {img.dtype}")
        index = self._acquire()
        if index is None:
            return False
        w, h = self.extent
        # --- pixels into the staging buffer (BGRA or RGBA, exactly w x h)
        self._fill_staging(img, w, h)
        # --- record: undefined -> transfer dst, copy, -> present src
        image = self._images[index]
        cmd = self._begin_commands()
        rng = vk.VkImageSubresourceRange(aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, baseMipLevel=0,
                                         levelCount=1, baseArrayLayer=0, layerCount=1)
        to_dst = vk.VkImageMemoryBarrier(
            srcAccessMask=0, dstAccessMask=vk.VK_ACCESS_TRANSFER_WRITE_BIT,
            oldLayout=vk.VK_IMAGE_LAYOUT_UNDEFINED, newLayout=vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
            srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED, dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
            image=image, subresourceRange=rng)
        vk.vkCmdPipelineBarrier(cmd, vk.VK_PIPELINE_STAGE_TRANSFER_BIT, vk.VK_PIPELINE_STAGE_TRANSFER_BIT,
                                0, 0, None, 0, None, 1, [to_dst])
        layers = vk.VkImageSubresourceLayers(aspectMask=vk.VK_IMAGE_ASPECT_COLOR_BIT, mipLevel=0,
                                             baseArrayLayer=0, layerCount=1)
        region = vk.VkBufferImageCopy(bufferOffset=0, bufferRowLength=0, bufferImageHeight=0,
                                      imageSubresource=layers,
                                      imageOffset=vk.VkOffset3D(x=0, y=0, z=0),
                                      imageExtent=vk.VkExtent3D(width=w, height=h, depth=1))
        vk.vkCmdCopyBufferToImage(cmd, self._staging.handle, image, vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                                  1, [region])
        to_present = vk.VkImageMemoryBarrier(
            srcAccessMask=vk.VK_ACCESS_TRANSFER_WRITE_BIT, dstAccessMask=0,
            oldLayout=vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, newLayout=vk.VK_IMAGE_LAYOUT_PRESENT_SRC_KHR,
            srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED, dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
            image=image, subresourceRange=rng)
        vk.vkCmdPipelineBarrier(cmd, vk.VK_PIPELINE_STAGE_TRANSFER_BIT,
                                vk.VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, 0, 0, None, 0, None, 1,
                                [to_present])
        self._submit_and_present(index, vk.VK_PIPELINE_STAGE_TRANSFER_BIT)
        return True

    # -------------------------------------------------------------- cleanup
    def close(self) -> None:
        """Destroy every Vulkan object, the device and the instance (idempotent)."""
        dev = self.dev
        if dev is None:
            return
        d = dev.device
        if d is not None:
            try:
                vk.vkDeviceWaitIdle(d)
            except Exception:  # pragma: no cover - device lost
                pass
            self._free_staging()
            self._destroy_targets()
            for s in self._render_done:
                self._destroy_semaphore(s)
            self._render_done = []
            if self._acquired is not None:
                self._destroy_semaphore(self._acquired)
                self._acquired = None
            if self._fence is not None:
                vk.vkDestroyFence(d, self._fence, None)
                track("fence", -1)
                self._fence = None
            if self._cmd is not None:
                vk.vkFreeCommandBuffers(d, dev.command_pool, 1, [self._cmd])
                track("command_buffer", -1)
                self._cmd = None
            if self.swapchain is not None:
                self._fn["vkDestroySwapchainKHR"](d, self.swapchain, None)
                track("swapchain", -1)
                self.swapchain = None
        if self.surface is not None and dev.instance is not None:
            self._fn_inst["vkDestroySurfaceKHR"](dev.instance, self.surface, None)
            track("surface", -1)
            self.surface = None
        dev.close()
        self.dev = None
