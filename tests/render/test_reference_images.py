"""Small scenes against committed reference PNGs (tests/render/references/).

Regenerate after an intended visual change with
``SPLATEDIT_UPDATE_REFERENCES=1 pytest tests/render/test_reference_images.py``;
on failure actual/expected/diff images are written to tests/_artifacts/.
Tolerances: see REF_* in tests/render/conftest.py.
"""

from __future__ import annotations

import numpy as np

from splatedit.render.camera import Camera
from tests.render.deform_util import gaussian_basis
from tests.render.scenes import sphere, torus

W = H = 160


def test_torus(renderer, compare_reference):
    cloud = torus(100, 40)
    renderer.set_cloud(cloud)
    cam = Camera(eye=(0.6, -2.2, 2.0), target=(0, 0, 0), up=(0, 0, 1), fov_deg=45)
    compare_reference("torus", renderer.render(cam, W, H))


def test_deformed_sphere(renderer, compare_reference):
    cloud = sphere(6000, colors=True)
    renderer.set_cloud(cloud)
    idx = np.flatnonzero(cloud.positions[:, 1] > 0.0)
    B, Bx, By, Bz = gaussian_basis(cloud.positions[idx], seed=5, sigma=0.6)
    renderer.set_basis(idx, B, Bx, By, Bz)
    renderer.set_displacement([[0.0, 0.3, 0.0], [0.1, 0.2, 0.0], [0.0, 0.0, 0.2], [-0.1, 0.1, 0.0]])
    cam = Camera(eye=(0.0, 0.8, 4.0), target=(0, 0.2, 0), fov_deg=40)
    compare_reference("sphere_deformed", renderer.render(cam, W, H))


def test_selection_tint(renderer, compare_reference):
    cloud = sphere(6000)
    renderer.set_cloud(cloud)
    support = cloud.positions[:, 0] > -0.2
    handle = cloud.positions[:, 0] > 0.6
    renderer.set_selection(support, handle)
    cam = Camera(eye=(0.5, 0.6, 3.8), target=(0, 0, 0), fov_deg=40)
    img = renderer.render(cam, W, H)
    compare_reference("sphere_selection", img)
    # the handle is greenish, the support bluish (Botsch & Kobbelt 2005, Fig. 1)
    renderer.set_selection(None, None)
    plain = renderer.render(cam, W, H).astype(int)
    d = img.astype(int) - plain
    assert (d[..., 2] > 10).sum() > 500 and (d[..., 1] > 10).sum() > 100
