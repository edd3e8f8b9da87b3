"""Affine 4x4 matrices for handle transforms (edit scripts, manipulator widgets).

Every function returns a fresh (4, 4) float64 matrix acting on column vectors
in homogeneous coordinates: ``x' = M[:3, :3] @ x + M[:3, 3]``.  ``compose``
multiplies left to right in *application order*: ``compose(A, B)`` first
applies ``A``, then ``B`` (i.e. it returns ``B @ A``).
"""

from __future__ import annotations

import numpy as np

from splatedit.errors import ParameterError


def _vec3(name: str, value) -> np.ndarray:
    arr = np.asarray(value, dtype=np.float64)
    if arr.shape != (3,):
        raise ParameterError(name, f"must be 3 numbers, got shape {arr.shape}")
    if not np.isfinite(arr).all():
        raise ParameterError(name, f"must be finite, got {arr.tolist()}")
    return arr


def _finite(name: str, value) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ParameterError(name, f"must be a number, got {value!r}") from None
    if not np.isfinite(x):
        raise ParameterError(name, f"must be finite, got {x}")
    return x


def identity() -> np.ndarray:
    """The (4, 4) identity."""
    return np.eye(4)


def translate(offset) -> np.ndarray:
    """Translation by ``offset`` (3,)."""
    m = np.eye(4)
    m[:3, 3] = _vec3("offset", offset)
    return m


def rotation_matrix(axis, degrees: float) -> np.ndarray:
    """(3, 3) rotation by ``degrees`` about the unit direction of ``axis``
    (right-handed, Rodrigues' formula)."""
    a = _vec3("axis", axis)
    big = float(np.abs(a).max())
    if big == 0.0:
        raise ParameterError("axis", "must be a non-zero vector")
    a = a / big     # scaled first: the norm of [1e308, 1e308, 0] or [1e-200, 0, 1e-200]
    k = a / float(np.linalg.norm(a))   # would overflow / underflow
    theta = np.deg2rad(_finite("degrees", degrees))
    kx = np.array([[0.0, -k[2], k[1]],
                   [k[2], 0.0, -k[0]],
                   [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(theta) * kx + (1.0 - np.cos(theta)) * (kx @ kx)


def rotate(axis, degrees: float, center=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Rotation by ``degrees`` about the line through ``center`` along ``axis``."""
    c = _vec3("center", center)
    r = rotation_matrix(axis, degrees)
    m = np.eye(4)
    m[:3, :3] = r
    m[:3, 3] = c - r @ c
    return m


def scale(factor: float, center=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Uniform scaling by ``factor`` (> 0) about ``center``."""
    s = _finite("factor", factor)
    if s <= 0.0:
        raise ParameterError("factor", f"must be > 0, got {s}")
    c = _vec3("center", center)
    m = np.eye(4)
    m[:3, :3] *= s
    m[:3, 3] = c - s * c
    return m


def compose(*matrices) -> np.ndarray:
    """The affine map applying ``matrices[0]`` first, then ``matrices[1]``, ...
    (returns ``matrices[-1] @ ... @ matrices[0]``; identity when empty)."""
    out = np.eye(4)
    for i, m in enumerate(matrices):
        out = as_affine(m, name=f"matrices[{i}]") @ out
    return out


def as_affine(matrix, *, name: str = "matrix") -> np.ndarray:
    """Validate a (4, 4) affine matrix (finite, last row ``0 0 0 1``) and
    return it as float64; a (3, 4) matrix gets the row appended."""
    m = np.asarray(matrix, dtype=np.float64)
    if m.shape == (3, 4):
        m = np.vstack([m, [0.0, 0.0, 0.0, 1.0]])
    if m.shape != (4, 4):
        raise ParameterError(name, f"must be a (4, 4) affine matrix, got shape {m.shape}")
    if not np.isfinite(m).all():
        raise ParameterError(name, "must be finite")
    if not np.array_equal(m[3], [0.0, 0.0, 0.0, 1.0]):
        raise ParameterError(name, f"last row must be [0, 0, 0, 1], got {m[3].tolist()}")
    return m


def apply_affine(matrix, points) -> np.ndarray:
    """Apply a (4, 4) affine matrix to (p, 3) points (or one (3,) point)."""
    m = as_affine(matrix)
    pts = np.asarray(points, dtype=np.float64)
    out = pts @ m[:3, :3].T + m[:3, 3]
    return out


def apply_linear(matrix, vectors) -> np.ndarray:
    """Apply only the linear part of a (4, 4) affine matrix to (p, 3) direction
    vectors (tangent axes; no translation)."""
    m = as_affine(matrix)
    return np.asarray(vectors, dtype=np.float64) @ m[:3, :3].T
