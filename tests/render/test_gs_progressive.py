"""The Gaussian full frame drawn in chunks (splatedit.render.gaussian.progressive):
consecutive chunks of the sorted order blended front to back give the
one-shot frame; until done it shows the frame under it; a pick between the
steps (it rewrites the pre-pass records) makes it sort again."""

import numpy as np
import pytest

from splatedit.data import gaussian_scene_path
from splatedit.io import read_gaussians
from splatedit.render.camera import Camera
from splatedit.render.gaussian.resources import gaussian_bounds

pytestmark = pytest.mark.gpu


def test_chunks_give_the_one_shot_frame_and_show_the_under_frame_meanwhile():
    from splatedit.render.gaussian.renderer import GaussianRenderer
    from splatedit.render.gaussian.progressive import GaussianProgressiveFrame
    scene = read_gaussians(str(gaussian_scene_path()))
    lo, hi = gaussian_bounds(scene)
    cam = Camera.frame(lo, hi, aspect=4 / 3, direction=(0.3, 0.4, 1.0))
    w, h = 200, 150
    with GaussianRenderer() as r:
        r.set_gaussians(scene)
        whole = r.render(cam, w, h)
        under = np.zeros((h, w, 4), np.uint8)
        f = GaussianProgressiveFrame(r, cam, w, h, chunk=700)
        f.set_under(under)
        f.step()                                       # the sort
        assert f.phase == "attr" and not f.done and f.show() is under
        f.step()
        r.pick(cam, w, h)                              # rewrites the records: the next step sorts again
        f.step()
        assert f.phase == "attr" and f.next == 0
        steps = 0
        while not f.done:
            f.step()
            steps += 1
            if not f.done:
                assert f.show() is under and 0 < f.fraction < 1
        assert steps >= 3 and f.fraction == 1.0
        img = f.show()
        diff = np.abs(img.astype(int) - whole)
        assert diff.max() <= 1, diff.max()             # the same sums in the same order
        assert (img[..., :3].min(axis=2) < 230).mean() > 0.05     # not an empty frame
        f.close()
