"""The real editor window refining a large-enough model: one Vulkan device.

A 60,000-splat model (the smallest that gets levels of detail,
``EDITOR_LOD_MIN_SPLATS``) opened with a 5 ms motion budget (moving frames
are levels of detail) and ``SPLATEDIT_REFINE_ABOVE_MS=1`` (every still view
is refined): after a wheel step the view is refined progressively to full
quality on the editor's own device, then the brush's pick map of the view is
drawn in chunks, and the process has created exactly one Vulkan device
(rendering, refinement, picking and presentation share it)."""

from __future__ import annotations

import pytest

from tests.app.window_harness import WINDOW, EditorProcess

pytestmark = [pytest.mark.window, pytest.mark.gpu]


def test_refinement_after_motion_uses_the_editors_one_device(xvfb, tmp_path, monkeypatch):
    from splatedit.bench.editor import bunny_surface_cloud
    from splatedit.io import write
    from splatedit.tolerances import EDITOR_LOD_MIN_SPLATS

    model = tmp_path / "refine.ply"
    write(model, bunny_surface_cloud(EDITOR_LOD_MIN_SPLATS), overwrite=True)
    monkeypatch.setenv("SPLATEDIT_REFINE_ABOVE_MS", "1")
    ed = EditorProcess(xvfb, tmp_path, str(model), "--budget-ms", "5")
    try:
        s = ed.idle(lambda s: s["loaded"] and s["full_quality"] and s["refinements"] >= 1,
                    "opened and refined", 120)
        done = s["refinements"]
        d0 = s["camera"]["distance"]
        ed.xdo("mousemove", WINDOW[0] // 2, WINDOW[1] // 2, "click", "5")      # a wheel step
        seen = ed.wait(lambda s: s["camera"]["distance"] != d0 and not s["full_quality"],
                       "a level-of-detail frame of the new view", 60)
        assert seen["n"] == EDITOR_LOD_MIN_SPLATS
        s = ed.idle(lambda s: s["full_quality"] and s["refinements"] > done and s["camera"]["distance"] != d0,
                    "the new view refined", 120)
        lr = s["last_refinement"]
        assert lr["done_s"] is not None and lr["steps"] >= 2 and lr["frames"] >= 1
        # then the brush's pick map of the still view, in chunks on the same device
        s = ed.idle(lambda s: s["pick_map_ready"], "the pick map of the view", 60)
        assert s["vulkan_devices_created"] == 1, s["vulkan_devices_created"]
    finally:
        ed.close()
