"""Instance, device, queue, validation messages and command submission
(errors and handle accounting: :mod:`splatedit.render.vk.handles`).

Every raw ``vk*`` call of splatedit lives in this package (``splatedit.render.vk``).
The rest of the renderer talks to :class:`Device` and the resource classes.

Python-binding pitfalls handled here (see docs in the package ``__init__``):
non-success codes (``VK_TIMEOUT``, ``VK_SUBOPTIMAL_KHR``...) raise in the
bindings and are caught where they are expected; nested structs are kept in
locals until the call returns; ``VK_WHOLE_SIZE`` is spelled ``WHOLE_SIZE``.
"""

from __future__ import annotations

import os
import threading

import vulkan as vk

from splatedit.render.vk.commands import CommandBuffer
from splatedit.render.vk.handles import (DeviceNotFoundError, VulkanError, call, count_created, devices_created,
                                         flag_bits, live_handles, release, result_name, track)

#: VK_WHOLE_SIZE as a uint64 (the bindings' -1 overflows uint64 fields)
WHOLE_SIZE = 0xFFFFFFFFFFFFFFFF
VALIDATION_LAYER = "VK_LAYER_KHRONOS_validation"
API_VERSION = vk.VK_MAKE_VERSION(1, 2, 0)


# ---------------------------------------------------- validation messages
_MESSAGES: list[str] = []
_MSG_LOCK = threading.Lock()


def validation_enabled() -> bool:
    """True when ``SPLATEDIT_VALIDATION`` asks for the Khronos validation layer."""
    return os.environ.get("SPLATEDIT_VALIDATION", "0") not in ("", "0", "false", "no")


def drain_validation_messages() -> list[str]:
    """Return and forget the validation warnings/errors reported so far."""
    with _MSG_LOCK:
        out = list(_MESSAGES)
        _MESSAGES.clear()
    return out


def _debug_callback(severity, types, data, user_data):  # called from the driver thread
    try:
        text = vk.ffi.string(data.pMessage).decode("utf-8", "replace")
        if data.pMessageIdName:
            text = vk.ffi.string(data.pMessageIdName).decode("utf-8", "replace") + ": " + text
    except Exception as exc:  # never raise into C
        text = f"<undecodable validation message: {exc}>"
    sev = "ERROR" if severity & vk.VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT else "WARNING"
    with _MSG_LOCK:
        _MESSAGES.append(f"[{sev}] {text}")
    return 0


def _messenger_info():
    return vk.VkDebugUtilsMessengerCreateInfoEXT(
        messageSeverity=(vk.VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT
                         | vk.VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT),
        messageType=(vk.VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT
                     | vk.VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT
                     | vk.VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT),
        pfnUserCallback=_debug_callback)


# ------------------------------------------------------------ the device
def _device_name(pd) -> str:
    props = vk.vkGetPhysicalDeviceProperties(pd)
    name = props.deviceName
    return name if isinstance(name, str) else vk.ffi.string(name).decode()


