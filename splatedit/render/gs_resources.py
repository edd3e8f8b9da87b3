"""Buffers layouts, render passes and per-size images of the Gaussian splatting
renderer (:mod:`splatedit.render.gaussians`), and the packing of a
GaussianCloud, a deformation basis and a selection into its GPU buffers
(mirrors shaders_glsl/gs_common.glsl)."""

from __future__ import annotations

import numpy as np

from splatedit.errors import ParameterError
from splatedit.model.gaussians import GaussianCloud
from splatedit.render import vk as V
from splatedit.render.renderer import RenderTarget
from splatedit.tolerances import RENDER_MAX_BASIS_COLUMNS

_UBO_BYTES = 224
_GEOM_FLOATS = 16
_REC_BYTES = 64
_MAX_GROUPS = (RENDER_MAX_BASIS_COLUMNS + 3) // 4
#: deform.glsl's block: dC (3 vec4 per group) and the handle rotations (4 vec4 per group)
_DEFORM_UBO_BYTES = 48 * _MAX_GROUPS + 64 * _MAX_GROUPS
_MAX_SIZE = 16384
_PREP_WG = 64
_SORT_WG = 256
_NONE = 0xFFFFFFFF
#: set 0 of the pre-pass, the sort and the draws: frame UBO, geometry, SH
#: bands 1-3, basis row per Gaussian, basis rows, records, keys, order,
#: indirect draw, deformation UBO (shaders_glsl/gs_common.glsl)
_GS_SET = (V.Binding(0, "uniform", "vert|frag|comp"), V.Binding(1, "storage", "comp"),
           V.Binding(2, "storage", "comp"), V.Binding(3, "storage", "comp"), V.Binding(4, "storage", "comp"),
           V.Binding(5, "storage", "vert|comp"), V.Binding(6, "storage", "comp"),
           V.Binding(7, "storage", "vert|comp"), V.Binding(8, "storage", "comp"), V.Binding(9, "uniform", "comp"),
           V.Binding(11, "storage", "comp"))
_RESOLVE_SET = (V.Binding(0, "uniform", "frag"), V.Binding(10, "sampled", "frag"))
_RP_PICK = V.RenderPassDesc(colors=(V.Attachment("r32ui", "clear", final="transfer_src"),),
                            depth=V.Attachment("d32f", "clear", final="transfer_src"))
SORTS = ("cpu", "gpu")


def _rp_accum(fmt: str) -> V.RenderPassDesc:
    return V.RenderPassDesc(colors=(V.Attachment(fmt, "clear", final="shader_read"),))


def _rp_resolve(target: RenderTarget) -> V.RenderPassDesc:
    return V.RenderPassDesc(colors=(V.Attachment(target.format, "dont_care", final=target.final),))


def gaussian_bounds(cloud: GaussianCloud, sigmas: float = 3.0) -> tuple[np.ndarray, np.ndarray]:
    """Box (lo, hi), each (3,) float64, of the centres grown by ``sigmas``
    times each Gaussian's largest standard deviation (model units)."""
    r = sigmas * cloud.scales().max(axis=1)
    p = cloud.positions
    return (p - r[:, None]).min(axis=0), (p + r[:, None]).max(axis=0)


class _Targets:
    """Per-size images: the RGBA accumulator, pick index + depth, framebuffers."""

    def __init__(self, r, width: int, height: int):      # r: the GaussianRenderer
        self.width, self.height = width, height
        self.objects = []
        self.target_fbs = {}
        self._r = r
        try:
            dev = r.dev
            self.accum = self._add(V.Image(dev, width, height, r.accum_format, ("color", "sampled")))
            self.fb_accum = self._add(V.Framebuffer(dev, r.cache.render_pass(_rp_accum(r.accum_format)),
                                                    [self.accum], width, height))
            self.out = self._add(V.Image(dev, width, height, "rgba8", ("color", "transfer_src")))
            self.offscreen = RenderTarget(self.out, "rgba8", "transfer_src")
            self.resolve_set = self._add(V.DescriptorSet(dev, r.cache.set_layout(_RESOLVE_SET)))
            self.resolve_set.write({0: r.ubo, 10: (self.accum, r.sampler)})
            self.fb_pick = None
        except BaseException:
            self.destroy()
            raise

    def _add(self, obj):
        self.objects.append(obj)
        return obj

    def target_fb(self, target: RenderTarget):
        hit = self.target_fbs.get(target.serial)
        if hit is None:
            rp = self._r.cache.render_pass(_rp_resolve(target))
            fb = self._add(V.Framebuffer(self._r.dev, rp, [target.attachment], self.width, self.height))
            hit = self.target_fbs[target.serial] = (target, fb)
        return hit[1]

    def ensure_pick(self):
        if self.fb_pick is None:
            dev = self._r.dev
            self.pick_index = self._add(V.Image(dev, self.width, self.height, "r32ui", ("color", "transfer_src")))
            self.pick_depth = self._add(V.Image(dev, self.width, self.height, "d32f", ("depth", "transfer_src")))
            self.fb_pick = self._add(V.Framebuffer(dev, self._r.cache.render_pass(_RP_PICK),
                                                   [self.pick_index, self.pick_depth], self.width, self.height))

    def destroy(self):
        for o in reversed(self.objects):
            o.destroy()
        self.objects.clear()
        self.target_fbs.clear()


