"""The Vulkan swapchain presenter on a real glfw window under Xvfb.

Validation messages (the presenter's device is a ``core.Device``) fail the
test through tests/conftest.py.
"""

from __future__ import annotations

import os
import time

import numpy as np
import pytest

from tests.app.xwd import read_xwd

pytestmark = [pytest.mark.window, pytest.mark.gpu]


@pytest.fixture
def window(xvfb, monkeypatch):
    monkeypatch.setenv("DISPLAY", xvfb["display"])
    from splatedit.render.vk.swapchain import SwapchainPresenter
    from splatedit.render.vk.window import Window
    win = Window("swapchain-test", 320, 200)
    pres = SwapchainPresenter(win.handle, validation=True)
    yield win, pres, xvfb["screen"]
    pres.close()
    win.close()


def _show(win, pres, rgba, frames=3):
    for _ in range(frames):
        win.poll()
        pres.present(rgba)
    time.sleep(0.2)


def test_present_resize_and_recreate(window):
    win, pres, screen = window
    assert pres.extent == (320, 200)
    img = np.zeros((200, 320, 4), np.uint8)
    img[:100, :, 0] = 255          # top half red
    img[100:, :, 2] = 255          # bottom half blue
    _show(win, pres, img)
    shot = read_xwd(screen)
    assert tuple(shot[50, 100]) == (255, 0, 0) and tuple(shot[150, 100]) == (0, 0, 255)
    # resize: the next present re-creates the swapchain at the new size
    win.set_size(400, 260)
    for _ in range(20):
        win.poll(0.01)
        if win.framebuffer_size() == (400, 260):
            break
    img2 = np.full((260, 400, 4), 40, np.uint8)
    img2[..., 1] = 200
    _show(win, pres, img2)
    assert pres.extent == (400, 260)
    shot = read_xwd(screen)
    assert tuple(shot[250, 390]) == (40, 200, 40)
    # a frame of the wrong size is shown at the top-left, the rest black
    _show(win, pres, img)
    shot = read_xwd(screen)
    assert tuple(shot[50, 100]) == (255, 0, 0) and tuple(shot[250, 390]) == (0, 0, 0)
    # an out-of-date swapchain (as after VK_ERROR_OUT_OF_DATE_KHR) is re-created
    old = pres.swapchain
    pres.needs_recreate = True
    _show(win, pres, img2, frames=1)
    assert pres.swapchain is not None and pres.swapchain != old


def test_minimized_window_skips_frames(window):
    win, pres, screen = window
    img = np.zeros((200, 320, 4), np.uint8)
    n0 = pres.frames_presented
    win.iconify()             # no window manager under Xvfb: may stay visible, must not fail
    for _ in range(3):
        win.poll(0.02)
        pres.present(img)
    win.restore()
    _show(win, pres, img)
    assert pres.frames_presented > n0


def test_presenter_uses_core_device_and_leaks_nothing(xvfb, monkeypatch):
    """The presenter's device is a core.Device (env parsing, SPLATEDIT_DEVICE,
    error mapping) and every handle it creates is counted and destroyed."""
    monkeypatch.setenv("DISPLAY", xvfb["display"])
    from splatedit.render.vk import core
    from splatedit.render.vk.swapchain import SwapchainPresenter
    from splatedit.render.vk.window import Window
    base = core.live_handles()
    win = Window("swapchain-leaks", 160, 120)
    try:
        pres = SwapchainPresenter(win.handle)
        try:
            assert isinstance(pres.dev, core.Device)
            assert pres.validation        # SPLATEDIT_VALIDATION=1 (tests/conftest.py)
            live = core.live_handles()
            for kind in ("instance", "device", "surface", "swapchain", "semaphore", "fence",
                         "command_buffer", "buffer", "memory"):
                assert live.get(kind, 0) > base.get(kind, 0), kind
            img = np.zeros((120, 160, 4), np.uint8)
            for _ in range(3):
                win.poll()
                pres.present(img)
            pres.needs_recreate = True      # re-creation must not leak either
            pres.present(img)
        finally:
            pres.close()
            pres.close()                    # idempotent
        assert core.live_handles() == base
        # SPLATEDIT_DEVICE is honoured (core's selection and its error)
        monkeypatch.setenv("SPLATEDIT_DEVICE", "no-such-vulkan-device")
        with pytest.raises(core.DeviceNotFoundError, match="SPLATEDIT_DEVICE"):
            SwapchainPresenter(win.handle)
        assert core.live_handles() == base
    finally:
        win.close()


@pytest.mark.parametrize("value", ["false", "no", "0"])
def test_validation_off_values_match_core(xvfb, monkeypatch, value):
    """SPLATEDIT_VALIDATION=false/no/0 turns validation off, as for the renderer."""
    monkeypatch.setenv("DISPLAY", xvfb["display"])
    monkeypatch.setenv("SPLATEDIT_VALIDATION", value)
    from splatedit.render.vk.swapchain import SwapchainPresenter
    from splatedit.render.vk.window import Window
    win = Window("swapchain-env", 160, 120)
    try:
        pres = SwapchainPresenter(win.handle)
        try:
            assert pres.validation is False and pres.dev.validation is False
        finally:
            pres.close()
    finally:
        win.close()
