"""GUI benchmark: cost of one Dear ImGui panel frame drawn by our Vulkan GUI pass.

``bench_gui`` yields one dict (the CLI prints it as a JSON line) for an
editor-like panel (tool palette buttons, selection/solver readouts, display
sliders and checkboxes, a 12-entry history list; about the widget count of
issue 10's panels) over a ``size`` target, validation off:

* ``imgui_ms``: ImGui's widget code on the CPU (new_frame and the widgets);
* ``record_ms``: ``Gui.render`` on the CPU: ``imgui.render`` (ImGui builds the
  draw lists), texture requests, geometry upload, command recording;
* ``frame_ms``: wall time of record + submit + wait of the GUI pass (what a
  frame pays on lavapipe, where the GPU is the CPU), and ``gpu_ms``: the GUI
  pass alone by timestamps;
* ``clear_ms``: the same submission with an empty pass (clear only): the
  fixed cost of a submission, measured in the same run;
* ``cpu_overlay_ms``: today's CPU path for a text panel of the same number
  of lines (``splatedit.app.ui.overlay.text_panel`` + ``blend`` into the frame),
  without the readback it also needs.

Medians over ``repeats`` frames after warm-up.  The machine is shared: compare
the ratios, measured in the same run.
"""

from __future__ import annotations

import time
from typing import Iterator

import numpy as np

HISTORY = tuple(f"{i + 1}. move handle {i % 3} by (0.0{i}, 0.1, -0.02)" for i in range(12))


def editor_panel(state: dict) -> int:
    """Widgets of a typical editor panel; returns the number of text lines shown."""
    from imgui_bundle import imgui
    imgui.set_next_window_pos((10, 10), imgui.Cond_.first_use_ever)
    imgui.set_next_window_size((320, 520), imgui.Cond_.first_use_ever)
    imgui.begin("splatedit")
    lines = 0
    for name in ("Support", "Handle", "Erase", "Curve", "Grab", "Rotate", "Scale"):
        if imgui.button(name):
            state["tool"] = name
        imgui.same_line()
    imgui.new_line()
    for text in ("model: bunny.ply  35,947 splats", "selection: 1,204 support, 87 handle",
                 "solver: LU 0.12 s, residual 3.1e-12", "fit: 412 centres, 2 levels",
                 "drag: 0.031 m (x 0.020, y 0.024)"):
        imgui.text(text)
        lines += 1
    _, state["size"] = imgui.slider_float("splat size", state["size"], 0.1, 4.0)
    _, state["bg"] = imgui.slider_float("background", state["bg"], 0.0, 1.0)
    _, state["colours"] = imgui.checkbox("file colours", state["colours"])
    _, state["heat"] = imgui.checkbox("distortion heat map", state["heat"])
    _, state["xyz"] = imgui.input_float3("translate", state["xyz"])
    if imgui.collapsing_header("History", imgui.TreeNodeFlags_.default_open):
        for i, h in enumerate(HISTORY):
            if imgui.selectable(h, state["at"] == i)[0]:
                state["at"] = i
            lines += 1
    imgui.end()
    return lines + 6


def bench_gui(size=(1280, 720), repeats: int = 30) -> Iterator[dict]:
    from splatedit.render import vk as V
    from splatedit.render.gui.gui import Gui
    w, h = size
    dev = V.Device(validation=False)
    img = fb = gui = pool = None
    try:
        img = V.Image(dev, w, h, "rgba8", ("color", "transfer_src"))
        gui = Gui(dev)
        fb = V.Framebuffer(dev, gui.painter.render_pass("rgba8"), [img], w, h)
        pool = V.QueryPool(dev, 2)
        state = {"tool": "", "size": 1.0, "bg": 0.2, "colours": False, "heat": False,
                 "xyz": [0.0, 0.0, 0.0], "at": 11}
        times = {k: [] for k in ("imgui_ms", "record_ms", "frame_ms", "gpu_ms", "clear_ms")}
        lines = 0
        for it in range(repeats + 3):
            t0 = time.perf_counter()
            gui.new_frame(w, h, 1 / 60)
            lines = editor_panel(state)
            t1 = time.perf_counter()
            rec_ms = {}

            def rec(cb, empty=False):
                cb.reset_queries(pool)
                cb.timestamp(pool, 0, bottom=False)
                r0 = time.perf_counter()
                if empty:
                    gui.painter.record(cb, fb, [], scale=(0, 0), translate=(0, 0), fmt="rgba8",
                                       clear=(0.1, 0.1, 0.1, 1.0))
                else:
                    gui.render(cb, fb, fmt="rgba8", clear=(0.1, 0.1, 0.1, 1.0))
                rec_ms["v"] = 1e3 * (time.perf_counter() - r0)
                cb.timestamp(pool, 1)
            t2 = time.perf_counter()
            dev.submit(rec)
            t3 = time.perf_counter()
            gpu = float(pool.results_ns()[1]) * 1e-6
            record = rec_ms["v"]
            t4 = time.perf_counter()
            dev.submit(lambda cb: rec(cb, empty=True))
            t5 = time.perf_counter()
            if it >= 3:
                times["imgui_ms"].append(1e3 * (t1 - t0))
                times["record_ms"].append(record)
                times["frame_ms"].append(1e3 * (t3 - t2))
                times["gpu_ms"].append(gpu)
                times["clear_ms"].append(1e3 * (t5 - t4))
        out = {"bench": "gui", "size": f"{w}x{h}", "draws": gui.last_stats.draws,
               "vertices": gui.last_stats.vertices}
        out.update({k: round(float(np.median(v)), 3) for k, v in times.items()})
        cpu = _cpu_overlay_ms(lines, w, h, repeats)
        if cpu is not None:
            out["cpu_overlay_ms"] = round(cpu, 3)
            out["frame_over_cpu_overlay"] = round(out["frame_ms"] / cpu, 2)
        out["frame_over_clear"] = round(out["frame_ms"] / max(out["clear_ms"], 1e-6), 2)
        yield out
    finally:
        for obj in (pool, fb, gui, img):
            if obj is not None:
                (obj.close if hasattr(obj, "close") else obj.destroy)()
        dev.close()


def _cpu_overlay_ms(lines: int, w: int, h: int, repeats: int) -> float | None:
    """Median ms of today's CPU overlay for a panel of ``lines`` text lines
    (the panel image is cached by text, as in the editor: mostly the blend)."""
    try:
        from splatedit.app.ui import overlay
    except ImportError:           # the editor package is optional for this comparison
        return None
    frame = np.zeros((h, w, 4), np.uint8)
    text = tuple(f"line {i}: " + HISTORY[i % len(HISTORY)] for i in range(lines))
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        patch = overlay.text_panel(text)
        overlay.blend(frame, overlay.Patch(10, 10, patch))
        runs.append(1e3 * (time.perf_counter() - t0))
    return float(np.median(runs))
