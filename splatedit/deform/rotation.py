"""Rotation-aware handles (issue 9): blend each handle's rotation over the support.

The paper's deformation interpolates a handle's affine map ``T_h(x) = A_h x + t_h``
linearly, p' = p + B dC, so a point half-way between the fixed band and a
handle rotated by 180 degrees moves half-way along the chord: large bends and
twists collapse the middle of a bar.  ``DeformationMode.ROTATION`` splits the
map instead:

* polar decomposition ``A_h = R_h S_h`` (rotation times symmetric stretch; a
  reflection is taken out of the stretch so that det R_h = +1), rotation vector
  ``w_h = log R_h`` (axis times angle, angle in [0, pi]: a handle turned by more
  than 180 degrees blends the short way round);
* centre ``c_h``: the point of the screw axis of the rigid part nearest the
  handle's centroid ``g_h`` (``c_h = g_h + d``, d the minimum-norm solution of
  ``(R_h - I) d = g_h - T_h(g_h)``), so a rotation about a gizmo pivot anywhere
  on that axis is a pure rotation about ``c_h`` with only a translation along
  the axis left over; or, when that axis is far enough from the support that
  its arcs stretch more, ``g_h`` itself (the handle turns about its middle and
  the translation ``(R_h - I)(pivot - g_h)`` goes through the residual, along
  the chord): :mod:`splatedit.deform.rotation_centre` measures both;
* weight field ``s_h(p)``: the sum of the handle's 4 affine-coordinate columns
  of the basis (1 on the handle, 0 on the fixed band and on other handles,
  smooth between), gradient ``grad s_h`` = the sum of its 4 Bx/By/Bz columns.
  Nothing per splat is added: the basis rows already hold both;
* the rigid part ``G_h(x) = R_h (x - c_h) + c_h`` is what the paper's linear
  mode interpolates as ``(R_h - I) v_h(p)`` with ``v_h = sum_k B_hk (C_hk - c_h)``
  (the interpolated control frame relative to the centre: ``p - c_h`` on the
  handle, 0 on the fixed band).  This mode replaces the chord ``R_h - I`` by the
  arc of the blended angle, ``F_h(s) = (R_h(s) - I) / s`` with
  ``R_h(s) = exp(s [w_h]x)`` (Rodrigues; F is smooth at s = 0, series there),
  and the RBF carries the residual map ``T_h - G_h + identity`` (stretch and
  the translation along the axis) linearly, as control-frame displacements
  ``dC_res``::

      p' = p + sum_h F_h(s_h) v_h(p) + B dC_res
      J  = I + sum_h [F_h(s_h) grad v_h + (F_h'(s_h) v_h) grad s_h^T] + J_res

  On handle h (s_h = 1, v_h = p - c_h, the other fields 0) this is exactly
  ``T_h``; on the fixed band it is the identity; to first order in the angle it
  *is* the linear mode (``F_h(s) = (R_h - I) + O(angle^2)``), so small
  rotations stay close to the paper.  A point at weight s turns by ``s`` times
  the handle's angle about ``c_h``, so a bar's cross-sections turn instead of
  shrinking (``python -m splatedit.bench.bars``).  Axes follow ``u' = J u``
  (splats stay hole-free), normals ``J^-T n``.  (Rotating ``p - c_h`` itself,
  ``R_h(s)(p - c_h)``, keeps cross-sections exactly rigid but differs from
  the linear mode at first order: 50 % of the displacement for a 10-degree
  bend of the bench bar, so it was not taken.)

Several handles: the sum above (each handle's rotation blended by its own
field; the fields of different handles add like the paper's columns do).
Control curves carry no rotation: they are displacements of picked points and
go through the linear part (their columns of ``dC_res`` are their ``dC``).
A handle whose angle is below :data:`~splatedit.tolerances.ROTATION_MIN_ANGLE`
(pure translations in particular) takes the linear path bitwise.

Small rotations: the arc differs from the chord at second order (about angle / 8
of the displacement), so the blend ramps in with the angle: a share
``phi = smoothstep(angle / ROTATION_FULL_DEGREES)`` of the rigid part goes
through the arc (its frame offsets are scaled by phi: ``phi F(s) v`` is the
same formula with ``phi v``), the rest ``(1 - phi)(R - I)(x - c)`` joins the
residual map and is interpolated linearly as in the paper.  The handle still
moves exactly by ``T_h`` (both parts are exact there); the Jacobian stays exact
(phi is constant per frame); nothing changes on the GPU.

Per frame this costs 4 vec4 uniforms per handle (w_h and the frame offsets
``C_h - c_h``) beyond the paper's dC;
the GPU pre-pass evaluates the same formula (``shaders_glsl/rotation.glsl``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import polar
from scipy.spatial.transform import Rotation

from splatedit.deform.modes import DeformationMode
from splatedit.tolerances import ROTATION_FULL_DEGREES, ROTATION_MIN_ANGLE


@dataclass(frozen=True)
class HandleRotation:
    """The rotation part of one handle's map.

    Attributes:
        w: (3,) float64 rotation vector (unit axis times angle in radians,
            angle in [0, pi]); zeros when the handle does not rotate.
        center: (3,) float64 model-space arc centre: the point of the
            rotation axis nearest the handle's centroid, or the centroid
            (:func:`~splatedit.deform.rotation_centre.choose_centre`, called by
            :func:`~splatedit.deform.rotation_centre.rotation_displacement`).
        offsets: (4, 3) float64 the handle's control frame minus ``center``
            (model units), times the arc share phi (:func:`arc_share`):
            ``v_h = B_h offsets``.
    """
    w: np.ndarray
    center: np.ndarray
    offsets: np.ndarray

    @property
    def angle(self) -> float:
        """Rotation angle in radians."""
        return float(np.linalg.norm(self.w))

    @property
    def degrees(self) -> float:
        return float(np.degrees(self.angle))


def rotation_part(matrix: np.ndarray) -> np.ndarray:
    """(3, 3) rotation R of the polar decomposition ``A = R S`` of the linear
    part of a (4, 4) affine ``matrix`` (det R = +1; a reflection stays in S)."""
    a = np.asarray(matrix, dtype=np.float64)[:3, :3]
    r, _ = polar(a)
    if np.linalg.det(r) < 0.0:       # reflection: flip the axis of the smallest singular value
        u, _, vt = np.linalg.svd(a)
        d = np.ones(3)
        d[-1] = -1.0
        r = (u * d) @ vt
    return r


def arc_share(angle: float) -> float:
    """Share phi in [0, 1] of a handle's rotation that is blended along the arc
    (the rest is interpolated linearly): smoothstep of ``angle`` (radians) over
    [0, ROTATION_FULL_DEGREES]."""
    t = min(1.0, max(0.0, float(np.degrees(angle)) / ROTATION_FULL_DEGREES))
    return t * t * (3.0 - 2.0 * t)


def screw_axis(matrix: np.ndarray, controls: np.ndarray):
    """The rotation of a handle's map and the point of its axis nearest the
    handle's centroid.

    Args:
        matrix: (4, 4) float64 affine map; controls: (4, 3) control frame.
    Returns:
        ``(r, w, pivot)``: (3, 3) polar rotation, (3,) rotation vector and
        (3,) pivot ``g + d``, d the minimum-norm solution of
        ``(R - I) d = g - T(g)``; pivot is None below ROTATION_MIN_ANGLE.
    """
    m = np.asarray(matrix, dtype=np.float64)
    g = np.asarray(controls, dtype=np.float64)[0]
    r = rotation_part(m)
    w = Rotation.from_matrix(r).as_rotvec()
    if not np.linalg.norm(w) >= ROTATION_MIN_ANGLE:
        return r, w, None
    tg = m[:3, :3] @ g + m[:3, 3]
    d = np.linalg.lstsq(r - np.eye(3), g - tg, rcond=None)[0]
    return r, w, g + d


def decompose(matrix: np.ndarray, controls: np.ndarray,
              centre: np.ndarray | None = None) -> tuple[HandleRotation, np.ndarray]:
    """Split a handle's (4, 4) affine map ``T`` into its blended rotation and
    the residual affine map ``T - G + identity`` (G the rigid rotation about
    the centre).

    Args:
        matrix: (4, 4) float64 affine map (acts on column vectors).
        controls: (4, 3) float64 the handle's control frame (row 0: its centroid).
        centre: (3,) the arc centre (model units; any point: the residual
            takes the rest of the motion).  None: the screw axis' point
            nearest the centroid (:func:`screw_axis`).
    Returns:
        (HandleRotation, residual (4, 4) float64).  Below ROTATION_MIN_ANGLE
        the rotation is zero and the residual is ``matrix`` itself.
    """
    m = np.asarray(matrix, dtype=np.float64)
    ctl = np.asarray(controls, dtype=np.float64)
    g = ctl[0]
    r, w, pivot = screw_axis(m, ctl)
    if pivot is None:
        return HandleRotation(np.zeros(3), g.copy(), ctl - g), m
    c = pivot if centre is None else np.asarray(centre, dtype=np.float64)
    phi = arc_share(float(np.linalg.norm(w)))
    lin = (1.0 - phi) * (r - np.eye(3))          # the linearly interpolated share of R - I
    res = m.copy()
    res[:3, :3] = m[:3, :3] - r + np.eye(3) + lin
    res[:3, 3] = m[:3, 3] - (c - r @ c) - lin @ c
    return HandleRotation(w, c, phi * (ctl - c)), res


@dataclass(frozen=True)
class RotationDisplacement:
    """Per-frame input of a rotation-aware deformation (what
    ``DeformationBasis.displacement(..., mode=ROTATION)`` returns and
    ``apply`` / ``displacements`` / ``jacobians`` and ``Renderer.set_displacement``
    accept in place of a plain dC).

    Attributes:
        dC: (K, 3) float64 control-frame displacements of the residual maps
            (handles) and of the curves' controls.
        rotations: one :class:`HandleRotation` per handle (handles are the
            first groups, 4 columns each).
    """
    dC: np.ndarray
    rotations: tuple[HandleRotation, ...]
    mode: DeformationMode = DeformationMode.ROTATION

    @property
    def rotating(self) -> list[int]:
        """Handles with a non-zero rotation."""
        return [i for i, r in enumerate(self.rotations) if r.w.any()]

    def any(self) -> bool:
        """Whether anything moves (like ``ndarray.any`` of a plain dC)."""
        return bool(self.rotating) or bool(np.any(self.dC))

    def tobytes(self) -> bytes:
        """The frame's contents as bytes (a cache key, like ``ndarray.tobytes``)."""
        return np.asarray(self.dC, dtype=np.float64).tobytes() + b"".join(
            np.concatenate([r.w, r.center, r.offsets.ravel()]).tobytes() for r in self.rotations)


