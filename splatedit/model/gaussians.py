"""GaussianCloud: a 3D (or 2D) Gaussian Splatting scene as plain numpy arrays.

This is the in-memory contract shared by the 3DGS reader/writer (splatedit/io),
the deformation (splatedit/deform) and the renderers (splatedit/render).
Attributes are kept in the file's own parametrisation (log scales, logit
opacities, unnormalised quaternions w-first, spherical-harmonic coefficients)
so that an unedited round trip is bit for bit; derived quantities
(covariances, opacities, unit quaternions) are computed on demand.

Spherical harmonics: ``sh[:, k, c]`` is coefficient k (k = 0 the DC term,
k = 1..3 band 1, 4..8 band 2, 9..15 band 3) of colour channel c.  The 3DGS PLY
stores ``f_dc_0..2`` (k = 0, channels RGB) and ``f_rest_*`` channel-major
(all of R's k = 1.., then G's, then B's).  Colour = 0.5 + SH(view dir), clamped
at 0 (Kerbl et al. 2023, the reference implementation's convention).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum

import numpy as np


class GaussianKind(str, Enum):
    """3DGS: three scales (ellipsoids); 2DGS: two scales (surfels, flat in the third axis)."""

    GS3D = "3dgs"
    GS2D = "2dgs"


@dataclass(eq=False)
class GaussianCloud:
    """A Gaussian splatting scene.

    Attributes:
        positions: (n, 3) float64 centres (model units; exact copies of the file's float32).
        log_scales: (n, 3) float32 for 3DGS, (n, 2) for 2DGS: natural log of the standard deviations.
        rotations: (n, 4) float32 quaternions (w, x, y, z) as stored (not necessarily unit).
        opacity_logits: (n,) float32, logit of the opacity.
        sh: (n, (d + 1)^2, 3) float32 spherical-harmonic coefficients, d = SH degree 0..3.
        normals: (n, 3) float32 or None (the optional nx ny nz, kept for the round trip).
        extra: unknown per-vertex properties kept for writing back, name -> (n,) array, file order.
        kind: 3DGS or 2DGS.
        name, source: for display and error messages.
        layout: the file's vertex properties in file order, ``(name, numpy
            dtype string)`` (e.g. ``("x", "<f4")``), or None for a scene made
            in memory; the writer keeps this order and these types so that an
            unedited round trip is bit for bit.
    """

    positions: np.ndarray
    log_scales: np.ndarray
    rotations: np.ndarray
    opacity_logits: np.ndarray
    sh: np.ndarray
    normals: np.ndarray | None = None
    extra: dict[str, np.ndarray] = field(default_factory=dict)
    kind: GaussianKind = GaussianKind.GS3D
    name: str = ""
    source: str | None = field(default=None, repr=False)
    layout: tuple[tuple[str, str], ...] | None = field(default=None, repr=False)

    def take(self, index) -> "GaussianCloud":
        """The Gaussians ``index`` ((m,) int indices or (n,) bool mask) in
        order, every per-Gaussian array included (unknown properties, the
        file layout, name and source kept: a delete or crop of a scene)."""
        idx = np.asarray(index)
        if idx.dtype == bool:
            idx = np.flatnonzero(idx)
        idx = idx.astype(np.int64)
        return GaussianCloud(positions=self.positions[idx], log_scales=self.log_scales[idx],
                             rotations=self.rotations[idx], opacity_logits=self.opacity_logits[idx],
                             sh=self.sh[idx], normals=None if self.normals is None else self.normals[idx],
                             extra={k: v[idx] for k, v in self.extra.items()}, kind=self.kind,
                             name=self.name, source=self.source, layout=self.layout)

    def __len__(self) -> int:
        return len(self.positions)

    @property
    def sh_degree(self) -> int:
        """Degree d of the spherical harmonics, from (d + 1)^2 coefficients."""
        return int(round(np.sqrt(self.sh.shape[1]))) - 1

    def unit_rotations(self, index=None) -> np.ndarray:
        """(n, 4) float64 unit quaternions (w, x, y, z); only rows ``index`` when given."""
        q = (self.rotations if index is None else self.rotations[index]).astype(np.float64)
        return q / np.linalg.norm(q, axis=1, keepdims=True)

    def rotation_matrices(self, index=None) -> np.ndarray:
        """(n, 3, 3) float64 rotation matrices of the unit quaternions; only rows ``index`` when given."""
        w, x, y, z = self.unit_rotations(index).T
        return np.stack([
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ], axis=1)

    def scales(self) -> np.ndarray:
        """(n, 3) float64 standard deviations; 2DGS gets 0 in the third axis."""
        s = np.exp(self.log_scales.astype(np.float64))
        if s.shape[1] == 2:
            s = np.concatenate([s, np.zeros((len(s), 1))], axis=1)
        return s

    def covariances(self) -> np.ndarray:
        """(n, 3, 3) float64 covariances R diag(s^2) R^T."""
        r = self.rotation_matrices()
        s2 = self.scales() ** 2
        return np.einsum("nij,nj,nkj->nik", r, s2, r)

    def opacities(self) -> np.ndarray:
        """(n,) float64 opacities in [0, 1] (sigmoid of the logits)."""
        return 1.0 / (1.0 + np.exp(-self.opacity_logits.astype(np.float64)))

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(min, max) corners of the axis-aligned bounding box of the centres."""
        return self.positions.min(axis=0), self.positions.max(axis=0)

    def dc_colors(self) -> np.ndarray:
        """(n, 3) float64 view-independent colours in [0, 1]: ``0.5 + C0 * DC``, clamped."""
        from splatedit.model.spherical_harmonics import C0
        return np.clip(0.5 + C0 * self.sh[:, 0, :].astype(np.float64), 0.0, 1.0)

    def replace(self, **changes) -> "GaussianCloud":
        """A new scene with some arrays replaced (the others are shared)."""
        import dataclasses
        return dataclasses.replace(self, **changes)

    def proxy_splats(self, sigmas: float | None = None):
        """The scene as a plain :class:`~splatedit.model.cloud.SplatCloud`: one
        elliptical disc per Gaussian, centred on it, spanned by its two largest
        axes scaled to ``sigmas`` standard deviations (default
        ``GAUSSIAN_PROXY_SIGMAS``), coloured by the DC term.  Selections, the
        selection closure and the deformation bases work on it unchanged
        (index i of the proxy is Gaussian i); it is also the lossy
        Gaussian -> splat conversion.  Axes shorter than
        ``GAUSSIAN_PROXY_MIN_AXIS_REL`` of the bounding-box diagonal (needle
        Gaussians) are lengthened to that, so the proxy is a valid cloud."""
        from splatedit.model.cloud import SplatCloud
        from splatedit.tolerances import GAUSSIAN_PROXY_MIN_AXIS_REL, GAUSSIAN_PROXY_SIGMAS
        k = GAUSSIAN_PROXY_SIGMAS if sigmas is None else float(sigmas)
        r = self.rotation_matrices()
        s = self.scales()
        order = np.argsort(-s, axis=1, kind="stable")[:, :2]            # two largest axes
        rows = np.arange(len(s))
        axes = []
        lo, hi = self.bounds()
        floor = GAUSSIAN_PROXY_MIN_AXIS_REL * max(float(np.linalg.norm(hi - lo)), 1e-300)
        for j in range(2):
            col = order[:, j]
            a = r[rows, :, col] * (k * np.maximum(s[rows, col], floor / k))[:, None]
            axes.append(a)
        colors = np.empty((len(s), 4), dtype=np.uint8)
        colors[:, :3] = np.round(self.dc_colors() * 255.0)
        colors[:, 3] = 255
        return SplatCloud(self.positions, axes[0], axes[1], colors, name=self.name,
                          source=self.source)
