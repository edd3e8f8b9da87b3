"""Device capabilities beyond VkPhysicalDeviceProperties: the subgroup
properties (Vulkan 1.1 core, ``VkPhysicalDeviceSubgroupProperties``) that
decide which variant of a compute shader runs (:mod:`splatedit.render.gaussian.gpu_sort`)."""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import vulkan as vk

from splatedit.render.vk.core import Device
from splatedit.render.vk.handles import call


@dataclass(frozen=True)
class SubgroupProperties:
    """``size``: invocations per subgroup; ``compute``: subgroup operations
    allowed in compute shaders; ``ballot`` / ``arithmetic``: those operation
    classes supported."""
    size: int
    compute: bool
    ballot: bool
    arithmetic: bool


#: the subgroup properties asked so far, per device (forgotten with the device)
_SUBGROUP_PROPS: "weakref.WeakKeyDictionary[Device, SubgroupProperties]" = weakref.WeakKeyDictionary()


def subgroup_properties(dev: Device) -> SubgroupProperties:
    """The device's subgroup properties (lavapipe 22.3 on AVX2: size 8,
    compute and fragment stages, basic/vote/arithmetic/ballot/shuffle/quad)."""
    cached = _SUBGROUP_PROPS.get(dev)
    if cached is not None:
        return cached
    sp = vk.VkPhysicalDeviceSubgroupProperties()
    p2 = vk.VkPhysicalDeviceProperties2(pNext=sp)
    call(vk.vkGetPhysicalDeviceProperties2, dev.physical, p2)
    out = SubgroupProperties(
        size=int(sp.subgroupSize),
        compute=bool(sp.supportedStages & vk.VK_SHADER_STAGE_COMPUTE_BIT),
        ballot=bool(sp.supportedOperations & vk.VK_SUBGROUP_FEATURE_BALLOT_BIT),
        arithmetic=bool(sp.supportedOperations & vk.VK_SUBGROUP_FEATURE_ARITHMETIC_BIT))
    _SUBGROUP_PROPS[dev] = out
    return out


def is_cpu_device(dev: Device) -> bool:
    """Whether ``dev`` is a CPU implementation (VK_PHYSICAL_DEVICE_TYPE_CPU: lavapipe)."""
    return dev.properties.deviceType == vk.VK_PHYSICAL_DEVICE_TYPE_CPU