def handle_blocks(basis) -> list[slice]:
    """Column slices of a DeformationBasis' handles (4 columns each, in order)."""
    return [basis.columns_for_group(g) for g, kind in enumerate(basis.group_kinds) if kind == "handle"]


def apply_rotation(basis, cloud, dC: np.ndarray, rot: "RotationDisplacement"):
    """Unfused reference of ``DeformationBasis.apply_arrays`` of a rotating
    frame: the linear GEMM with the residual (K, 3) ``dC``, plus the blended
    rotations at the support splats (:func:`blend_terms`, support-sized
    temporaries per handle).  Returns (positions, u, v) (n, 3) float64.
    ``apply_arrays`` itself takes the folded path of
    :mod:`splatedit.deform.rotation_apply` (5-7x faster, equal within 1e-12
    relative); this one stays as its test oracle and the bench's "before"."""
    outs = basis.apply_arrays(cloud, dC)
    idx = basis.indices
    dp, (du, dv) = blend_terms(rot, basis._pack, handle_blocks(basis), (cloud.u[idx], cloud.v[idx]))
    for o, x in zip(outs, (dp, du, dv)):
        o[idx] += x
    return outs


def split_displacement(dC) -> tuple[np.ndarray, RotationDisplacement | None]:
    """``(dC, rotation-or-None)`` of a plain (K, 3) dC or a RotationDisplacement
    (None also when no handle rotates: the linear path applies)."""
    if isinstance(dC, RotationDisplacement):
        return dC.dC, (dC if dC.rotating else None)
    return dC, None


