"""One frame model and one renderer interface for splats and Gaussians
(splatedit.render.frame, gs_passes, scene): both renderers satisfy the
SceneRenderer protocol the viewport drives, the Gaussian frames are checked
pass lists, and the Gaussian resident frame is the read-back frame."""

import numpy as np
import pytest

from splatedit.data import gaussian_scene_path
from splatedit.io import read_gaussians
from splatedit.render.camera import Camera
from splatedit.render.frame import Frame, Resolve
from splatedit.render.gaussian.passes import (GsPick, GsPrepare, GsQuads, GsSort, GsTiles, draw_frame, pick_frame,
                                       prepare_frame)
from splatedit.render.gaussian.resources import gaussian_bounds
from splatedit.render.scene import SceneRenderer
from tests.render.scenes import sphere

pytestmark = pytest.mark.gpu


@pytest.fixture(scope="module")
def scene():
    return read_gaussians(str(gaussian_scene_path()))


def test_both_renderers_satisfy_the_scene_renderer_protocol(renderer, scene):
    from splatedit.render.gaussian.renderer import GaussianRenderer
    renderer.set_cloud(sphere(500))
    assert isinstance(renderer, SceneRenderer) and renderer.supports_detail and renderer.resident_frames
    with GaussianRenderer(device=renderer.dev) as g:
        g.set_cloud(scene)
        assert isinstance(g, SceneRenderer) and not g.supports_detail and not g.resident_frames


def test_gaussian_frames_are_ordered_pass_lists():
    assert [type(p) for p in prepare_frame("gpu").passes] == [GsPrepare, GsSort]
    assert prepare_frame("gpu").passes[0].compact and not prepare_frame("bitonic").passes[0].compact
    assert [type(p) for p in prepare_frame("cpu").passes] == [GsPrepare]      # sorted on the host after it
    assert [type(p) for p in draw_frame("raster").passes] == [GsQuads, Resolve]
    assert [type(p) for p in draw_frame("compute").passes] == [GsTiles, Resolve]
    assert draw_frame("raster").timings == ("draw", "resolve")
    assert [type(p) for p in pick_frame().passes] == [GsPrepare, GsPick]
    with pytest.raises(ValueError, match="order"):
        Frame([GsPrepare(), GsQuads()])                 # drawing before any sort
    with pytest.raises(ValueError, match="records"):
        Frame([GsSort()])
    with pytest.raises(ValueError):
        draw_frame("fragments")


@pytest.mark.parametrize("path", ["raster", "compute"])
def test_gaussian_resident_frame_is_the_read_back_frame(scene, path):
    from splatedit.render.gaussian.renderer import GaussianRenderer
    lo, hi = gaussian_bounds(scene)
    cam = Camera.frame(lo, hi, aspect=4 / 3, direction=(0.3, 0.4, 1.0))
    with GaussianRenderer(path=path, sort="cpu") as g:
        g.set_gaussians(scene)
        img = g.render(cam, 120, 90)
        out = g.render_resident(cam, 120, 90)
        assert out is g.targets.out and g.last_timings_ms["draw"] >= 0 and g.last_timings_ms["visible"] > 0
        again = g.targets.read_output(lambda cb: None)
        assert np.array_equal(again, img)
        assert (img[..., :3].min(axis=2) < 230).mean() > 0.05          # not an empty frame
