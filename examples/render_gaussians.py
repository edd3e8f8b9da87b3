"""Render a Gaussian splatting scene from code: synthetic Gaussians on the
bundled bunny's splats, one frame, a pick and a PNG.  Run:
``.venv/bin/python examples/render_gaussians.py`` (writes scene.png into the
current folder); docs/gaussians.md explains the renderer."""

from splatedit.bench.gs_scenes import gaussians_from_splats
from splatedit.data import default_model_path
from splatedit.io import read
from splatedit.render.gaussian.renderer import GaussianRenderer
from splatedit.render.gaussian.headless import default_camera, render_gaussians_to_png

scene = gaussians_from_splats(read(default_model_path()))    # synthetic Gaussians on the bunny's splats
with GaussianRenderer() as r:                  # sort="gpu": the GPU radix sort; path="compute": the tile rasterizer
    r.set_gaussians(scene)                     # a splatedit.model.gaussians.GaussianCloud
    cam = default_camera(scene, 640, 480)
    img = r.render(cam, 640, 480)              # (480, 640, 4) uint8
    idx, depth = r.pick(cam, 640, 480)         # Gaussian per pixel (-1: none), view depth
render_gaussians_to_png(scene, "scene.png", size=(640, 480))
print(img.shape, f"{(idx >= 0).mean():.0%} of the pixels hit a Gaussian")
