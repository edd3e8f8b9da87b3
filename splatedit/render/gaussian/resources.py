"""Buffers layouts, render passes and per-size images of the Gaussian splatting
renderer (:mod:`splatedit.render.gaussian.renderer`), and the packing of a
GaussianCloud into its GPU buffers (mirrors shaders_glsl/gs_common.glsl); the
packing of a deformation basis and a selection is shared with the splat
renderer (:mod:`splatedit.render.gpu_units`)."""

from __future__ import annotations

import numpy as np

from splatedit.model.gaussians import GaussianCloud
from splatedit.render import vk as V
from splatedit.render.targets import RenderTarget, SizedTargets
from splatedit.render.uniforms import GS_FRAME_UBO, GS_GEOM, GS_REC

GS_UBO_BYTES = GS_FRAME_UBO.itemsize
GS_GEOM_FLOATS = GS_GEOM.itemsize // 4
GS_REC_BYTES = GS_REC.itemsize
GS_PREP_WG = 64
GS_SORT_WG = 256
NO_BASIS_ROW = 0xFFFFFFFF
#: set 0 of the pre-pass, the sort and the draws: frame UBO, geometry, SH
#: bands 1-3, basis row per Gaussian, basis rows, records, keys, order,
#: indirect draw, deformation UBO (shaders_glsl/gs_common.glsl)
GS_SET = (V.Binding(0, "uniform", "vert|frag|comp"), V.Binding(1, "storage", "comp"),
           V.Binding(2, "storage", "comp"), V.Binding(3, "storage", "comp"), V.Binding(4, "storage", "comp"),
           V.Binding(5, "storage", "vert|comp"), V.Binding(6, "storage", "comp"),
           V.Binding(7, "storage", "vert|comp"), V.Binding(8, "storage", "comp"), V.Binding(9, "uniform", "comp"),
           V.Binding(11, "storage", "comp"))
GS_RESOLVE_SET = (V.Binding(0, "uniform", "frag"), V.Binding(10, "sampled", "frag"))
#: depth sorts: "auto" (:func:`splatedit.render.gaussian.renderer.choose_sort`), "cpu"
#: (numpy), "gpu" (the GPU radix sort), "bitonic" (the GPU sort it replaced)
SORTS = ("auto", "cpu", "gpu", "bitonic")
#: draw paths: "auto" (:func:`splatedit.render.gaussian.renderer.choose_path`), "raster"
#: (a quad per Gaussian, fixed-function blending), "compute" (the tile rasterizer)
PATHS = ("auto", "raster", "compute")


def rp_accum(fmt: str) -> V.RenderPassDesc:
    """The Gaussian accumulation render pass: one colour attachment of format ``fmt``, cleared, left readable by shaders."""
    return V.RenderPassDesc(colors=(V.Attachment(fmt, "clear", final="shader_read"),))


def gaussian_bounds(cloud: GaussianCloud, sigmas: float = 3.0) -> tuple[np.ndarray, np.ndarray]:
    """Box (lo, hi), each (3,) float64, of the centres grown by ``sigmas``
    times each Gaussian's largest standard deviation (model units)."""
    r = sigmas * cloud.scales().max(axis=1)
    p = cloud.positions
    return (p - r[:, None]).min(axis=0), (p + r[:, None]).max(axis=0)


class GaussianTargets(SizedTargets):
    """Per-size images: the RGBA accumulator, pick index + depth, framebuffers."""

    def _create(self, r):       # r: the GaussianRenderer
        dev = r.dev
        # storage: the compute tile rasterizer (gaussian/tiles.py) writes it instead of the quad draw
        self.accum = self.add(V.Image(dev, self.width, self.height, r.accum_format, ("color", "sampled", "storage")))
        self.fb_accum = self.framebuffer(r.cache.render_pass(rp_accum(r.accum_format)), [self.accum])
        self.out = self.add(V.Image(dev, self.width, self.height, "rgba8", ("color", "transfer_src")))
        self.offscreen = RenderTarget(self.out, "rgba8", "transfer_src")
        self.resolve_set = self.add(V.DescriptorSet(dev, r.cache.set_layout(GS_RESOLVE_SET)))
        self.resolve_set.write({0: r.ubo, 10: (self.accum, r.sampler)})


def pack_geometry(cloud: GaussianCloud, origin: np.ndarray, scale: float):
    """GPU arrays of a scene: ((n, 16) float32 geometry, the
    :data:`~splatedit.render.uniforms.GS_GEOM` records: centre relative to
    ``origin`` / ``scale``, opacity, covariance xx xy xz yy yz zz / scale^2, SH DC
    rgb, unit shortest axis; (n, m) uint32 SH bands 1-3 as pairs of half floats (m = 0 for degree 0))."""
    n = len(cloud)
    rec = np.zeros(n, GS_GEOM)
    rec["center"] = (cloud.positions - origin) / scale
    rec["opacity"] = cloud.opacities()
    c = cloud.covariances() / (scale * scale)
    rec["cov"] = c[:, [0, 0, 0, 1, 1, 2], [0, 1, 2, 1, 2, 2]]
    rec["sh_dc"] = cloud.sh[:, 0, :]
    shortest = np.argmin(cloud.scales(), axis=1)          # the heat map's normal (2DGS: the third axis)
    rec["normal"] = cloud.rotation_matrices()[np.arange(n), :, shortest]
    geom = rec.view(np.float32).reshape(n, GS_GEOM_FLOATS)
    rest = np.ascontiguousarray(cloud.sh[:, 1:, :], np.float32).reshape(n, -1).astype(np.float16)
    if rest.shape[1] % 2:
        rest = np.concatenate([rest, np.zeros((n, 1), np.float16)], axis=1)
    return geom, np.ascontiguousarray(rest).view(np.uint32)
