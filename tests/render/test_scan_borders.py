"""Rendered open borders: no huge discs past the border of a mesh whose edge
is a strip of sliver triangles, and no holes inside it."""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from splatedit.model.mesh import cloud_from_mesh, mesh_vertex_radii
from splatedit.render.camera import Camera
from splatedit.tolerances import MESH_SPLAT_RADIUS_FACTOR
from tests.model.scan_helpers import grid_with_sliver_border
from tests.render.test_ground_truth import eye_rays

W = H = 256


def _plane_hits(cam):
    """World (x, y) where every pixel's ray meets z = 0."""
    d = eye_rays(cam, W, H) @ cam.view_matrix()[:3, :3]
    t = -cam.eye[2] / d[..., 2]
    return (cam.eye + t[..., None] * d)[..., :2]


def test_sliver_border_renders_without_flaps_or_holes(renderer):
    v, f, top = grid_with_sliver_border()          # spacing 1, x in [0, 64], y in [0, top]
    cloud = cloud_from_mesh(v, f)
    r_old = mesh_vertex_radii(v, f) * MESH_SPLAT_RADIUS_FACTOR
    scale = (r_old / cloud.radii)[:, None]
    old = cloud.replace(u=cloud.u * scale, v=cloud.v * scale)
    cam = Camera(eye=(32.0, 20.0, 120.0), target=(32.0, 20.0, 0.0), up=(0.0, 1.0, 0.0), fov_deg=40.0)
    xy = _plane_hits(cam)
    px = float(abs(xy[0, 1, 0] - xy[0, 0, 0]))       # model units per pixel
    overhang = {}
    for name, c in (("old", old), ("new", cloud)):
        renderer.set_cloud(c)
        fg = renderer.render_buffers(cam, W, H)["weight"] > 0
        overhang[name] = float(xy[..., 1][fg].max() - top)
        if name == "new":
            inside = (xy[..., 0] > 0) & (xy[..., 0] < 64) & (xy[..., 1] > 0) & (xy[..., 1] < top)
            holes = ndimage.binary_erosion(inside, iterations=1) & ~fg
            assert holes.sum() == 0, f"{holes.sum()} background pixels inside the mesh"
    assert overhang["old"] > 4.0, overhang          # the flaps of the longest-edge rule
    assert overhang["new"] <= 1.5 + px, overhang
