"""Command buffers (one-shot, fenced) and timestamp query pools."""

from __future__ import annotations

import numpy as np
import vulkan as vk

from splatedit.render.vk.handles import VulkanError, call, flag_bits, release, track

#: image layouts by the short names the recording helpers and passes take
IMAGE_LAYOUTS = {
    "undefined": vk.VK_IMAGE_LAYOUT_UNDEFINED,
    "general": vk.VK_IMAGE_LAYOUT_GENERAL,
    "color": vk.VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
    "depth": vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
    "depth_read": vk.VK_IMAGE_LAYOUT_DEPTH_STENCIL_READ_ONLY_OPTIMAL,
    "shader_read": vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
    "transfer_src": vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
    "transfer_dst": vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
    "present": vk.VK_IMAGE_LAYOUT_PRESENT_SRC_KHR,
}

_FENCE_TIMEOUT_NS = 600 * 10**9


class CommandBuffer:
    """A primary command buffer for one submission; :meth:`submit_and_wait` blocks on a fence."""

    def __init__(self, device, handle=None):
        """``device``: the :class:`~splatedit.render.vk.core.Device` whose
        command pool and queue it uses.  ``handle``: record into an existing
        command buffer that its owner allocated, submits and frees (e.g. the swapchain presenter's); the
        object then owns nothing and :meth:`submit_and_wait` is unavailable."""
        self.dev = device
        self.handle = None
        self._fence = None
        self._keep = []  # python objects referenced by recorded commands
        self._owned = handle is None
        if handle is not None:
            self.handle = handle
            return
        d = device.device
        info = vk.VkCommandBufferAllocateInfo(commandPool=device.command_pool,
                                              level=vk.VK_COMMAND_BUFFER_LEVEL_PRIMARY,
                                              commandBufferCount=1)
        self.handle = call(vk.vkAllocateCommandBuffers, d, info)[0]
        track("command_buffer", 1)
        self._fence = call(vk.vkCreateFence, d, vk.VkFenceCreateInfo(), None)
        track("fence", 1)

    def begin(self):
        call(vk.vkBeginCommandBuffer, self.handle, vk.VkCommandBufferBeginInfo(
            flags=vk.VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT))

    def end(self):
        call(vk.vkEndCommandBuffer, self.handle)

    def submit_and_wait(self):
        cbs = [self.handle]
        info = vk.VkSubmitInfo(commandBufferCount=1, pCommandBuffers=cbs)
        call(vk.vkQueueSubmit, self.dev.queue, 1, [info], self._fence)
        try:
            vk.vkWaitForFences(self.dev.device, 1, [self._fence], vk.VK_TRUE, _FENCE_TIMEOUT_NS)
        except vk.VkTimeout:
            raise VulkanError("vkWaitForFences", "VK_TIMEOUT", "GPU work did not finish in 10 minutes") from None
        except (vk.VkError, vk.VkException) as exc:
            raise VulkanError("vkWaitForFences", type(exc).__name__) from None
        self._keep.clear()

    def destroy(self):
        d = self.dev.device
        if not self._owned:
            self.handle = None
            self._keep.clear()
            return
        if self._fence is not None:
            vk.vkDestroyFence(d, self._fence, None)
            track("fence", -1)
            self._fence = None
        if self.handle is not None:
            vk.vkFreeCommandBuffers(d, self.dev.command_pool, 1, [self.handle])
            track("command_buffer", -1)
            self.handle = None

    # ------------------------------------------------------------ transfers
    def copy_buffer(self, src, dst, size, src_offset=0, dst_offset=0):
        region = vk.VkBufferCopy(srcOffset=src_offset, dstOffset=dst_offset, size=size)
        vk.vkCmdCopyBuffer(self.handle, src.handle, dst.handle, 1, [region])

    def fill_buffer(self, buf, value: int = 0, offset: int = 0, size: int | None = None):
        size = buf.size - offset if size is None else size
        vk.vkCmdFillBuffer(self.handle, buf.handle, offset, size, value)

    def copy_image_to_buffer(self, image, buf, rect=None, buf_offset=0):
        """Copy ``rect`` = (x, y, w, h) of an image in TRANSFER_SRC layout, tightly packed."""
        vk.vkCmdCopyImageToBuffer(self.handle, image.handle, vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                                  buf.handle, 1, [_texel_region(image, rect, buf_offset)])

    def copy_buffer_to_image(self, buf, image, rect=None, buf_offset=0):
        """Copy tightly packed texels at ``buf_offset`` into ``rect`` = (x, y, w, h)
        of an image in TRANSFER_DST layout."""
        vk.vkCmdCopyBufferToImage(self.handle, buf.handle, image.handle,
                                  vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, [_texel_region(image, rect, buf_offset)])

    def blit_image(self, src, dst, src_rect=None, dst_rect=None, nearest: bool = True):
        """Copy ``src_rect`` = (x, y, w, h) of ``src`` (TRANSFER_SRC layout) into
        ``dst_rect`` of ``dst`` (TRANSFER_DST layout), scaling and converting the
        format (e.g. rgba8 -> a bgra8 swapchain image); ``nearest`` filtering."""
        sx, sy, sw, sh = src_rect if src_rect is not None else (0, 0, src.width, src.height)
        dx, dy, dw, dh = dst_rect if dst_rect is not None else (0, 0, dst.width, dst.height)
        sub = lambda im: vk.VkImageSubresourceLayers(aspectMask=im.aspect, mipLevel=0,  # noqa: E731
                                                     baseArrayLayer=0, layerCount=1)
        region = vk.VkImageBlit(srcSubresource=sub(src),
                                srcOffsets=[vk.VkOffset3D(sx, sy, 0), vk.VkOffset3D(sx + sw, sy + sh, 1)],
                                dstSubresource=sub(dst),
                                dstOffsets=[vk.VkOffset3D(dx, dy, 0), vk.VkOffset3D(dx + dw, dy + dh, 1)])
        vk.vkCmdBlitImage(self.handle, src.handle, vk.VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                          dst.handle, vk.VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, [region],
                          vk.VK_FILTER_NEAREST if nearest else vk.VK_FILTER_LINEAR)

    # ------------------------------------------------------------- barriers
    def host_read_barrier(self):
        """Make transfer writes visible to host reads."""
        mb = vk.VkMemoryBarrier(srcAccessMask=vk.VK_ACCESS_TRANSFER_WRITE_BIT,
                                dstAccessMask=vk.VK_ACCESS_HOST_READ_BIT)
        vk.vkCmdPipelineBarrier(self.handle, vk.VK_PIPELINE_STAGE_TRANSFER_BIT,
                                vk.VK_PIPELINE_STAGE_HOST_BIT, 0, 1, [mb], 0, None, 0, None)

    def memory_barrier(self, src_stage: str, src_access: str, dst_stage: str, dst_access: str):
        """A global memory barrier; stages/accesses by short names (see _STAGES/_ACCESS)."""
        mb = vk.VkMemoryBarrier(srcAccessMask=_access(src_access), dstAccessMask=_access(dst_access))
        vk.vkCmdPipelineBarrier(self.handle, _stage(src_stage), _stage(dst_stage), 0, 1, [mb],
                                0, None, 0, None)

    def image_barrier(self, image, new_layout: str, src_stage: str, src_access: str,
                      dst_stage: str, dst_access: str):
        """Transition ``image`` from its recorded layout to ``new_layout``."""
        new = IMAGE_LAYOUTS[new_layout]
        sub = vk.VkImageSubresourceRange(aspectMask=image.aspect, baseMipLevel=0, levelCount=1,
                                         baseArrayLayer=0, layerCount=1)
        ib = vk.VkImageMemoryBarrier(srcAccessMask=_access(src_access), dstAccessMask=_access(dst_access),
                                     oldLayout=image.layout, newLayout=new,
                                     srcQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
                                     dstQueueFamilyIndex=vk.VK_QUEUE_FAMILY_IGNORED,
                                     image=image.handle, subresourceRange=sub)
        vk.vkCmdPipelineBarrier(self.handle, _stage(src_stage), _stage(dst_stage), 0, 0, None,
                                0, None, 1, [ib])
        image.layout = new

    # ------------------------------------------------------------ rendering
    def begin_render_pass(self, render_pass, framebuffer, clears):
        """``clears``: one entry per attachment: an RGBA tuple (float or uint), a
        depth float, or None (attachment is loaded, value ignored)."""
        values = []
        for c in clears:
            if c is None:
                values.append(vk.VkClearValue(color=vk.VkClearColorValue(float32=[0.0, 0.0, 0.0, 0.0])))
            elif isinstance(c, (int, float)):
                values.append(vk.VkClearValue(depthStencil=vk.VkClearDepthStencilValue(depth=float(c), stencil=0)))
            elif all(isinstance(x, int) for x in c):
                values.append(vk.VkClearValue(color=vk.VkClearColorValue(uint32=list(c))))
            else:
                values.append(vk.VkClearValue(color=vk.VkClearColorValue(float32=[float(x) for x in c])))
        area = vk.VkRect2D(offset=vk.VkOffset2D(0, 0), extent=vk.VkExtent2D(framebuffer.width, framebuffer.height))
        info = vk.VkRenderPassBeginInfo(renderPass=render_pass.handle, framebuffer=framebuffer.handle,
                                        renderArea=area, clearValueCount=len(values), pClearValues=values)
        vk.vkCmdBeginRenderPass(self.handle, info, vk.VK_SUBPASS_CONTENTS_INLINE)
        vp = vk.VkViewport(x=0.0, y=0.0, width=float(framebuffer.width), height=float(framebuffer.height),
                           minDepth=0.0, maxDepth=1.0)
        vk.vkCmdSetViewport(self.handle, 0, 1, [vp])
        sc = vk.VkRect2D(offset=vk.VkOffset2D(0, 0), extent=vk.VkExtent2D(framebuffer.width, framebuffer.height))
        vk.vkCmdSetScissor(self.handle, 0, 1, [sc])
        for att, lay in zip(framebuffer.attachments, render_pass.final_layouts):
            att.layout = lay

    def end_render_pass(self):
        vk.vkCmdEndRenderPass(self.handle)

    def bind_pipeline(self, pipeline):
        bp = vk.VK_PIPELINE_BIND_POINT_COMPUTE if pipeline.compute else vk.VK_PIPELINE_BIND_POINT_GRAPHICS
        vk.vkCmdBindPipeline(self.handle, bp, pipeline.handle)

    def bind_descriptor_set(self, pipeline, dset, set_index: int = 0):
        bp = vk.VK_PIPELINE_BIND_POINT_COMPUTE if pipeline.compute else vk.VK_PIPELINE_BIND_POINT_GRAPHICS
        vk.vkCmdBindDescriptorSets(self.handle, bp, pipeline.layout.handle, set_index, 1, [dset.handle], 0, None)

    def bind_vertex_buffers(self, first_binding: int, buffers, offsets=None):
        handles = [b.handle for b in buffers]
        offsets = list(offsets) if offsets is not None else [0] * len(handles)
        vk.vkCmdBindVertexBuffers(self.handle, first_binding, len(handles), handles, offsets)

    def push_constants(self, pipeline, data: np.ndarray):
        arr = np.ascontiguousarray(data)
        self._keep.append(arr)
        vk.vkCmdPushConstants(self.handle, pipeline.layout.handle, pipeline.layout.push_stages, 0,
                              arr.nbytes, vk.ffi.from_buffer(arr))

    def draw(self, vertex_count, instance_count=1, first_vertex=0, first_instance=0):
        vk.vkCmdDraw(self.handle, vertex_count, instance_count, first_vertex, first_instance)

    def draw_indirect(self, buf, offset=0, draw_count=1, stride=16):
        vk.vkCmdDrawIndirect(self.handle, buf.handle, offset, draw_count, stride)

    def bind_index_buffer(self, buf, offset: int = 0, uint32: bool = False):
        vk.vkCmdBindIndexBuffer(self.handle, buf.handle, offset,
                                vk.VK_INDEX_TYPE_UINT32 if uint32 else vk.VK_INDEX_TYPE_UINT16)

    def draw_indexed(self, index_count, instance_count=1, first_index=0, vertex_offset=0, first_instance=0):
        vk.vkCmdDrawIndexed(self.handle, index_count, instance_count, first_index, vertex_offset,
                            first_instance)

    def set_scissor(self, x: int, y: int, w: int, h: int):
        """Scissor rectangle in framebuffer pixels (the pipeline's scissor is dynamic)."""
        sc = vk.VkRect2D(offset=vk.VkOffset2D(int(x), int(y)), extent=vk.VkExtent2D(int(w), int(h)))
        vk.vkCmdSetScissor(self.handle, 0, 1, [sc])

    def dispatch(self, x, y=1, z=1):
        vk.vkCmdDispatch(self.handle, x, y, z)

    def dispatch_indirect(self, buf, offset: int = 0):
        """A dispatch whose group counts (3 uint32: x, y, z) the GPU reads from
        ``buf`` (usage "indirect") at byte ``offset`` when it runs."""
        vk.vkCmdDispatchIndirect(self.handle, buf.handle, offset)

    # ----------------------------------------------------------- timestamps
    def reset_queries(self, pool, first=0, count=None):
        vk.vkCmdResetQueryPool(self.handle, pool.handle, first, pool.count if count is None else count)

    def timestamp(self, pool, index, bottom=True):
        stage = vk.VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT if bottom else vk.VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT
        vk.vkCmdWriteTimestamp(self.handle, stage, pool.handle, index)


