"""VkResult to exceptions, and the accounting of live Vulkan handles.

The ground floor of :mod:`splatedit.render.vk`: every other module of the
package raises :class:`VulkanError` through :func:`call` and counts the
handles it creates and destroys (:func:`track`, :func:`release`), which the
leak tests read (:func:`live_handles`).  It knows no device or command
buffer, so :mod:`~splatedit.render.vk.core` (the device) and
:mod:`~splatedit.render.vk.commands` (command buffers) both build on it
without importing each other both ways.
"""

from __future__ import annotations

import threading
from collections import Counter

import vulkan as vk

from splatedit.errors import SplatEditError


# ----------------------------------------------------------------- errors
class VulkanError(SplatEditError):
    """A Vulkan call failed; ``result`` is the VkResult name (e.g. ``VK_ERROR_OUT_OF_DEVICE_MEMORY``)."""

    def __init__(self, call: str, result: str, detail: str = ""):
        self.call = call
        self.result = result
        msg = f"{call} failed: {result}"
        if detail:
            msg += f" ({detail})"
        super().__init__(msg)


class DeviceNotFoundError(VulkanError):
    """No usable Vulkan device (no driver installed, or SPLATEDIT_DEVICE matched nothing)."""

    def __init__(self, message: str, devices: list[str]):
        self.devices = list(devices)
        SplatEditError.__init__(self, message)
        self.call = "device selection"
        self.result = "VK_ERROR_INITIALIZATION_FAILED"


def result_name(exc: BaseException) -> str:
    """The Vulkan result code name of a python-vulkan exception
    (``VkErrorOutOfDeviceMemory`` -> ``VK_ERROR_OUT_OF_DEVICE_MEMORY``)."""
    name = type(exc).__name__  # e.g. VkErrorOutOfDeviceMemory, VkTimeout
    out = ["VK"]
    word = ""
    for ch in name[2:]:
        if ch.isupper() and word:
            out.append(word.upper())
            word = ""
        word += ch
    if word:
        out.append(word.upper())
    return "_".join(out)


def call(fn, *args, name: str | None = None):
    """Call a raw binding function, turning every binding exception (errors and
    non-success codes alike) into :class:`VulkanError`."""
    try:
        return fn(*args)
    except (vk.VkError, vk.VkException) as exc:
        raise VulkanError(name or getattr(fn, "__name__", "vulkan call"), result_name(exc)) from None


# ---------------------------------------------------------- live handles
_LIVE: Counter = Counter()
_LIVE_LOCK = threading.Lock()


def track(kind: str, delta: int) -> None:
    """Count ``delta`` live Vulkan handles of ``kind`` (the leak tests read the counts)."""
    with _LIVE_LOCK:
        _LIVE[kind] += delta
        if _LIVE[kind] == 0:
            del _LIVE[kind]


def release(owner, attr: str, destroy_fn, kind: str) -> None:
    """Destroy ``owner.<attr>`` (a handle made on ``owner.dev``) with
    ``destroy_fn(VkDevice, handle, None)``, count it out of :func:`live_handles`
    as ``kind`` and set the attribute to None; nothing when it is None already
    (destroy methods stay idempotent)."""
    handle = getattr(owner, attr)
    if handle is not None:
        destroy_fn(owner.dev.device, handle, None)
        track(kind, -1)
        setattr(owner, attr, None)


def flag_bits(table: dict, names, what: str) -> int:
    """OR of ``table[name]`` over ``names``: an iterable of names, or one
    string of names joined by ``|`` (``"vert|frag"``); an unknown name raises
    ValueError naming ``what`` and the known names."""
    if isinstance(names, str):
        names = names.split("|")
    out = 0
    for n in names:
        try:
            out |= table[n.strip()]
        except KeyError:
            raise ValueError(f"unknown {what} {n!r}; known: {sorted(table)}") from None
    return out


_CREATED: Counter = Counter()


def count_created(kind: str) -> None:
    """Count one more object of ``kind`` created in this process (:func:`devices_created`)."""
    with _LIVE_LOCK:
        _CREATED[kind] += 1


def devices_created() -> int:
    """Vulkan devices (``vkCreateDevice``) this process has created so far (the
    editor creates one for rendering, refinement and presentation)."""
    with _LIVE_LOCK:
        return _CREATED["device"]


def live_handles() -> dict[str, int]:
    """Number of live Vulkan objects created through this layer, by kind."""
    with _LIVE_LOCK:
        return {k: v for k, v in _LIVE.items() if v}
