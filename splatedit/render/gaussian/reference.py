"""Reference 3D Gaussian Splatting rasteriser in numpy (slow; small images, tests).

The standard image formation (Kerbl et al. 2023; EWA splatting, Zwicker et
al. 2001), with the camera model of :mod:`splatedit.render.camera`:

1. every centre goes to eye space; centres nearer than the near plane are culled;
2. the 3D covariance Sigma projects to the screen covariance
   Sigma2 = Jp W Sigma W^T Jp^T + GS_LOWPASS_PX2 I (W the view rotation, Jp the
   Jacobian of the perspective projection at the centre, in pixels);
3. colour = max(0.5 + SH(view direction), 0) with the direction from the eye
   to the centre (rotated by ``frames^T`` first where given: a deformed
   Gaussian evaluates its SH in its original frame);
4. Gaussians sorted by view depth, blended front to back with
   alpha = min(GS_ALPHA_MAX, opacity exp(-0.5 d^T Sigma2^-1 d)), skipped
   below GS_ALPHA_MIN, until the transmittance would fall below
   GS_MIN_TRANSMITTANCE; the background fills the rest.

Pixel (i, j) is sampled at its centre (i + 0.5, j + 0.5), row 0 at the top.
Colours are display values (no gamma), as the 3DGS reference renders them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from splatedit.errors import ParameterError
from splatedit.model.gaussians import GaussianCloud
from splatedit.model.spherical_harmonics import sh_colors   # the 3DGS convention, one numpy copy
from splatedit.render.camera import Camera
from splatedit.tolerances import (GS_ALPHA_MAX, GS_ALPHA_MIN, GS_FRUSTUM_CLAMP, GS_LOWPASS_PX2,
                                  GS_MIN_TRANSMITTANCE, GS_NEAR_CULL_REL, RENDER_BACKGROUND)

@dataclass
class Projected:
    """Screen-space Gaussians of one view (only those in front of the near plane).

    Attributes:
        index: (m,) int64 Gaussian indices, sorted front to back.
        center: (m, 2) float64 pixel coordinates of the projected centres.
        conic: (m, 3) float64 inverse screen covariance (a, b, c): d^T [[a, b], [b, c]] d.
        cov2: (m, 3) float64 screen covariance (xx, xy, yy) in pixels^2.
        depth: (m,) float64 view depth (model units, along the view axis).
        color: (m, 3) float64 RGB in display units.
        opacity: (m,) float64.
    """

    index: np.ndarray
    center: np.ndarray
    conic: np.ndarray
    cov2: np.ndarray
    depth: np.ndarray
    color: np.ndarray
    opacity: np.ndarray


def project(camera: Camera, width: int, height: int, positions, covariances, opacities, sh,
            frames=None, near: float | None = None) -> Projected:
    """Project Gaussians to the screen (steps 1-3 of the module docstring).

    Args:
        positions: (n, 3) float64 centres; covariances: (n, 3, 3) float64;
        opacities: (n,) in [0, 1]; sh: (n, (d+1)^2, 3).
        frames: optional (n, 3, 3) rotations; the SH of Gaussian i is evaluated
            at frames[i]^T (view direction).
        near: cull distance (default: the camera's clip range for the centres' box).
    """
    pos = np.asarray(positions, np.float64)
    cov = np.asarray(covariances, np.float64)
    if near is None:
        near, _ = camera.clip_range(pos.min(axis=0), pos.max(axis=0))
    view = camera.view_matrix()
    t = pos @ view[:3, :3].T + view[:3, 3]
    z = -t[:, 2]
    keep = np.nonzero(z > near * GS_NEAR_CULL_REL)[0]
    t, z = t[keep], z[keep]
    f = 1.0 / math.tan(math.radians(camera.fov_deg) / 2.0)
    fy = fx = 0.5 * f * height            # pixels per unit of x/z and y/z
    lim_x = GS_FRUSTUM_CLAMP * (0.5 * width / fx)
    lim_y = GS_FRUSTUM_CLAMP * (0.5 * height / fy)
    tx = np.clip(t[:, 0] / z, -lim_x, lim_x) * z
    ty = np.clip(t[:, 1] / z, -lim_y, lim_y) * z
    jp = np.zeros((len(keep), 2, 3))
    jp[:, 0, 0] = fx / z
    jp[:, 0, 2] = fx * tx / (z * z)
    jp[:, 1, 1] = -fy / z
    jp[:, 1, 2] = -fy * ty / (z * z)
    m = jp @ view[:3, :3]
    c2 = np.einsum("nij,njk,nlk->nil", m, cov[keep], m)
    xx = c2[:, 0, 0] + GS_LOWPASS_PX2
    xy = c2[:, 0, 1]
    yy = c2[:, 1, 1] + GS_LOWPASS_PX2
    det = xx * yy - xy * xy
    ok = det > 0
    center = np.stack([fx * t[:, 0] / z + 0.5 * width, -fy * t[:, 1] / z + 0.5 * height], axis=1)
    dirs = pos[keep] - camera.eye
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    if frames is not None:
        dirs = np.einsum("nji,nj->ni", np.asarray(frames, np.float64)[keep], dirs)
    color = sh_colors(np.asarray(sh)[keep], dirs)
    with np.errstate(divide="ignore", invalid="ignore"):
        conic = np.stack([yy / det, -xy / det, xx / det], axis=1)
    order = np.argsort(z[ok], kind="stable")
    sel = np.nonzero(ok)[0][order]
    return Projected(index=keep[sel], center=center[sel], conic=conic[sel],
                     cov2=np.stack([xx, xy, yy], axis=1)[sel], depth=z[sel], color=color[sel],
                     opacity=np.asarray(opacities, np.float64)[keep][sel])


def composite(pr: Projected, width: int, height: int, background=RENDER_BACKGROUND):
    """Front-to-back blending (step 4): returns ((height, width, 3) float64
    colour with the background composited, (height, width) transmittance)."""
    col = np.zeros((height, width, 3))
    trans = np.ones((height, width))
    done = np.zeros((height, width), bool)
    for g in range(len(pr.index)):
        op = pr.opacity[g]
        if op < GS_ALPHA_MIN:
            continue
        # alpha >= GS_ALPHA_MIN needs d^T conic d <= 2 ln(op / GS_ALPHA_MIN): the
        # bounding box of that ellipse (half-widths sqrt(q * Sigma2_xx), ...)
        q = 2.0 * math.log(op / GS_ALPHA_MIN)
        cx, cy = pr.center[g]
        hx, hy = math.sqrt(q * pr.cov2[g, 0]), math.sqrt(q * pr.cov2[g, 2])
        x0, x1 = max(int(math.floor(cx - hx)), 0), min(int(math.ceil(cx + hx)) + 1, width)
        y0, y1 = max(int(math.floor(cy - hy)), 0), min(int(math.ceil(cy + hy)) + 1, height)
        if x0 >= x1 or y0 >= y1:
            continue
        dx = np.arange(x0, x1) + 0.5 - cx
        dy = (np.arange(y0, y1) + 0.5 - cy)[:, None]
        a, b, c = pr.conic[g]
        power = -0.5 * (a * dx * dx + c * dy * dy) - b * dx * dy
        alpha = np.minimum(GS_ALPHA_MAX, op * np.exp(power))
        tt = trans[y0:y1, x0:x1]
        dd = done[y0:y1, x0:x1]
        use = (power <= 0) & (alpha >= GS_ALPHA_MIN) & ~dd
        test_t = tt * (1.0 - alpha)
        stop = use & (test_t < GS_MIN_TRANSMITTANCE)
        use &= ~stop
        dd |= stop
        w = np.where(use, alpha * tt, 0.0)
        col[y0:y1, x0:x1] += w[..., None] * pr.color[g]
        trans[y0:y1, x0:x1] = np.where(use, test_t, tt)
    col += trans[..., None] * np.asarray(background, np.float64)[:3]
    return col, trans


def render_reference(cloud: GaussianCloud, camera: Camera, width: int, height: int, *,
                     background=RENDER_BACKGROUND, positions=None, covariances=None, frames=None,
                     near: float | None = None) -> np.ndarray:
    """Render a GaussianCloud: (height, width, 4) uint8 RGBA (alpha 255).

    ``positions`` (n, 3), ``covariances`` (n, 3, 3) and ``frames`` (n, 3, 3)
    override the cloud's own (a deformed state: p + B dC, J Sigma J^T and the
    polar rotation of J).  ``near`` defaults to the camera's clip range of the
    Gaussians' centres."""
    if not isinstance(cloud, GaussianCloud):
        raise ParameterError("cloud", f"must be a GaussianCloud, got {type(cloud).__name__}")
    for name, v in (("width", width), ("height", height)):
        if not isinstance(v, (int, np.integer)) or not 1 <= v <= 1024:
            raise ParameterError(name, f"must be an integer in 1..1024 (reference rasteriser), got {v!r}")
    pos = cloud.positions if positions is None else positions
    cov = cloud.covariances() if covariances is None else covariances
    pr = project(camera, width, height, pos, cov, cloud.opacities(), cloud.sh, frames=frames, near=near)
    col, _ = composite(pr, width, height, background)
    out = np.empty((height, width, 4), np.uint8)
    out[..., :3] = np.round(np.clip(col, 0.0, 1.0) * 255.0).astype(np.uint8)
    out[..., 3] = 255
    return out