_STAGES = {
    "top": vk.VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT,
    "bottom": vk.VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT,
    "transfer": vk.VK_PIPELINE_STAGE_TRANSFER_BIT,
    "compute": vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
    "vertex_input": vk.VK_PIPELINE_STAGE_VERTEX_INPUT_BIT,
    "vertex": vk.VK_PIPELINE_STAGE_VERTEX_SHADER_BIT,
    "fragment": vk.VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT,
    "draw_indirect": vk.VK_PIPELINE_STAGE_DRAW_INDIRECT_BIT,
    "color_output": vk.VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT,
    "depth_tests": (vk.VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | vk.VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT),
    "host": vk.VK_PIPELINE_STAGE_HOST_BIT,
}
_ACCESS = {
    "none": 0,
    "transfer_write": vk.VK_ACCESS_TRANSFER_WRITE_BIT,
    "transfer_read": vk.VK_ACCESS_TRANSFER_READ_BIT,
    "shader_write": vk.VK_ACCESS_SHADER_WRITE_BIT,
    "shader_read": vk.VK_ACCESS_SHADER_READ_BIT,
    "vertex_read": vk.VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT,
    "indirect_read": vk.VK_ACCESS_INDIRECT_COMMAND_READ_BIT,
    "uniform_read": vk.VK_ACCESS_UNIFORM_READ_BIT,
    "color_write": vk.VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT,
    "color_read": vk.VK_ACCESS_COLOR_ATTACHMENT_READ_BIT,
    "depth_write": vk.VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
    "host_write": vk.VK_ACCESS_HOST_WRITE_BIT,
    "host_read": vk.VK_ACCESS_HOST_READ_BIT,
}


