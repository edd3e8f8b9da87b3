"""Present CPU-side RGBA frames in a window through a Vulkan swapchain.

:class:`SwapchainPresenter` owns a small Vulkan context of its own (instance
with the surface extensions glfw asks for, one device queue that can present,
a swapchain, one persistently mapped staging buffer) and shows numpy images:
every :meth:`~SwapchainPresenter.present` copies an ``(h, w, 4)`` uint8 RGBA
frame into the staging buffer, records ``vkCmdCopyBufferToImage`` into the
acquired swapchain image (transfer-dst layout, then present-src) and presents.

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

Validation: with ``SPLATEDIT_VALIDATION=1`` the Khronos validation layer is
enabled and every message is appended to :attr:`validation_messages` and
printed on stderr (prefixed ``splatedit: vulkan validation:``).
"""

from __future__ import annotations

import os
import sys

import numpy as np
import vulkan as vk

from splatedit.errors import SplatEditError

_UINT64_MAX = 0xFFFFFFFFFFFFFFFF
_VALIDATION_LAYER = "VK_LAYER_KHRONOS_validation"


class PresentError(SplatEditError):
    """The window cannot be shown with Vulkan (no device, no surface...)."""


def validation_requested() -> bool:
    return os.environ.get("SPLATEDIT_VALIDATION", "") not in ("", "0")


