"""The GPU side of both renderers works in "GPU units": model coordinates
relative to an origin (the model's box centre), divided by a power of two near
the model's size, so that float32 keeps its precision for a model of any size.
Helpers to go there from model units: the scale, the camera, the deformation
uniform block and basis rows, and the bound on how far a deformation moves a
point (near/far planes); and the per-splat selection tint flags.  Shared by
the splat and the Gaussian renderer.  Pure numpy."""

from __future__ import annotations

import numpy as np

from splatedit.errors import ParameterError
from splatedit.render.camera import Camera
# MAX_GROUPS: groups of 4 basis columns (deform.glsl), re-exported
from splatedit.render.uniforms import BASIS_GROUP, DEFORM_UBO, MAX_GROUPS  # noqa: F401

#: deform.glsl's block: dC (3 vec4 per group) and the handle rotations (4 vec4 per group)
DEFORM_UBO_BYTES = DEFORM_UBO.itemsize


def unit_scale(diagonal: float, max_radius: float) -> float:
    """The power of two nearest the model's size (its bounding-box diagonal,
    or its largest splat for a single point): dividing by it is exact, and
    it brings every model to about unit size for the float32 GPU side."""
    size = max(diagonal, max_radius)
    if not (size > 0 and np.isfinite(size)):
        return 1.0
    return float(2.0 ** round(float(np.log2(size))))


def gpu_camera(camera: Camera, origin: np.ndarray, scale: float) -> Camera:
    """``camera`` in GPU units (eye, target, near, far minus ``origin`` (3,),
    divided by ``scale``): a similarity, so the image is the same."""
    if not isinstance(camera, Camera):
        raise ParameterError("camera", f"must be a Camera, got {type(camera).__name__}")
    o, sc = origin, scale
    return Camera((camera.eye - o) / sc, (camera.target - o) / sc, up=camera.up, fov_deg=camera.fov_deg,
                  near=None if camera.near is None else camera.near / sc,
                  far=None if camera.far is None else camera.far / sc)


def displacement_bound(dC: np.ndarray, rot) -> float:
    """max_k |dC_k| (model units) plus, for a RotationDisplacement ``rot``
    (or None), each handle's arc bound: |F(s) v| <= (|sin x / x| + |(1 - cos x)
    / x|) angle |v| <= 2 angle |v| for its frame offsets v."""
    move = float(np.linalg.norm(dC, axis=1).max(initial=0.0))
    if rot is not None:
        move += max(2.0 * r.angle * float(np.linalg.norm(r.offsets, axis=1).max()) for r in rot.rotations)
    return move


def pack_deform_block(dC: np.ndarray, rot, scale: float) -> np.ndarray:
    """deform.glsl's uniform block (a :data:`~splatedit.render.uniforms.DEFORM_UBO`
    record) as (DEFORM_UBO.itemsize / 4,) float32: dC (K, 3) (model units,
    divided by ``scale``) zero-padded to 4 groups as rows dC[3g + i] =
    (dC_{4g..4g+3})[i]; per group g the rotation of handle g of ``rot`` (a
    RotationDisplacement or None): rot[4g] = (unit axis, angle; 0 = none),
    rot[4g + 1 + i] = (D_0..D_3)[i] / ``scale``."""
    pad = np.zeros((4 * MAX_GROUPS, 3))
    pad[:len(dC)] = np.asarray(dC, np.float64) / scale
    blocks = np.zeros((MAX_GROUPS, 4, 4))
    if rot is not None:
        for g in rot.rotating:
            r = rot.rotations[g]
            blocks[g, 0, :3] = r.w / r.angle
            blocks[g, 0, 3] = r.angle
            blocks[g, 1:, :] = (r.offsets / scale).T     # translation-free: no origin shift
    rec = np.zeros((), DEFORM_UBO)
    rec["dC"] = pad.reshape(MAX_GROUPS, 4, 3).transpose(0, 2, 1).reshape(3 * MAX_GROUPS, 4)
    rec["rot"] = blocks.reshape(4 * MAX_GROUPS, 4)
    return rec.reshape(1).view(np.float32)


def pack_basis_rows(mats, scale: float) -> np.ndarray:
    """Basis rows for the GPU: B, Bx, By, Bz (N, K) -> (max(N, 1), G, 4, 4)
    float32 (G :data:`~splatedit.render.uniforms.BASIS_GROUP` records per row), G = ceil(K / 4) groups of (B, Bx, By, Bz) x 4 columns, gradients
    per GPU unit (times ``scale``; B is unitless), zero-padded."""
    k = mats[0].shape[1]
    g = (k + 3) // 4
    n = len(mats[0])
    rows = np.zeros((max(n, 1), g), BASIS_GROUP)
    for name, a in zip(BASIS_GROUP.names, [mats[0]] + [m * scale for m in mats[1:]]):
        padded = np.zeros((n, 4 * g))
        padded[:, :k] = a
        rows[name][:n] = padded.reshape(n, g, 4)
    return rows.view(np.float32).reshape(max(n, 1), g, 4, 4)


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