def pack_geometry(cloud: GaussianCloud, origin: np.ndarray, scale: float):
    """GPU arrays of a scene: ((n, 16) float32 geometry: centre relative to
    ``origin`` / ``scale``, opacity, covariance xx xy xz yy yz zz / scale^2, SH DC
    rgb, unit shortest axis; (n, m) uint32 SH bands 1-3 as pairs of half floats (m = 0 for degree 0))."""
    n = len(cloud)
    geom = np.zeros((n, _GEOM_FLOATS), np.float32)
    geom[:, 0:3] = (cloud.positions - origin) / scale
    geom[:, 3] = cloud.opacities()
    c = cloud.covariances() / (scale * scale)
    geom[:, 4:10] = c[:, [0, 0, 0, 1, 1, 2], [0, 1, 2, 1, 2, 2]]
    geom[:, 10:13] = cloud.sh[:, 0, :]
    shortest = np.argmin(cloud.scales(), axis=1)          # the heat map's normal (2DGS: the third axis)
    geom[:, 13:16] = cloud.rotation_matrices()[np.arange(n), :, shortest]
    rest = np.ascontiguousarray(cloud.sh[:, 1:, :], np.float32).reshape(n, -1).astype(np.float16)
    if rest.shape[1] % 2:
        rest = np.concatenate([rest, np.zeros((n, 1), np.float16)], axis=1)
    return geom, np.ascontiguousarray(rest).view(np.uint32)


def pack_deform_block(dC: np.ndarray, rot, scale: float) -> np.ndarray:
    """deform.glsl's uniform block as float32: dC (K, 3) (model units, divided
    by ``scale``) zero-padded to 4 groups as rows dC[3g + i] = (dC_{4g..4g+3})[i];
    then per group g the rotation of handle g of ``rot`` (a RotationDisplacement
    or None): (unit axis, angle; 0 = none), frame offsets D_0..D_3 / ``scale``."""
    pad = np.zeros((4 * _MAX_GROUPS, 3))
    pad[:len(dC)] = np.asarray(dC, np.float64) / scale
    blocks = np.zeros((_MAX_GROUPS, 4, 4))
    if rot is not None:
        for g in rot.rotating:
            r = rot.rotations[g]
            blocks[g, 0, :3] = r.w / r.angle
            blocks[g, 0, 3] = r.angle
            blocks[g, 1:, :] = (r.offsets / scale).T
    block = np.concatenate([pad.reshape(_MAX_GROUPS, 4, 3).transpose(0, 2, 1).reshape(-1), blocks.reshape(-1)])
    return np.ascontiguousarray(block, np.float32)


def pack_basis_rows(mats, scale: float) -> np.ndarray:
    """Basis rows for the GPU: B, Bx, By, Bz (N, K) -> (max(N, 1), G, 4, 4)
    float32, G = ceil(K / 4) groups of (B, Bx, By, Bz) x 4 columns, gradients
    per GPU unit (times ``scale``), zero-padded."""
    k = mats[0].shape[1]
    g = (k + 3) // 4
    n = len(mats[0])
    rows = np.zeros((max(n, 1), g, 4, 4), np.float32)
    for j, a in enumerate([mats[0]] + [m * scale for m in mats[1:]]):
        padded = np.zeros((n, 4 * g))
        padded[:, :k] = a
        rows[:n, :, j, :] = padded.reshape(n, g, 4)
    return rows


def selection_flags(n: int, support=None, handle=None, inactive=None) -> np.ndarray:
    """(n,) uint32 tint flags (1 support, 2 handle, 2|8 inactive handle) from
    boolean masks (n,) or index arrays; None: none."""
    flags = np.zeros(n, np.uint32)
    for name, m, bit in (("support_mask", support, 1), ("handle_mask", handle, 2),
                         ("inactive_mask", inactive, 2 | 8)):
        if m is None:
            continue
        a = np.asarray(m)
        if a.dtype == bool:
            if a.shape != (n,):
                raise ParameterError(name, f"boolean mask must have shape ({n},), got {a.shape}")
            a = np.nonzero(a)[0]
        a = a.astype(np.int64).reshape(-1)
        if len(a) and (a.min() < 0 or a.max() >= n):
            raise ParameterError(name, f"indices must be in 0..{n - 1}")
        flags[a] |= np.uint32(bit)
    return flags
