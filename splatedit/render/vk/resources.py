"""Buffers, images and samplers with explicit destruction, staging uploads and readback."""

from __future__ import annotations

import numpy as np
import vulkan as vk

from splatedit.render.vk.core import Device
from splatedit.render.vk.handles import VulkanError, call, flag_bits, release, track

_BUFFER_USAGE = {
    "vertex": vk.VK_BUFFER_USAGE_VERTEX_BUFFER_BIT,
    "index": vk.VK_BUFFER_USAGE_INDEX_BUFFER_BIT,
    "uniform": vk.VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT,
    "storage": vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
    "indirect": vk.VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT,
    "transfer_src": vk.VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
    "transfer_dst": vk.VK_BUFFER_USAGE_TRANSFER_DST_BIT,
}

FORMATS = {
    "rgba8": vk.VK_FORMAT_R8G8B8A8_UNORM,
    "rgba8_srgb": vk.VK_FORMAT_R8G8B8A8_SRGB,
    "bgra8": vk.VK_FORMAT_B8G8R8A8_UNORM,
    "bgra8_srgb": vk.VK_FORMAT_B8G8R8A8_SRGB,
    "rgba16f": vk.VK_FORMAT_R16G16B16A16_SFLOAT,
    "rgba32f": vk.VK_FORMAT_R32G32B32A32_SFLOAT,
    "r32ui": vk.VK_FORMAT_R32_UINT,
    "r32f": vk.VK_FORMAT_R32_SFLOAT,
    "d32f": vk.VK_FORMAT_D32_SFLOAT,
}
#: bytes per texel and numpy dtype / channel count for readback
FORMAT_INFO = {
    "rgba8": (4, np.uint8, 4), "rgba8_srgb": (4, np.uint8, 4), "bgra8": (4, np.uint8, 4),
    "bgra8_srgb": (4, np.uint8, 4), "rgba16f": (8, np.float16, 4), "rgba32f": (16, np.float32, 4),
    "r32ui": (4, np.uint32, 1), "r32f": (4, np.float32, 1), "d32f": (4, np.float32, 1),
}

_IMAGE_USAGE = {
    "color": vk.VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT,
    "depth": vk.VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT,
    "sampled": vk.VK_IMAGE_USAGE_SAMPLED_BIT,
    "storage": vk.VK_IMAGE_USAGE_STORAGE_BIT,
    "input": vk.VK_IMAGE_USAGE_INPUT_ATTACHMENT_BIT,
    "transfer_src": vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
    "transfer_dst": vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT,
}


def _allocate(device: Device, req, flags: int):
    """Device memory for requirements ``req`` (VkMemoryRequirements) in a
    memory type with property ``flags``; counted in live_handles as "memory"."""
    ainfo = vk.VkMemoryAllocateInfo(allocationSize=req.size,
                                    memoryTypeIndex=device.memory_type(req.memoryTypeBits, flags))
    memory = call(vk.vkAllocateMemory, device.device, ainfo, None)
    track("memory", 1)
    return memory


