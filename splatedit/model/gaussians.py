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

    def __len__(self) -> int:
        return len(self.positions)

    @property
    def sh_degree(self) -> int:
        """Degree d of the spherical harmonics, from (d + 1)^2 coefficients."""
        return int(round(np.sqrt(self.sh.shape[1]))) - 1

    def unit_rotations(self) -> np.ndarray:
        """(n, 4) float64 unit quaternions (w, x, y, z)."""
        q = self.rotations.astype(np.float64)
        return q / np.linalg.norm(q, axis=1, keepdims=True)

    def rotation_matrices(self) -> np.ndarray:
        """(n, 3, 3) float64 rotation matrices of the unit quaternions."""
        w, x, y, z = self.unit_rotations().T
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