class Device:
    """Vulkan instance + one logical device with one graphics/compute queue.

    Args:
        device_name: substring of the device name to use; default: env var
            ``SPLATEDIT_DEVICE``, else the first discrete GPU, else the first device.
        validation: enable ``VK_LAYER_KHRONOS_validation`` with a debug
            messenger; default: env var ``SPLATEDIT_VALIDATION=1``.
        instance_extensions: extra instance extensions (e.g. those glfw needs
            for a window surface).
        device_extensions: extra device extensions (e.g. ``VK_KHR_swapchain``).

    Destroy with :meth:`close` (or use as a context manager); objects created
    from the device must be destroyed before it.
    """

    def __init__(self, device_name: str | None = None, validation: bool | None = None,
                 instance_extensions=(), device_extensions=()):
        self.instance = None
        self.device = None
        self._messenger = None
        #: the device's command pool (command buffers are allocated from it)
        self.command_pool = None
        self._closed = False
        if validation is None:
            validation = validation_enabled()
        if device_name is None:
            device_name = os.environ.get("SPLATEDIT_DEVICE") or None
        self.validation = validation
        try:
            self._create_instance(validation, list(instance_extensions))
            self._pick_device(device_name)
            self._create_device(list(device_extensions))
        except BaseException:
            self.close()
            raise

    # -- creation
    def _create_instance(self, validation, extensions):
        try:
            layers_avail = {p.layerName for p in vk.vkEnumerateInstanceLayerProperties()}
        except Exception:
            layers_avail = set()
        layers = []
        dbg = None
        if validation:
            if VALIDATION_LAYER not in layers_avail:
                raise VulkanError("vkCreateInstance", "VK_ERROR_LAYER_NOT_PRESENT",
                                  f"SPLATEDIT_VALIDATION=1 but {VALIDATION_LAYER} is not installed "
                                  "(Debian: apt-get install vulkan-validationlayers)")
            layers.append(VALIDATION_LAYER)
            extensions = extensions + ["VK_EXT_debug_utils"]
            dbg = _messenger_info()
        app = vk.VkApplicationInfo(pApplicationName="splatedit", applicationVersion=1,
                                   pEngineName="splatedit", engineVersion=1, apiVersion=API_VERSION)
        info = vk.VkInstanceCreateInfo(pApplicationInfo=app, ppEnabledLayerNames=layers or None,
                                       ppEnabledExtensionNames=extensions or None,
                                       pNext=dbg)
        try:
            self.instance = vk.vkCreateInstance(info, None)
        except (vk.VkError, vk.VkException, OSError) as exc:
            name = result_name(exc) if isinstance(exc, (vk.VkError, vk.VkException)) else str(exc)
            if "INCOMPATIBLE_DRIVER" in name:
                raise DeviceNotFoundError(
                    "no Vulkan driver is installed (vkCreateInstance: VK_ERROR_INCOMPATIBLE_DRIVER); "
                    "install one, e.g. Debian: apt-get install mesa-vulkan-drivers (lavapipe)", []) from None
            raise VulkanError("vkCreateInstance", name) from None
        track("instance", 1)
        if validation:
            create = vk.vkGetInstanceProcAddr(self.instance, "vkCreateDebugUtilsMessengerEXT")
            self._messenger = call(create, self.instance, dbg, None, name="vkCreateDebugUtilsMessengerEXT")
            track("debug_messenger", 1)
        self._dbg_info = dbg  # keep the callback alive

    def _pick_device(self, wanted):
        try:
            pds = vk.vkEnumeratePhysicalDevices(self.instance)
        except (vk.VkError, vk.VkException):
            pds = []
        names = [_device_name(pd) for pd in pds]
        if not pds:
            raise DeviceNotFoundError(
                "no Vulkan device found (is a Vulkan driver installed? Debian: apt-get install "
                "mesa-vulkan-drivers for the lavapipe CPU device)", [])
        if wanted:
            hits = [i for i, n in enumerate(names) if wanted.lower() in n.lower()]
            if not hits:
                listing = "; ".join(f"[{i}] {n}" for i, n in enumerate(names))
                raise DeviceNotFoundError(
                    f"no Vulkan device name contains {wanted!r} (SPLATEDIT_DEVICE); "
                    f"available devices: {listing}", names)
            idx = hits[0]
        else:
            types = [vk.vkGetPhysicalDeviceProperties(pd).deviceType for pd in pds]
            idx = next((i for i, t in enumerate(types)
                        if t == vk.VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU), 0)
        self.physical = pds[idx]
        self.name = names[idx]
        self.properties = vk.vkGetPhysicalDeviceProperties(self.physical)
        self.limits = self.properties.limits
        self.timestamp_period_ns = float(self.limits.timestampPeriod)
        self.memory_properties = vk.vkGetPhysicalDeviceMemoryProperties(self.physical)
        fams = vk.vkGetPhysicalDeviceQueueFamilyProperties(self.physical)
        want = vk.VK_QUEUE_GRAPHICS_BIT | vk.VK_QUEUE_COMPUTE_BIT
        qf = next((i for i, f in enumerate(fams) if (f.queueFlags & want) == want), None)
        if qf is None:
            raise DeviceNotFoundError(f"device {self.name!r} has no graphics+compute queue", names)
        self.queue_family = qf
        self.timestamp_valid_bits = fams[qf].timestampValidBits

    def _create_device(self, extensions):
        prio = vk.ffi.new("float[1]", [1.0])
        qinfo = vk.VkDeviceQueueCreateInfo(queueFamilyIndex=self.queue_family, queueCount=1,
                                           pQueuePriorities=prio)
        avail = vk.vkGetPhysicalDeviceFeatures(self.physical)
        atomics = self._atomic_features()
        feats = vk.VkPhysicalDeviceFeatures(
            largePoints=avail.largePoints, multiDrawIndirect=avail.multiDrawIndirect,
            shaderFloat64=0, vertexPipelineStoresAndAtomics=avail.vertexPipelineStoresAndAtomics,
            shaderInt64=1 if atomics else 0)
        self.features = feats
        #: the device runs the compute splat rasterizer (splatedit.render.splat.compute_raster):
        #: 64-bit buffer atomics (atomicMin of depth << 32 | id) and float32 buffer
        #: atomicAdd (VK_EXT_shader_atomic_float), both enabled at creation
        self.compute_raster = atomics
        chain = None
        if atomics:
            extensions = extensions + ["VK_EXT_shader_atomic_float"]
            fl = vk.VkPhysicalDeviceShaderAtomicFloatFeaturesEXT(shaderBufferFloat32AtomicAdd=1,
                                                                  shaderBufferFloat32Atomics=1)
            chain = vk.VkPhysicalDeviceVulkan12Features(pNext=fl, shaderBufferInt64Atomics=1)
        info = vk.VkDeviceCreateInfo(queueCreateInfoCount=1, pQueueCreateInfos=[qinfo],
                                     pEnabledFeatures=feats, pNext=chain,
                                     ppEnabledExtensionNames=extensions or None)
        self.device = call(vk.vkCreateDevice, self.physical, info, None)
        track("device", 1)
        count_created("device")
        self.queue = vk.vkGetDeviceQueue(self.device, self.queue_family, 0)
        pinfo = vk.VkCommandPoolCreateInfo(
            flags=vk.VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT,
            queueFamilyIndex=self.queue_family)
        self.command_pool = call(vk.vkCreateCommandPool, self.device, pinfo, None)
        track("command_pool", 1)

    def _atomic_features(self) -> bool:
        """True when the physical device offers what the compute splat
        rasterizer needs: Vulkan 1.2 with shaderInt64 and
        shaderBufferInt64Atomics, and VK_EXT_shader_atomic_float with
        shaderBufferFloat32AtomicAdd (lavapipe 22.3 and NVIDIA drivers have both)."""
        api = self.properties.apiVersion
        if (vk.VK_VERSION_MAJOR(api), vk.VK_VERSION_MINOR(api)) < (1, 2):
            return False
        try:
            names = {e.extensionName for e in vk.vkEnumerateDeviceExtensionProperties(self.physical, None)}
        except (vk.VkError, vk.VkException):
            return False
        if "VK_EXT_shader_atomic_float" not in names:
            return False
        fl = vk.VkPhysicalDeviceShaderAtomicFloatFeaturesEXT()
        f12 = vk.VkPhysicalDeviceVulkan12Features(pNext=fl)
        f2 = vk.VkPhysicalDeviceFeatures2(pNext=f12)
        vk.vkGetPhysicalDeviceFeatures2(self.physical, f2)
        return bool(f2.features.shaderInt64 and f12.shaderBufferInt64Atomics and fl.shaderBufferFloat32AtomicAdd)

    # -- helpers
    def memory_type(self, type_bits: int, flags: int) -> int:
        mp = self.memory_properties
        for i in range(mp.memoryTypeCount):
            if type_bits & (1 << i) and (mp.memoryTypes[i].propertyFlags & flags) == flags:
                return i
        raise VulkanError("memory type selection", "VK_ERROR_OUT_OF_DEVICE_MEMORY",
                          f"no memory type with flags {flags:#x} in {type_bits:#x}")

    def host_visible_device_local(self, type_bits: int) -> bool:
        """True if some memory type is both device-local and host-visible (CPU devices, ReBAR)."""
        try:
            self.memory_type(type_bits, vk.VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT
                             | vk.VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT
                             | vk.VK_MEMORY_PROPERTY_HOST_COHERENT_BIT)
            return True
        except VulkanError:
            return False

    def wait_idle(self):
        if self.device is not None:
            call(vk.vkDeviceWaitIdle, self.device)

    # -- command submission
    def submit(self, record, *, wait: bool = True):
        """Record commands with ``record(cmd)`` (cmd is a :class:`CommandBuffer`),
        submit them and wait for completion."""
        cb = CommandBuffer(self)
        try:
            cb.begin()
            record(cb)
            cb.end()
            cb.submit_and_wait()
        finally:
            cb.destroy()

    # -- teardown
    def close(self):
        """Destroy the device and instance (idempotent)."""
        if self._closed:
            return
        self._closed = True
        if self.device is not None:
            try:
                vk.vkDeviceWaitIdle(self.device)
            except Exception:
                pass
            if self.command_pool is not None:
                vk.vkDestroyCommandPool(self.device, self.command_pool, None)
                track("command_pool", -1)
                self.command_pool = None
            vk.vkDestroyDevice(self.device, None)
            track("device", -1)
            self.device = None
        if self.instance is not None:
            if self._messenger is not None:
                destroy = vk.vkGetInstanceProcAddr(self.instance, "vkDestroyDebugUtilsMessengerEXT")
                destroy(self.instance, self._messenger, None)
                track("debug_messenger", -1)
                self._messenger = None
            vk.vkDestroyInstance(self.instance, None)
            track("instance", -1)
            self.instance = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def list_devices() -> list[str]:
    """Names of the Vulkan devices (empty if no driver is installed)."""
    try:
        inst = vk.vkCreateInstance(vk.VkInstanceCreateInfo(
            pApplicationInfo=vk.VkApplicationInfo(apiVersion=API_VERSION)), None)
    except Exception:
        return []
    try:
        return [_device_name(pd) for pd in vk.vkEnumeratePhysicalDevices(inst)]
    finally:
        vk.vkDestroyInstance(inst, None)