#: below this |s angle| the arc coefficients use their Taylor series (the
#: closed forms lose digits to cancellation: (1 - cos x) / x at x = 1e-3 keeps
#: about 10 digits in float64; the series' next terms are below 1e-16 there)
_SERIES_X = 1e-3


def arc_coefficients(theta: float, s: np.ndarray):
    """Coefficients of ``F(s) = (R(s) - I) / s = a1 K + a2 K^2`` and of its
    derivative ``F'(s) = b1 K + b2 K^2`` (K = [axis]x, R(s) = exp(s theta K)).

    Args:
        theta: the angle (radians, > 0).
        s: (N,) weights.
    Returns:
        (a1, a2, b1, b2), each (N,) float64.
    """
    x = np.asarray(s, dtype=np.float64) * theta
    with np.errstate(divide="ignore", invalid="ignore"):   # x = 0 rows are replaced below
        sn, h = np.sin(x), np.sin(0.5 * x)
        omc = 2.0 * h * h                                   # 1 - cos x without cancellation
        inv = 1.0 / x
        f1 = sn * inv                                       # sin x / x
        f2 = omc * inv                                      # (1 - cos x) / x
        g1 = ((1.0 - omc) - f1) * inv                       # d/dx f1 = (x cos x - sin x) / x^2
        g2 = (sn - f2) * inv                                # d/dx f2 = (x sin x - 1 + cos x) / x^2
    series_fill(x, f1, f2, g1, g2)
    return theta * f1, theta * f2, theta * theta * g1, theta * theta * g2


