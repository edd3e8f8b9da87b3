"""Presentation cost of an editor frame: the readback path versus the GPU path.

Both paths start from the same full-quality scene drawn by the editor's
:class:`~splatedit.app.view.viewport.Viewport` and end with the finished frame in
a ``bgra8`` image like a swapchain image (no window: the acquire / present
calls, the same for both, are left out):

* **CPU path** (``SPLATEDIT_GUI=0``, the editor before the GUI): the frame is
  read back (``Viewport.render``), a status panel and the brush ring are
  blended on the CPU (:mod:`splatedit.app.ui.overlay`), the pixels are swizzled
  into a host-visible staging buffer and copied into the image
  (``SwapchainPresenter.present``);
* **GPU path** (the editor with its ImGui interface): the frame stays on the
  device (``Viewport.render(resident=True)``), is blitted into the image and
  an ImGui panel of the same text plus the brush ring is drawn over it by
  the GUI pass (``Gui.render``), one submission.

``present_*_ms`` is each path's frame time minus the scene's own render time
measured by the renderer's timestamps, medians over ``repeats`` frames;
``present_cpu_ms`` with the panel image cached (an idle frame: the text did
not change), ``present_cpu_text_ms`` with the panel's text re-rasterised (a
frame while dragging: its readout and frame time change every frame).  The
GUI path costs the same either way (ImGui lays out its text every frame).
"""

from __future__ import annotations

import time

import numpy as np

PANEL_LINES = tuple(f"line {i} of the status panel, 1234 ms" for i in range(9))


def _gui_panel(imgui) -> None:
    imgui.set_next_window_pos(imgui.ImVec2(8, 27), imgui.Cond_.always)
    imgui.begin("panel", None, imgui.WindowFlags_.always_auto_resize.value)
    for t in PANEL_LINES:
        imgui.text(t)
    imgui.button("Support")
    imgui.end()
    imgui.get_background_draw_list().add_circle(imgui.ImVec2(600, 300), 24.0, 0xFFFFFFFF, 0, 2.0)


def bench_presentation(vp, cam, w: int, h: int, repeats: int = 5) -> dict:
    """``present_cpu_ms`` / ``present_gpu_ms`` (and the whole frames) for the
    viewport's current scene at ``w`` x ``h``; ``vp`` has a cloud set."""
    from imgui_bundle import imgui

    from splatedit.app.ui import overlay as ov
    from splatedit.render import vk as V
    from splatedit.render.gui.gui import Gui

    dev = vp.full.r.dev
    target = V.Image(dev, w, h, "bgra8", ("color", "transfer_dst"))
    staging = V.Buffer(dev, w * h * 4, ("transfer_src",), host_visible=True)
    gui = Gui(dev)
    tgt = _Target(target)
    try:
        cpu, gpu, cpu_frame, gpu_frame, moving = [], [], [], [], []
        cached = ov.text_panel(PANEL_LINES)
        for it in range(2 * repeats + 2):
            # --- CPU path: readback, blend, swizzle, copy; odd frames re-render the
            # panel's text, as while dragging (its readout and frame time change)
            t0 = time.perf_counter()
            frame = vp.render(cam, w, h)
            render_ms = vp.full.r.last_timings_ms.get("total", 0.0)
            panel = cached if it % 2 == 0 else ov.text_panel(PANEL_LINES[:-1] + (f"distance {it * 0.01:.4f}",))
            for p in (ov.Patch(8, 27, panel), ov.Patch(600, 300, ov.ring(24))):
                ov.blend(frame, p)
            dst = staging.view()[:w * h * 4].reshape(h, w, 4)
            dst[..., 0], dst[..., 1], dst[..., 2], dst[..., 3] = frame[..., 2], frame[..., 1], frame[..., 0], 255

            def copy(cb):
                cb.image_barrier(target, "transfer_dst", "transfer", "none", "transfer", "transfer_write")
                cb.copy_buffer_to_image(staging, target)
            dev.submit(copy)
            t1 = time.perf_counter()
            # --- GPU path: resident frame, blit, GUI pass
            t2 = time.perf_counter()
            res = vp.render(cam, w, h, resident=True)
            render_ms_gpu = vp.full.r.last_timings_ms.get("total", 0.0)
            gui.new_frame(w, h, 1 / 60)
            _gui_panel(imgui)

            def draw(cb):
                cb.memory_barrier("color_output", "color_write", "transfer", "transfer_read")
                cb.image_barrier(target, "transfer_dst", "transfer", "none", "transfer", "transfer_write")
                cb.blit_image(res.image, target, (0, 0, res.width, res.height), (0, 0, w, h))
                gui.render_into(cb, tgt, final="color")
            dev.submit(draw)
            t3 = time.perf_counter()
            if it >= 2:
                gpu_frame.append((t3 - t2) * 1e3)
                gpu.append((t3 - t2) * 1e3 - render_ms_gpu)
                if it % 2 == 0:
                    cpu_frame.append((t1 - t0) * 1e3)
                    cpu.append((t1 - t0) * 1e3 - render_ms)
                else:
                    moving.append((t1 - t0) * 1e3 - render_ms)
        med = lambda v: round(float(np.median(v)), 2)  # noqa: E731
        return {"present_cpu_ms": med(cpu), "present_cpu_text_ms": med(moving), "present_gpu_ms": med(gpu),
                "frame_cpu_ms": med(cpu_frame), "frame_gpu_ms": med(gpu_frame),
                "present_gpu_over_cpu": round(med(gpu) / max(med(cpu), 1e-6), 2),
                "present_gpu_over_cpu_text": round(med(gpu) / max(med(moving), 1e-6), 2)}
    finally:
        dev.wait_idle()
        tgt.destroy()
        gui.close()
        staging.destroy()
        target.destroy()


class _Target:
    """An Image seen as ``Gui.render_into``'s target (framebuffers kept per pass)."""

    def __init__(self, image):
        self.image = image
        self.format = "bgra8"
        self._fbs = {}

    def framebuffer(self, rp):
        from splatedit.render import vk as V
        fb = self._fbs.get(rp)
        if fb is None:
            fb = self._fbs[rp] = V.Framebuffer(self.image.dev, rp, [self.image], self.image.width,
                                               self.image.height)
        return fb

    def destroy(self) -> None:
        for fb in self._fbs.values():
            fb.destroy()
        self._fbs.clear()
