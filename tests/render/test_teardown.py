"""Vulkan objects are released on every failure path: a render target that
cannot be created part-way, and a renderer closed after a device loss."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.render import vk as V
from splatedit.render.camera import Camera
from splatedit.render.splat.renderer import Renderer
from tests.render.scenes import sphere


def _oom(*_a, **_k):
    raise V.VulkanError("vkAllocateMemory", "VK_ERROR_OUT_OF_DEVICE_MEMORY")


def _fail_nth(monkeypatch, name: str, nth: int):
    """Make the nth (0-based) V.<name>(...) from now on raise an out-of-memory VulkanError."""
    real = getattr(V, name)
    calls = [0]

    def flaky(*a, **k):
        calls[0] += 1
        if calls[0] - 1 == nth:
            _oom()
        return real(*a, **k)
    monkeypatch.setattr(V, name, flaky)
    return calls


@pytest.fixture
def small(renderer):
    """A renderer on the shared device with a small cloud and warm pipeline caches."""
    r = Renderer(device=renderer.dev)
    cloud = sphere(500)
    r.set_cloud(cloud)
    cam = Camera.frame(*cloud.bounds(), 1.0)
    r.render(cam, 32, 32)
    r.pick(cam, 32, 32)
    yield r, cam
    r.close()


@pytest.mark.parametrize("name, nth", [("Image", 0), ("Image", 2), ("Image", 3),
                                       ("Framebuffer", 0), ("Framebuffer", 1), ("DescriptorSet", 0)])
def test_failed_render_target_leaks_nothing(small, monkeypatch, name, nth):
    r, cam = small
    r.dev.wait_idle()
    r._targets.destroy()           # the state a new size starts from
    r._targets = None
    base = V.live_handles()
    calls = _fail_nth(monkeypatch, name, nth)
    with pytest.raises(V.VulkanError, match="OUT_OF_DEVICE_MEMORY"):
        r.render(cam, 48, 40)
    assert calls[0] == nth + 1
    assert V.live_handles() == base
    assert r._targets is None
    monkeypatch.undo()
    img = r.render(cam, 48, 40)     # still usable
    assert img.shape == (40, 48, 4) and (img[..., :3] < 250).any()


@pytest.mark.parametrize("name, nth", [("Image", 0), ("Image", 1), ("Framebuffer", 0)])
def test_failed_pick_target_leaks_nothing(small, monkeypatch, name, nth):
    r, cam = small
    r.render(cam, 40, 40)           # targets without the picking images
    base = V.live_handles()
    _fail_nth(monkeypatch, name, nth)
    with pytest.raises(V.VulkanError):
        r.pick(cam, 40, 40)
    assert V.live_handles() == base
    monkeypatch.undo()
    idx, _ = r.pick(cam, 40, 40)
    assert (idx >= 0).any()


def test_image_memory_failure_part_way_leaks_nothing(renderer, monkeypatch):
    """The device refuses the memory of the 8-byte-per-texel accumulators (the
    depth image before them is already created): a VulkanError and no leak."""
    import splatedit.render.vk.resources as res
    r = Renderer(device=renderer.dev)
    try:
        r.set_cloud(sphere(200))
        base = V.live_handles()
        real = res.call
        sizes = []

        def call(fn, *a, **k):
            if fn is res.vk.vkAllocateMemory:
                sizes.append(a[1].allocationSize)
                if a[1].allocationSize >= 60 * 60 * 8:
                    _oom()
            return real(fn, *a, **k)
        monkeypatch.setattr(res, "call", call)
        with pytest.raises(V.VulkanError, match="OUT_OF_DEVICE_MEMORY"):
            r.render(Camera.frame(*r.cloud.bounds(), 1.0), 60, 60)
        assert len(sizes) == 2                      # depth image created, first accumulator refused
        assert V.live_handles() == base
    finally:
        monkeypatch.undo()
        r.close()


def test_close_after_device_loss_still_destroys_everything(monkeypatch):
    base = V.live_handles()
    r = Renderer()
    cloud = sphere(500)
    r.set_cloud(cloud)
    cam = Camera.frame(*cloud.bounds(), 1.0)
    r.render(cam, 32, 32)
    r.set_basis(np.arange(10), *(np.zeros((10, 4)),) * 4)
    r.pick(cam, 32, 32)
    assert V.live_handles() != base

    def lost():
        raise V.VulkanError("vkDeviceWaitIdle", "VK_ERROR_DEVICE_LOST")
    monkeypatch.setattr(r.dev, "wait_idle", lost)
    with pytest.raises(V.VulkanError, match="DEVICE_LOST"):
        r.close()
    assert V.live_handles() == base
    r.close()                       # idempotent


def test_exit_keeps_the_with_block_error(renderer, monkeypatch):
    base = V.live_handles()
    with pytest.raises(RuntimeError, match="inside"):
        with Renderer(device=renderer.dev) as r:
            r.set_cloud(sphere(100))

            def lost():
                raise V.VulkanError("vkDeviceWaitIdle", "VK_ERROR_DEVICE_LOST")
            monkeypatch.setattr(r.dev, "wait_idle", lost)
            raise RuntimeError("inside")
    assert V.live_handles() == base
