"""Real spherical harmonics of degree 0..3 in the 3D Gaussian Splatting convention,
and their rotation.

Basis: ``sh_basis(d)[..., k]`` for unit directions ``d``; k = 0 (band 0), 1..3
(band 1), 4..8 (band 2), 9..15 (band 3), with the constants and signs of the
reference implementation's ``utils/sh_utils.py`` (Kerbl et al. 2023, after
Sloan's "Stupid spherical harmonics tricks"): band 1 is ``(-C1 y, C1 z, -C1 x)``
(the real harmonics with the Condon-Shortley phase).  A colour is
``0.5 + sum_k sh[k] * basis[k]``.

Rotation: a function ``f(d) = c . Y(d)`` carried along by an orthogonal map Q
becomes ``f'(d) = f(Q^T d)``.  Each band l is invariant under rotations (and
reflections), so ``f'`` lies in the same span and its coefficients follow
*exactly* from a least-squares fit on sample directions: with A = Y_l at
fixed well-spread directions d_i, ``c' = pinv(A) [Y_l(Q^T d_i)] c``.  This is
the "evaluate the rotated basis at sample points and project back" method
(e.g. Sloan 2008, section on rotation; exact here because A has full column
rank); an alternative closed form is the Ivanic-Ruedenberg recurrence (J.
Phys. Chem. 100, 1996).  The tests check ``SH'(Q d) == SH(d)`` for random
directions and rotations.
"""

from __future__ import annotations

import numpy as np

C0 = 0.28209479177387814
C1 = 0.4886025119029199
C2 = (1.0925484305920792, -1.0925484305920792, 0.31539156525252005, -1.0925484305920792,
      0.5462742152960396)
C3 = (-0.5900435899266435, 2.890611442640554, -0.4570457994644658, 0.3731763325901154,
      -0.4570457994644658, 1.445305721320277, -0.5900435899266435)

#: coefficient index ranges of the bands 0..3
BAND_SLICES = (slice(0, 1), slice(1, 4), slice(4, 9), slice(9, 16))


def sh_basis(dirs: np.ndarray, degree: int = 3) -> np.ndarray:
    """Real SH basis values.

    Args:
        dirs: (..., 3) float64 unit directions.
        degree: 0..3.
    Returns:
        (..., (degree + 1)^2) float64.
    """
    d = np.asarray(dirs, dtype=np.float64)
    x, y, z = (np.ascontiguousarray(d[..., j]) for j in range(3))
    out = np.empty(((degree + 1) ** 2,) + x.shape)     # band-major rows: contiguous writes
    out[0] = C0
    if degree >= 1:
        np.multiply(-C1, y, out=out[1])
        np.multiply(C1, z, out=out[2])
        np.multiply(-C1, x, out=out[3])
    if degree >= 2:
        xx, yy, zz = x * x, y * y, z * z
        xy = x * y
        out[4] = C2[0] * xy
        out[5] = C2[1] * (y * z)
        out[6] = C2[2] * (2 * zz - xx - yy)
        out[7] = C2[3] * (x * z)
        out[8] = C2[4] * (xx - yy)
    if degree >= 3:
        t = 4 * zz - xx - yy
        out[9] = C3[0] * y * (3 * xx - yy)
        out[10] = C3[1] * xy * z
        out[11] = C3[2] * y * t
        out[12] = C3[3] * z * (2 * zz - 3 * xx - 3 * yy)
        out[13] = C3[4] * x * t
        out[14] = C3[5] * z * (xx - yy)
        out[15] = C3[6] * x * (xx - 3 * yy)
    return np.moveaxis(out, 0, -1)


def sh_colors(sh: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """Colours ``max(0.5 + SH(d), 0)`` of Gaussians seen along ``dirs``.

    Args:
        sh: (n, (d + 1)^2, 3) coefficients.
        dirs: (n, 3) or (n, m, 3) unit directions (from the camera to the Gaussian).
    Returns:
        (n, 3) or (n, m, 3) float64 RGB.
    """
    deg = int(round(np.sqrt(sh.shape[1]))) - 1
    y = sh_basis(dirs, deg)
    c = np.asarray(sh, dtype=np.float64)
    if y.ndim == 2:
        return np.maximum(np.einsum("nk,nkc->nc", y, c) + 0.5, 0.0)
    return np.maximum(np.einsum("nmk,nkc->nmc", y, c) + 0.5, 0.0)


def _sample_directions(m: int = 64) -> np.ndarray:
    """(m, 3) Fibonacci-sphere directions (well spread; A below is well conditioned)."""
    i = np.arange(m) + 0.5
    z = 1.0 - 2.0 * i / m
    r = np.sqrt(1.0 - z * z)
    phi = np.pi * (1.0 + 5 ** 0.5) * i
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


#: sample directions of the projection: 20 Fibonacci points make every band's
#: matrix well conditioned (condition numbers 1.01, 1.08, 1.40 for bands 1..3;
#: 16 points give 3.4 for band 3, 32 points cost 60 % more time for 1.14)
_DIRS = _sample_directions(20)
#: per band l = 1..3: pinv of Y_l at the sample directions, (2l + 1, m)
_PINVS = {l: np.linalg.pinv(sh_basis(_DIRS, 3)[:, BAND_SLICES[l]]) for l in (1, 2, 3)}


def sh_rotation_matrices(rotations: np.ndarray, degree: int = 3) -> list[np.ndarray]:
    """Per band l = 1..degree, the (n, 2l + 1, 2l + 1) matrices M_l with
    ``c_l' = M_l c_l`` for orthogonal maps Q (n, 3, 3): ``M_l = pinv(A_l) Y_l(Q^T d_i)``."""
    q = np.asarray(rotations, dtype=np.float64)
    back = np.matmul(_DIRS, q)                       # (n, m, 3): rows (Q^T d_i)^T = d_i^T Q
    y = sh_basis(back, degree)
    return [np.matmul(_PINVS[l], y[..., BAND_SLICES[l]]) for l in range(1, degree + 1)]


def rotate_sh(sh: np.ndarray, rotations: np.ndarray, *, chunk: int = 16384) -> np.ndarray:
    """Rotate SH coefficients of bands 1..3 by orthogonal matrices.

    Args:
        sh: (n, (d + 1)^2, 3) coefficients (any float dtype; band 0 is copied).
        rotations: (n, 3, 3) orthogonal matrices Q (the function is carried
            along: ``f'(Q d) = f(d)``).
        chunk: rows per block (bounds the temporaries).
    Returns:
        (n, (d + 1)^2, 3) float64 rotated coefficients.
    """
    c = np.asarray(sh, dtype=np.float64)
    out = c.copy()
    deg = int(round(np.sqrt(c.shape[1]))) - 1
    if deg < 1:
        return out
    q = np.asarray(rotations, dtype=np.float64)
    for s in range(0, len(c), chunk):
        mats = sh_rotation_matrices(q[s:s + chunk], deg)
        for l, m in zip(range(1, deg + 1), mats):
            band = BAND_SLICES[l]
            out[s:s + chunk, band] = np.matmul(m, c[s:s + chunk, band])
    return out
