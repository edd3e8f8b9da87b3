"""Eye-dome lighting (frame_passes.EyeDomeResolve, shaders_glsl/resolve_edl.frag):
on a grey step scene it darkens the far side of the depth edge and leaves flat
areas alone; off, the frame is the plain resolve, byte for byte."""

import numpy as np
import pytest

from splatedit.model.cloud import SplatCloud
from splatedit.render.camera import Camera
from splatedit.render.splat.passes import EyeDomeResolve, Resolve, splat_frame
from tests.render.scenes import plane

pytestmark = pytest.mark.gpu

W, H = 96, 64
STEP = 0.1          # the right half lies this much farther away (depth 3.0 vs 3.1: log2 step 0.047)


def _step_scene():
    """Two half planes facing the camera: x < 0 at z = 0, x >= 0 at z = -STEP."""
    p = plane(n_side=120, size=6.0)
    left, right = p.positions[:, 0] < 0, p.positions[:, 0] >= 0
    pos = np.concatenate([p.positions[left], p.positions[right] - [0.0, 0.0, STEP]])
    u = np.concatenate([p.u[left], p.u[right]])
    v = np.concatenate([p.v[left], p.v[right]])
    return SplatCloud(pos, u, v, None, name="step")


def _render(r, edl):
    r.edl = edl
    try:
        return r.render(Camera((0.0, 0.0, 3.0), (0.0, 0.0, 0.0)), W, H)[..., :3].astype(float)
    finally:
        r.edl = False


def test_edl_frame_ends_with_the_eye_dome_resolve():
    for path in ("raster", "compute"):
        assert type(splat_frame(path).passes[-1]) is Resolve
        f = splat_frame(path, edl=True)
        assert type(f.passes[-1]) is EyeDomeResolve and f.timings[-1] == "shading"
        assert [type(p) for p in f.passes[:-1]] == [type(p) for p in splat_frame(path).passes[:-1]]
    assert not splat_frame("raster", resolve=False, edl=True).passes[-1].name.startswith("resolve")


@pytest.mark.parametrize("path", ["raster", "compute"])
def test_edl_darkens_the_depth_edge_and_not_flat_areas_and_off_is_unchanged(renderer, path):
    r = renderer
    old = r.raster_path, r.grey_shading
    r.raster_path, r.grey_shading = path, True
    try:
        r.set_cloud(_step_scene())
        if r.frame_path(W, H) != path:
            pytest.skip(f"the device draws this frame on the {r.frame_path(W, H)} path only")
        off = _render(r, False)
        assert type(r.splat_frame(W, H).passes[-1]) is Resolve
        r.edl = True
        assert type(r.splat_frame(W, H).passes[-1]) is EyeDomeResolve
        on = _render(r, True)
        assert type(r.splat_frame(W, H).passes[-1]) is Resolve        # back off after the frame
        off_again = _render(r, False)
    finally:
        r.raster_path, r.grey_shading = old
    assert np.array_equal(off, off_again)                  # EDL leaves nothing behind
    ratio = on.mean(axis=2) / off.mean(axis=2)             # (H, W), sRGB units
    col = ratio[8:-8].mean(axis=0)                         # per column, rows away from the border
    edge = int(np.argmin(col))
    assert W // 2 - 2 <= edge <= W // 2 + 2                # the step is in the middle of the image
    assert col[edge] < 0.5, col[edge - 3:edge + 4]         # the far side's edge pixels are darkened
    assert np.abs(off[8:-8, edge] - off[8:-8, edge - 1]).max() <= 2   # without EDL the step does not show
    flat = np.r_[0:edge - 3, edge + 3:W]
    assert np.abs(on[:, flat] - off[:, flat]).max() <= 1.0  # flat areas: unchanged (to 1/255)