class SwapchainPresenter:
    """A Vulkan swapchain on a glfw window that shows numpy RGBA frames.

    Args:
        window: the glfw window (created with ``GLFW_CLIENT_API = GLFW_NO_API``).
        vsync: FIFO present mode when True (default), else MAILBOX/IMMEDIATE.
        validation: enable the validation layer (default: ``SPLATEDIT_VALIDATION``).
    """

    def __init__(self, window, *, vsync: bool = True, validation: bool | None = None):
        import glfw
        self._glfw = glfw
        self.window = window
        self.vsync = vsync
        self.validation = validation_requested() if validation is None else validation
        self.validation_messages: list[str] = []
        self._messenger = None
        self._debug_cb = None
        self.instance = None
        self.device = None
        self.surface = None
        self.swapchain = None
        self.extent = (0, 0)
        self.needs_recreate = False
        self.frames_presented = 0
        self._images = []
        self._render_done = []
        self._staging = None
        self._staging_mem = None
        self._staging_map = None
        self._staging_size = 0
        try:
            self._create_instance()
            self._create_surface()
            self._pick_device()
            self._create_sync()
            self._create_swapchain()
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------ creation
    def _create_instance(self) -> None:
        exts = list(self._glfw.get_required_instance_extensions() or [])
        if not exts:
            raise PresentError("glfw reports no Vulkan surface support (no Vulkan loader or display)")
        layers = []
        if self.validation:
            available = {p.layerName for p in vk.vkEnumerateInstanceLayerProperties()}
            if _VALIDATION_LAYER in available:
                layers.append(_VALIDATION_LAYER)
                exts.append(vk.VK_EXT_DEBUG_UTILS_EXTENSION_NAME)
            else:
                print("splatedit: warning: SPLATEDIT_VALIDATION is set but the validation layer "
                      "is not installed", file=sys.stderr)
        app = vk.VkApplicationInfo(pApplicationName="splatedit-editor", applicationVersion=1,
                                   pEngineName="splatedit", engineVersion=1,
                                   apiVersion=vk.VK_MAKE_VERSION(1, 1, 0))
        info = vk.VkInstanceCreateInfo(pApplicationInfo=app, ppEnabledExtensionNames=exts,
                                       enabledExtensionCount=len(exts),
                                       ppEnabledLayerNames=layers, enabledLayerCount=len(layers))
        self.instance = vk.vkCreateInstance(info, None)
        self._fn_inst = {name: vk.vkGetInstanceProcAddr(self.instance, name) for name in (
            "vkDestroySurfaceKHR", "vkGetPhysicalDeviceSurfaceSupportKHR",
            "vkGetPhysicalDeviceSurfaceCapabilitiesKHR", "vkGetPhysicalDeviceSurfaceFormatsKHR",
            "vkGetPhysicalDeviceSurfacePresentModesKHR")}
        if layers:
            self._install_messenger()

    def _install_messenger(self) -> None:
        messages = self.validation_messages

        def callback(severity, types, data, user):
            try:
                text = vk.ffi.string(data.pMessage).decode("utf-8", "replace")
            except Exception:  # pragma: no cover - defensive
                text = "<unreadable message>"
            messages.append(text)
            print(f"splatedit: vulkan validation: {text}", file=sys.stderr)
            return 0

        # A private cffi callback: the bindings' pfn keyword would store the
        # python function in a module global shared with the renderer's messenger.
        self._debug_cb = vk.ffi.callback("PFN_vkDebugUtilsMessengerCallbackEXT", callback)
        info = vk.VkDebugUtilsMessengerCreateInfoEXT(
            messageSeverity=(vk.VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT
                             | vk.VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT),
            messageType=(vk.VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT
                         | vk.VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT
                         | vk.VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT))
        info.pfnUserCallback = self._debug_cb
        create = vk.vkGetInstanceProcAddr(self.instance, "vkCreateDebugUtilsMessengerEXT")
        self._messenger = create(self.instance, info, None)

    def _create_surface(self) -> None:
        ptr = vk.ffi.new("VkSurfaceKHR*")
        rc = self._glfw.create_window_surface(self.instance, self.window, None, ptr)
        if rc != 0:
            raise PresentError(f"glfwCreateWindowSurface failed (VkResult {rc})")
        self.surface = ptr[0]

    def _pick_device(self) -> None:
        supported = self._fn_inst["vkGetPhysicalDeviceSurfaceSupportKHR"]
        choice = None
        for pd in vk.vkEnumeratePhysicalDevices(self.instance):
            for qi, fam in enumerate(vk.vkGetPhysicalDeviceQueueFamilyProperties(pd)):
                if fam.queueFlags & (vk.VK_QUEUE_GRAPHICS_BIT | vk.VK_QUEUE_TRANSFER_BIT) and \
                        supported(pd, qi, self.surface):
                    choice = (pd, qi)
                    break
            if choice:
                break
        if choice is None:
            raise PresentError("no Vulkan device can present to this window")
        self.physical, self.queue_family = choice
        self.device_name = vk.vkGetPhysicalDeviceProperties(self.physical).deviceName
        qinfo = vk.VkDeviceQueueCreateInfo(queueFamilyIndex=self.queue_family, queueCount=1,
                                           pQueuePriorities=[1.0])
        dexts = [vk.VK_KHR_SWAPCHAIN_EXTENSION_NAME]
        dinfo = vk.VkDeviceCreateInfo(pQueueCreateInfos=[qinfo], queueCreateInfoCount=1,
                                      ppEnabledExtensionNames=dexts, enabledExtensionCount=1)
        self.device = vk.vkCreateDevice(self.physical, dinfo, None)
        self.queue = vk.vkGetDeviceQueue(self.device, self.queue_family, 0)
        self._fn = {name: vk.vkGetDeviceProcAddr(self.device, name) for name in (
            "vkCreateSwapchainKHR", "vkDestroySwapchainKHR", "vkGetSwapchainImagesKHR",
            "vkAcquireNextImageKHR", "vkQueuePresentKHR")}
        self._mem_props = vk.vkGetPhysicalDeviceMemoryProperties(self.physical)

    def _create_sync(self) -> None:
        d = self.device
        self._pool = vk.vkCreateCommandPool(d, vk.VkCommandPoolCreateInfo(
            flags=vk.VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT,
            queueFamilyIndex=self.queue_family), None)
        self._cmd = vk.vkAllocateCommandBuffers(d, vk.VkCommandBufferAllocateInfo(
            commandPool=self._pool, level=vk.VK_COMMAND_BUFFER_LEVEL_PRIMARY,
            commandBufferCount=1))[0]
        self._fence = vk.vkCreateFence(d, vk.VkFenceCreateInfo(flags=vk.VK_FENCE_CREATE_SIGNALED_BIT), None)
        self._acquired = vk.vkCreateSemaphore(d, vk.VkSemaphoreCreateInfo(), None)

    def _surface_extent(self) -> tuple[int, int]:
        caps = self._fn_inst["vkGetPhysicalDeviceSurfaceCapabilitiesKHR"](self.physical, self.surface)
        w, h = caps.currentExtent.width, caps.currentExtent.height
        if w == 0xFFFFFFFF:
            w, h = self._glfw.get_framebuffer_size(self.window)
            w = min(max(w, caps.minImageExtent.width), caps.maxImageExtent.width)
            h = min(max(h, caps.minImageExtent.height), caps.maxImageExtent.height)
        return int(w), int(h)

    def _create_swapchain(self) -> bool:
        """(Re)create the swapchain for the current surface size; False when minimized."""
        caps = self._fn_inst["vkGetPhysicalDeviceSurfaceCapabilitiesKHR"](self.physical, self.surface)
        w, h = self._surface_extent()
        if w == 0 or h == 0:
            return False
        if not caps.supportedUsageFlags & vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT:
            raise PresentError("the window's swapchain images cannot be transfer destinations")
        formats = self._fn_inst["vkGetPhysicalDeviceSurfaceFormatsKHR"](self.physical, self.surface)
        fmt = None
        for want in (vk.VK_FORMAT_B8G8R8A8_UNORM, vk.VK_FORMAT_R8G8B8A8_UNORM):
            for f in formats:
                if f.format == want:
                    fmt = f
                    break
            if fmt is not None:
                break
        if fmt is None:
            raise PresentError("the window offers no 8-bit UNORM RGBA/BGRA surface format")
        self.format = fmt.format
        self._bgra = fmt.format == vk.VK_FORMAT_B8G8R8A8_UNORM
        modes = list(self._fn_inst["vkGetPhysicalDeviceSurfacePresentModesKHR"](self.physical, self.surface))
        mode = vk.VK_PRESENT_MODE_FIFO_KHR
        if not self.vsync:
            for m in (vk.VK_PRESENT_MODE_MAILBOX_KHR, vk.VK_PRESENT_MODE_IMMEDIATE_KHR):
                if m in modes:
                    mode = m
                    break
        self.present_mode = mode
        count = max(caps.minImageCount + 1, 2)
        if caps.maxImageCount:
            count = min(count, caps.maxImageCount)
        old = self.swapchain
        info = vk.VkSwapchainCreateInfoKHR(
            surface=self.surface, minImageCount=count, imageFormat=fmt.format,
            imageColorSpace=fmt.colorSpace, imageExtent=vk.VkExtent2D(width=w, height=h),
            imageArrayLayers=1, imageUsage=vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT,
            imageSharingMode=vk.VK_SHARING_MODE_EXCLUSIVE,
            preTransform=caps.currentTransform,
            compositeAlpha=vk.VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR,
            presentMode=mode, clipped=vk.VK_TRUE,
            oldSwapchain=old if old is not None else vk.VK_NULL_HANDLE)
        self.swapchain = self._fn["vkCreateSwapchainKHR"](self.device, info, None)
        if old is not None:
            self._fn["vkDestroySwapchainKHR"](self.device, old, None)
        self._images = list(self._fn["vkGetSwapchainImagesKHR"](self.device, self.swapchain))
        for s in self._render_done:
            vk.vkDestroySemaphore(self.device, s, None)
        self._render_done = [vk.vkCreateSemaphore(self.device, vk.VkSemaphoreCreateInfo(), None)
                             for _ in self._images]
        self.extent = (w, h)
        self._ensure_staging(w * h * 4)
        self.needs_recreate = False
        return True

    def _memory_type(self, bits: int, flags: int) -> int:
        for i in range(self._mem_props.memoryTypeCount):
            if bits & (1 << i) and (self._mem_props.memoryTypes[i].propertyFlags & flags) == flags:
                return i
        raise PresentError("no host-visible coherent memory type")

    def _ensure_staging(self, size: int) -> None:
        if self._staging is not None and self._staging_size >= size:
            return
        self._free_staging()
        d = self.device
        self._staging = vk.vkCreateBuffer(d, vk.VkBufferCreateInfo(
            size=size, usage=vk.VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
            sharingMode=vk.VK_SHARING_MODE_EXCLUSIVE), None)
        req = vk.vkGetBufferMemoryRequirements(d, self._staging)
        mt = self._memory_type(req.memoryTypeBits, vk.VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT
                               | vk.VK_MEMORY_PROPERTY_HOST_COHERENT_BIT)
        self._staging_mem = vk.vkAllocateMemory(d, vk.VkMemoryAllocateInfo(
            allocationSize=req.size, memoryTypeIndex=mt), None)
        vk.vkBindBufferMemory(d, self._staging, self._staging_mem, 0)
        self._staging_map = vk.vkMapMemory(d, self._staging_mem, 0, size, 0)
        self._staging_size = size

    def _free_staging(self) -> None:
        if self._staging is None:
            return
        d = self.device
        vk.vkUnmapMemory(d, self._staging_mem)
        vk.vkDestroyBuffer(d, self._staging, None)
        vk.vkFreeMemory(d, self._staging_mem, None)
        self._staging = self._staging_mem = self._staging_map = None
        self._staging_size = 0

    def _recreate(self) -> bool:
        vk.vkDeviceWaitIdle(self.device)
        # a semaphore may hold a pending signal from an acquire whose index was lost
        vk.vkDestroySemaphore(self.device, self._acquired, None)
        self._acquired = vk.vkCreateSemaphore(self.device, vk.VkSemaphoreCreateInfo(), None)
        return self._create_swapchain()

    # ------------------------------------------------------------- frames
    def framebuffer_size(self) -> tuple[int, int]:
        """The size the next frame should have (the surface's current extent)."""
        w, h = self._glfw.get_framebuffer_size(self.window)
        return int(w), int(h)

    def present(self, rgba: np.ndarray) -> bool:
        """Show ``rgba`` ((h, w, 4) uint8, row 0 at the top).

        A frame whose size differs from the swapchain's is copied at the
        top-left and the rest is cleared to black.  Returns False when nothing
        was shown (window minimized, or the swapchain was out of date and has
        been re-created: draw the next frame at :meth:`framebuffer_size`).
        """
        if self.device is None:
            return False
        fw, fh = self.framebuffer_size()
        if fw == 0 or fh == 0:
            return False
        if self.needs_recreate or self.swapchain is None or (fw, fh) != self.extent:
            if not self._recreate():
                return False
        d = self.device
        vk.vkWaitForFences(d, 1, [self._fence], vk.VK_TRUE, _UINT64_MAX)
        idx_ptr = vk.ffi.new("uint32_t*")
        try:
            self._fn["vkAcquireNextImageKHR"](d, self.swapchain, _UINT64_MAX, self._acquired,
                                              vk.VK_NULL_HANDLE, idx_ptr)
        except vk.VkErrorOutOfDateKhr:
            self._recreate()
            return False
        except vk.VkSuboptimalKhr:
            # the image *was* acquired (suboptimal is a success code): use it, recreate after
            self.needs_recreate = True
        index = int(idx_ptr[0])
        w, h = self.extent
        # --- pixels into the staging buffer (BGRA or RGBA, exactly w x h)
        img = np.asarray(rgba)
        if img.ndim != 3 or img.shape[2] != 4 or img.dtype != np.uint8:
            raise ValueError(f"present() needs an (h, w, 4) uint8 image, got {img.shape} {img.dtype}")
        dst = np.frombuffer(self._staging_map, dtype=np.uint8, count=w * h * 4).reshape(h, w, 4)
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
        # --- record: undefined -> transfer dst, copy, -> present src
        image = self._images[index]
        cmd = self._cmd
        vk.vkResetCommandBuffer(cmd, 0)
        vk.vkBeginCommandBuffer(cmd, vk.VkCommandBufferBeginInfo(
            flags=vk.VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT))
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
        vk.vkCmdCopyBufferToImage(cmd, self._staging, image, vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                                  1, [region])
        to_present = vk.VkImageMemoryBarrier(
            srcAccessMask=vk.VK_ACCESS_TRANSFER_WRITE_BIT, dstAccessMask=0,
            oldLayout=vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, newLayout=vk.VK_IMAGE_LAYOUT_PRESENT_SRC_KHR,
            srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED, dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
            image=image, subresourceRange=rng)
        vk.vkCmdPipelineBarrier(cmd, vk.VK_PIPELINE_STAGE_TRANSFER_BIT,
                                vk.VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, 0, 0, None, 0, None, 1,
                                [to_present])
        vk.vkEndCommandBuffer(cmd)
        vk.vkResetFences(d, 1, [self._fence])
        done = self._render_done[index]
        submit = vk.VkSubmitInfo(waitSemaphoreCount=1, pWaitSemaphores=[self._acquired],
                                 pWaitDstStageMask=[vk.VK_PIPELINE_STAGE_TRANSFER_BIT],
                                 commandBufferCount=1, pCommandBuffers=[cmd],
                                 signalSemaphoreCount=1, pSignalSemaphores=[done])
        vk.vkQueueSubmit(self.queue, 1, [submit], self._fence)
        present = vk.VkPresentInfoKHR(waitSemaphoreCount=1, pWaitSemaphores=[done],
                                      swapchainCount=1, pSwapchains=[self.swapchain],
                                      pImageIndices=[index])
        try:
            self._fn["vkQueuePresentKHR"](self.queue, present)
        except (vk.VkErrorOutOfDateKhr, vk.VkSuboptimalKhr):
            self.needs_recreate = True
        self.frames_presented += 1
        return True

    # -------------------------------------------------------------- cleanup
    def close(self) -> None:
        """Destroy every Vulkan object (idempotent)."""
        d = self.device
        if d is not None:
            try:
                vk.vkDeviceWaitIdle(d)
            except Exception:  # pragma: no cover - device lost
                pass
            self._free_staging()
            for s in self._render_done:
                vk.vkDestroySemaphore(d, s, None)
            self._render_done = []
            for name in ("_acquired",):
                if getattr(self, name, None) is not None:
                    vk.vkDestroySemaphore(d, getattr(self, name), None)
                    setattr(self, name, None)
            if getattr(self, "_fence", None) is not None:
                vk.vkDestroyFence(d, self._fence, None)
                self._fence = None
            if getattr(self, "_pool", None) is not None:
                vk.vkDestroyCommandPool(d, self._pool, None)
                self._pool = None
            if self.swapchain is not None:
                self._fn["vkDestroySwapchainKHR"](d, self.swapchain, None)
                self.swapchain = None
            vk.vkDestroyDevice(d, None)
            self.device = None
        if self.instance is not None:
            if self.surface is not None:
                self._fn_inst["vkDestroySurfaceKHR"](self.instance, self.surface, None)
                self.surface = None
            if self._messenger is not None:
                destroy = vk.vkGetInstanceProcAddr(self.instance, "vkDestroyDebugUtilsMessengerEXT")
                destroy(self.instance, self._messenger, None)
                self._messenger = None
            vk.vkDestroyInstance(self.instance, None)
            self.instance = None
