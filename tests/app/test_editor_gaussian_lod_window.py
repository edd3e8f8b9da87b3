"""A Gaussian Splatting scene orbited in the real editor window (Xvfb +
xdotool): with a frame budget the full set cannot meet (``--budget-ms 5``),
the frames drawn while the camera moves are the Gaussian level of detail
(fewer Gaussians, status ``last_render.lod``), and once motion stops the full
set is drawn again (every Gaussian, full resolution, ``full_quality``): at
once, or (``SPLATEDIT_REFINE_ABOVE_MS=1``: every full frame counts as slow)
in chunks over several presented frames (``refinements``)."""

from __future__ import annotations

import pytest

from tests.app.window_harness import WINDOW, EditorProcess

pytestmark = [pytest.mark.window, pytest.mark.gpu, pytest.mark.slow]


@pytest.mark.parametrize("refine", ["at_once", "chunks"])
def test_orbiting_draws_the_lod_then_the_full_set(xvfb, tmp_path, monkeypatch, refine):
    from splatedit.data import gaussian_scene_path
    if refine == "chunks":
        monkeypatch.setenv("SPLATEDIT_REFINE_ABOVE_MS", "1")
    ed = EditorProcess(xvfb, tmp_path, str(gaussian_scene_path()), "--budget-ms", "5")
    try:
        s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0 and "lod" not in s["jobs"],
                    "scene loaded and ranked", 90)
        n = s["n"]
        assert s["gaussians"] and s["last_render"]["gaussians"]
        assert not s["last_render"]["lod"] and s["last_render"]["splats"] == n and s["full_quality"]
        frames = s["interactive_frames"]
        cx, cy = WINDOW[0] // 2, WINDOW[1] // 2
        ed.xdo("mousemove", cx, cy, "mousedown", "2")
        try:
            for k in range(1, 40):
                ed.xdo("mousemove", cx + 6 * k, cy + (k % 3))
                st = ed.status()
                if st.get("last_render", {}).get("lod") and st["interactive_frames"] > frames + 1:
                    break
            moving = ed.wait(lambda s: s["last_render"]["lod"], "a level-of-detail frame while orbiting")
        finally:
            ed.xdo("mouseup", "2")
        lr = moving["last_render"]
        assert lr["gaussians"] and lr["interactive"] and 0 < lr["splats"] < n, lr
        assert not moving["full_quality"]
        cam0 = s["camera"]
        s = ed.idle(lambda s: s["full_quality"] and not s["last_render"]["lod"], "the full set after motion", 60)
        assert s["last_render"]["splats"] == n and s["last_render"]["div"] == 1 and s["last_render"]["gaussians"]
        if refine == "chunks":
            assert s["refinements"] >= 1 and s["last_refinement"]["steps"] >= 2, s["last_refinement"]
        else:
            assert s["refinements"] == 0
        assert s["camera"]["yaw"] != cam0["yaw"]                      # it did orbit
        assert s["validation_messages"] == 0
    finally:
        ed.close()
