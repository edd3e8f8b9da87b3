"""The viewport keeps a renderer in step with the document through the
SceneRenderer interface only (splatedit.render.scene): a renderer that
exposes nothing else draws the same deformed, tinted frame and pick."""

import numpy as np
import pytest

from splatedit.bench.editor import support_and_handle, bunny_surface_cloud
from splatedit.app.view.camera_control import OrbitCamera
from splatedit.render.scene import SceneRenderer

pytestmark = pytest.mark.gpu

#: the members SceneRenderer declares (attributes and methods)
MEMBERS = frozenset(SceneRenderer.__annotations__) | {
    k for k, v in vars(SceneRenderer).items() if callable(v) and not k.startswith("_")}


class InterfaceOnly:
    """A real renderer seen through its SceneRenderer members alone (any other
    member raises AttributeError)."""

    def __init__(self, r):
        object.__setattr__(self, "_r", r)

    def __getattr__(self, name):
        if name not in MEMBERS:
            raise AttributeError(f"{name} is not a SceneRenderer member")
        return getattr(self._r, name)

    def __setattr__(self, name, value):
        if name not in MEMBERS:
            raise AttributeError(f"{name} is not a SceneRenderer member")
        setattr(self._r, name, value)


def test_viewport_drives_a_renderer_through_the_scene_interface_only():
    from splatedit.app.view.viewport import Viewport
    from splatedit.deform.basis import DeformationBasis
    from splatedit.render.splat.renderer import Renderer
    assert {"set_cloud", "set_basis", "render", "pick", "supports_detail"} <= MEMBERS
    cloud = bunny_surface_cloud(8000)
    sup, hnd = support_and_handle(cloud, 800)
    basis = DeformationBasis.fit(cloud, sup, [hnd])
    m = np.eye(4)
    m[:3, 3] = [0.0, 0.15, 0.0]
    cam = OrbitCamera(scene_radius=cloud.diagonal / 2)
    lo, hi = cloud.bounds()
    cam.frame((lo + hi) / 2, cloud.diagonal / 2, 160 / 120)
    frames = []
    for wrap in (lambda r: r, InterfaceOnly):
        vp = Viewport(renderer=wrap(Renderer(raster_path="raster")))   # one path: no timed probe between them
        try:
            vp.set_cloud(cloud)
            vp.set_selection(sup, hnd, 1)
            vp.set_basis(basis)
            vp.set_dc(basis.displacement([m]))
            vp.grey = True
            frames.append((vp.render(cam, 160, 120), vp.pick(cam, 160, 120)[0]))
        finally:
            vp.close()
    (img_a, pick_a), (img_b, pick_b) = frames
    # two renderers of the same frame differ by at most one level in a few pixels (additive blending);
    # a pixel where two overlapping splats lie at the same depth may pick either (0.27% of the
    # pixels seen): where the picks differ, they are overlapping neighbours
    assert np.abs(img_a.astype(int) - img_b).max() <= 1 and (pick_a != pick_b).mean() < 0.01
    both = (pick_a != pick_b) & (pick_a >= 0) & (pick_b >= 0)
    gap = np.linalg.norm(cloud.positions[pick_a[both]] - cloud.positions[pick_b[both]], axis=1)
    assert (gap <= 2.0 * cloud.radii[pick_a[both]]).all()
    assert (both == (pick_a != pick_b)).all()                   # never splat against background
    assert (pick_a >= 0).mean() > 0.1