def series_fill(x: np.ndarray, f1, f2, g1, g2) -> None:
    """Overwrite, where ``|x| < _SERIES_X``, the closed forms of ``sin x / x``,
    ``(1 - cos x) / x`` and their derivatives (arrays like ``x``) by their
    Taylor series (the closed forms cancel there)."""
    small = np.flatnonzero(np.abs(x) < _SERIES_X)
    if len(small):
        xs = x[small]
        x2 = xs * xs
        f1[small] = 1.0 - x2 / 6.0
        f2[small] = xs / 2.0 - xs * x2 / 24.0
        g1[small] = -xs / 3.0 + xs * x2 / 30.0
        g2[small] = 0.5 - x2 / 8.0


def _cross(k: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``k x y`` for a (3,) k and (N, 3) rows y (np.cross is slower for this shape)."""
    out = np.empty_like(y)
    out[:, 0] = k[1] * y[:, 2] - k[2] * y[:, 1]
    out[:, 1] = k[2] * y[:, 0] - k[0] * y[:, 2]
    out[:, 2] = k[0] * y[:, 1] - k[1] * y[:, 0]
    return out


def _k(k: np.ndarray, y: np.ndarray, c1: np.ndarray, c2: np.ndarray) -> np.ndarray:
    """``c1 (k x y) + c2 (k x (k x y))`` row-wise; (N, 3)."""
    ky = _cross(k, y)
    out = _cross(k, ky)
    out *= c2[:, None]
    ky *= c1[:, None]
    out += ky
    return out


def blend_terms(rot: RotationDisplacement, pack: np.ndarray, column_blocks, vectors=()):
    """The rotation terms at N support splats.

    Args:
        rot: the frame's rotations.
        pack: (N, 4, K) float64 the basis rows (B, Bx, By, Bz).
        column_blocks: per handle the slice of its 4 columns.
        vectors: (N, 3) arrays (the splat axes) to map by the rotation part of J.
    Returns:
        ``(dp, [dJ u for u in vectors])``: (N, 3) position offsets
        ``sum_h F_h(s_h) v_h`` and per vector
        ``sum_h F_h(s_h) (grad v_h u) + (F_h'(s_h) v_h) (grad s_h . u)``.
    """
    n = pack.shape[0]
    dp = np.zeros((n, 3))
    dv = [np.zeros((n, 3)) for _ in vectors]
    for h in rot.rotating:
        r = rot.rotations[h]
        sub = pack[:, :, column_blocks[h]]            # (N, 4, 4)
        b = sub[:, 0, :]
        s = b.sum(axis=1)
        v = b @ r.offsets
        theta = r.angle
        k = r.w / theta
        a1, a2, b1, b2 = arc_coefficients(theta, s)
        dp += _k(k, v, a1, a2)
        if not vectors:
            continue
        fv = _k(k, v, b1, b2)
        grad_s = sub[:, 1:, :].sum(axis=2)            # (N, 3)
        for out, u in zip(dv, vectors):
            gu = (sub[:, 1, :] * u[:, :1] + sub[:, 2, :] * u[:, 1:2] + sub[:, 3, :] * u[:, 2:]) @ r.offsets
            out += _k(k, gu, a1, a2)                                       # F(s) grad v_h u
            out += fv * (grad_s * u).sum(axis=1)[:, None]
    return dp, dv


def blend_jacobians(rot: RotationDisplacement, pack: np.ndarray, column_blocks) -> np.ndarray:
    """(N, 3, 3) rotation part of ``J - I`` (see :func:`blend_terms`)."""
    n = pack.shape[0]
    cols = []
    for j in range(3):
        e = np.zeros((n, 3))
        e[:, j] = 1.0
        cols.append(blend_terms(rot, pack, column_blocks, (e,))[1][0])
    return np.stack(cols, axis=2)