def _stage(names: str) -> int:
    return flag_bits(_STAGES, names, "pipeline stage")


def _access(names: str) -> int:
    return flag_bits(_ACCESS, names, "access")


def _texel_region(image, rect, buf_offset: int):
    """The VkBufferImageCopy of ``rect`` = (x, y, w, h) of ``image`` (default:
    all of it) and tightly packed texels at ``buf_offset``."""
    x, y, w, h = rect if rect is not None else (0, 0, image.width, image.height)
    sub = vk.VkImageSubresourceLayers(aspectMask=image.aspect, mipLevel=0, baseArrayLayer=0, layerCount=1)
    return vk.VkBufferImageCopy(bufferOffset=buf_offset, bufferRowLength=0, bufferImageHeight=0,
                                imageSubresource=sub, imageOffset=vk.VkOffset3D(x, y, 0),
                                imageExtent=vk.VkExtent3D(w, h, 1))


class QueryPool:
    """A timestamp query pool; :meth:`results_ns` returns times relative to its first query read."""

    def __init__(self, device, count: int):
        """``count`` timestamp queries on ``device`` (a :class:`~splatedit.render.vk.core.Device`)."""
        self.dev = device
        self.count = count
        info = vk.VkQueryPoolCreateInfo(queryType=vk.VK_QUERY_TYPE_TIMESTAMP, queryCount=count)
        self.handle = call(vk.vkCreateQueryPool, device.device, info, None)
        track("query_pool", 1)

    def results_ns(self, count: int | None = None, first: int = 0) -> np.ndarray:
        """Queries ``first`` .. ``first + count`` (waits for them), in ns relative to query ``first``."""
        count = self.count - first if count is None else count
        data = np.zeros(count, dtype=np.uint64)
        call(vk.vkGetQueryPoolResults, self.dev.device, self.handle, first, count, data.nbytes,
             vk.ffi.from_buffer(data), 8, vk.VK_QUERY_RESULT_64_BIT | vk.VK_QUERY_RESULT_WAIT_BIT)
        return (data.astype(np.float64) - float(data[0])) * self.dev.timestamp_period_ns

    def destroy(self):
        release(self, "handle", vk.vkDestroyQueryPool, "query_pool")
