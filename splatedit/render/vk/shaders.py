"""Compiled shaders: where their SPIR-V lies, shader modules, and
specialization constants."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import vulkan as vk

from splatedit.render.vk.core import Device
from splatedit.render.vk.handles import VulkanError, call, release, track

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


class ShaderModule:
    """A VkShaderModule loaded from the packaged SPIR-V file ``name`` (e.g. ``"splat.vert"``)."""
    def __init__(self, device: Device, name: str):
        self.dev = device
        self.name = name
        code = spirv_path(name).read_bytes()
        info = vk.VkShaderModuleCreateInfo(codeSize=len(code), pCode=code)
        self.handle = call(vk.vkCreateShaderModule, device.device, info, None)
        track("shader_module", 1)

    def destroy(self):
        release(self, "handle", vk.vkDestroyShaderModule, "shader_module")


def specialization(spec: tuple[tuple[int, int], ...]):
    """(VkSpecializationInfo or None, objects to keep alive until the pipeline
    is created) of ``spec`` = ((constant_id, int32 value), ...): the values
    packed as consecutive int32 (4 bytes each, in the order given)."""
    if not spec:
        return None, None
    entries = [vk.VkSpecializationMapEntry(constantID=cid, offset=4 * i, size=4) for i, (cid, _) in enumerate(spec)]
    values = np.array([v for _, v in spec], "<i4")
    data = vk.ffi.new("char[]", values.tobytes())
    info = vk.VkSpecializationInfo(mapEntryCount=len(entries), pMapEntries=entries,
                                   dataSize=values.nbytes, pData=data)
    return info, (entries, data)


def stage_info(stage: int, module: ShaderModule, spec) -> "vk.VkPipelineShaderStageCreateInfo":
    """One shader stage (``stage``: a VK_SHADER_STAGE_*_BIT) of ``module``'s
    ``main`` with specialization info ``spec`` (or None)."""
    return vk.VkPipelineShaderStageCreateInfo(stage=stage, module=module.handle, pName="main",
                                              pSpecializationInfo=spec)