class Buffer:
    """A VkBuffer with its own memory.

    ``host_visible=True`` gives persistently mapped, coherent memory: write
    with :meth:`write` / :meth:`view`, read with :meth:`read` (copies).
    Otherwise the memory is device-local and :meth:`upload` / :meth:`download`
    go through a temporary staging buffer.
    """

    def __init__(self, device: Device, size: int, usage=("vertex",), host_visible: bool = False):
        if size <= 0:
            raise ValueError(f"buffer size must be positive, got {size}")
        self.dev = device
        self.size = int(size)
        self.host_visible = host_visible
        self.handle = None
        self.memory = None
        self._mapped = None
        usage = set(usage) | ({"transfer_dst", "transfer_src"} if not host_visible else set())
        d = device.device
        info = vk.VkBufferCreateInfo(size=self.size, usage=flag_bits(_BUFFER_USAGE, usage, "buffer usage"),
                                     sharingMode=vk.VK_SHARING_MODE_EXCLUSIVE)
        self.handle = call(vk.vkCreateBuffer, d, info, None)
        track("buffer", 1)
        try:
            if host_visible:
                flags = vk.VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | vk.VK_MEMORY_PROPERTY_HOST_COHERENT_BIT
            else:
                flags = vk.VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT
            self.memory = _allocate(device, vk.vkGetBufferMemoryRequirements(d, self.handle), flags)
            call(vk.vkBindBufferMemory, d, self.handle, self.memory, 0)
            if host_visible:
                self._mapped = call(vk.vkMapMemory, d, self.memory, 0, self.size, 0)
        except BaseException:
            self.destroy()
            raise

    # -- host-visible access
    def view(self, dtype=np.uint8) -> np.ndarray:
        """Writable numpy view of the whole mapped buffer (host-visible only).
        Do not keep it past :meth:`destroy`."""
        if self._mapped is None:
            raise VulkanError("Buffer.view", "VK_ERROR_MEMORY_MAP_FAILED", "buffer is not host-visible")
        return np.frombuffer(self._mapped, dtype=dtype)

    def write(self, data, offset: int = 0) -> None:
        """Copy bytes of ``data`` (numpy array or bytes) to ``offset``."""
        src = np.ascontiguousarray(data).view(np.uint8).reshape(-1)
        if offset < 0 or offset + src.nbytes > self.size:
            raise ValueError(f"write of {src.nbytes} bytes at {offset} exceeds buffer size {self.size}")
        if self.host_visible:
            self.view()[offset:offset + src.nbytes] = src
        else:
            self.upload(src, offset)

    def read(self, nbytes: int | None = None, offset: int = 0) -> np.ndarray:
        """A copy of ``nbytes`` bytes from ``offset`` (uint8)."""
        nbytes = self.size - offset if nbytes is None else nbytes
        if self.host_visible:
            return self.view()[offset:offset + nbytes].copy()
        return self.download(nbytes, offset)

    # -- device-local access through staging
    def upload(self, data, offset: int = 0) -> None:
        src = np.ascontiguousarray(data).view(np.uint8).reshape(-1)
        if src.nbytes == 0:
            return
        if self.host_visible:
            self.write(src, offset)
            return
        staging = Buffer(self.dev, src.nbytes, ("transfer_src",), host_visible=True)
        try:
            staging.view()[:] = src
            self.dev.submit(lambda cb: cb.copy_buffer(staging, self, src.nbytes, 0, offset))
        finally:
            staging.destroy()

    def download(self, nbytes: int, offset: int = 0) -> np.ndarray:
        staging = Buffer(self.dev, nbytes, ("transfer_dst",), host_visible=True)
        try:
            self.dev.submit(lambda cb: (cb.copy_buffer(self, staging, nbytes, offset, 0),
                                        cb.host_read_barrier()))
            return staging.view()[:nbytes].copy()  # copy before unmapping
        finally:
            staging.destroy()

    def destroy(self) -> None:
        d = self.dev.device
        if self._mapped is not None:
            vk.vkUnmapMemory(d, self.memory)
            self._mapped = None
        release(self, "handle", vk.vkDestroyBuffer, "buffer")
        release(self, "memory", vk.vkFreeMemory, "memory")


class Image:
    """A 2D VkImage + view with its own device-local memory.

    ``layout`` records the layout the image is in after the last recorded
    command that changed it (kept up to date by render passes and barriers).
    """

    def __init__(self, device: Device, width: int, height: int, fmt: str, usage):
        self.dev = device
        self.width, self.height = int(width), int(height)
        self.format = fmt
        self.vk_format = FORMATS[fmt]
        self.is_depth = fmt.startswith("d")
        self.aspect = vk.VK_IMAGE_ASPECT_DEPTH_BIT if self.is_depth else vk.VK_IMAGE_ASPECT_COLOR_BIT
        self.layout = vk.VK_IMAGE_LAYOUT_UNDEFINED
        self.handle = self.memory = self.view = None
        d = device.device
        info = vk.VkImageCreateInfo(
            imageType=vk.VK_IMAGE_TYPE_2D, format=self.vk_format,
            extent=vk.VkExtent3D(self.width, self.height, 1), mipLevels=1, arrayLayers=1,
            samples=vk.VK_SAMPLE_COUNT_1_BIT, tiling=vk.VK_IMAGE_TILING_OPTIMAL,
            usage=flag_bits(_IMAGE_USAGE, usage, "image usage"), sharingMode=vk.VK_SHARING_MODE_EXCLUSIVE,
            initialLayout=vk.VK_IMAGE_LAYOUT_UNDEFINED)
        self.handle = call(vk.vkCreateImage, d, info, None)
        track("image", 1)
        try:
            self.memory = _allocate(device, vk.vkGetImageMemoryRequirements(d, self.handle),
                                    vk.VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT)
            call(vk.vkBindImageMemory, d, self.handle, self.memory, 0)
            sub = vk.VkImageSubresourceRange(aspectMask=self.aspect, baseMipLevel=0, levelCount=1,
                                             baseArrayLayer=0, layerCount=1)
            vinfo = vk.VkImageViewCreateInfo(image=self.handle, viewType=vk.VK_IMAGE_VIEW_TYPE_2D,
                                             format=self.vk_format, subresourceRange=sub)
            self.view = call(vk.vkCreateImageView, d, vinfo, None)
            track("image_view", 1)
        except BaseException:
            self.destroy()
            raise

    @property
    def texel_bytes(self) -> int:
        return FORMAT_INFO[self.format][0]

    def destroy(self) -> None:
        release(self, "view", vk.vkDestroyImageView, "image_view")
        release(self, "handle", vk.vkDestroyImage, "image")
        release(self, "memory", vk.vkFreeMemory, "memory")


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
        release(self, "handle", vk.vkDestroySampler, "sampler")


def readback_array(raw: np.ndarray, fmt: str, width: int, height: int) -> np.ndarray:
    """Interpret tightly packed texels read back from an image of format ``fmt``."""
    _, dtype, ch = FORMAT_INFO[fmt]
    arr = raw.view(dtype)
    return arr.reshape(height, width, ch) if ch > 1 else arr.reshape(height, width)
