"""Where a rotation-aware handle turns: about its pivot, or about itself.

The rotation mode (:mod:`splatedit.deform.rotation`) blends a handle's
rotation along arcs about a centre c on the rotation's axis; any c gives the
same handle motion (the residual map carries the translation
``(R - I)(c_pivot - c)`` linearly, as the paper does).  Two centres matter:

* the **pivot** centre, the axis point nearest the handle's centroid g: a
  splat at weight s turns by s times the angle about the axis.  Right when
  the support hinges about the axis (a bar bent about its base, a handle
  turned about itself);
* the **handle** centre, g itself: the handle's motion is split into a turn
  about an axis through the handle plus a translation, and the translation is
  interpolated along the straight chord.  Right when the axis is far from the
  support: an arc of radius D about a far axis is ``angle / (2 sin(angle /
  2))`` times longer than its chord (1.21x at 120 degrees, 1.57x at 180),
  and the transition between the fixed band and the handle has to absorb the
  whole arc: the pivot centre stretches those splats by that factor more than
  the linear mode (99th percentile, pivots 8 handle radii away on the bunny,
  the kitten and the hippo: ``python -m splatedit.bench.stretch``) and tears
  1.5-6.5x as many neighbours.

Which one a handle takes is measured, not guessed: the splat stretch of both
at up to ROTATION_PROBE_SPLATS free support splats (:class:`StretchProbe`,
sampled once at fit time) under a rigid turn by :data:`~splatedit.tolerances.ROTATION_PROBE_DEGREES`
about the frame's axis; the handle centre wins when it stretches less.  The
choice depends on the axis line only, not on the angle, so dragging a
rotation about a fixed pivot never jumps between the two; it is cached per
axis line.  A line that moves during a drag (grabbing a turned handle moves
its screw axis) passes smoothly from one to the other: near equal scores
give a centre between them.  The GPU evaluates the same formula with the chosen centre (the
centre only enters the per-frame uniforms).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from splatedit.deform.rotation import (HandleRotation, RotationDisplacement, blend_terms, decompose, handle_blocks,
                                       screw_axis)
from splatedit.deform.transform import as_affine, rotate
from splatedit.tolerances import (ROTATION_PROBE_BLEND, ROTATION_PROBE_DEGREES, ROTATION_PROBE_PERCENTILE,
                                  ROTATION_PROBE_SPLATS)

#: cached choices per basis (axis lines rounded to this many significant
#: digits relative to the handle's radius; a drag keeps the same line)
_KEY_DIGITS = 9
_CACHE_SIZE = 64


@dataclass(frozen=True)
class StretchProbe:
    """Support splats at which candidate centres are compared.

    Attributes:
        pack: (m, 4, K) float64 their basis rows (B, Bx, By, Bz).
        u, v: (m, 3) float64 their tangent axes (model units).
        wu, wv: (m, K) float64 ``u_x Bx + u_y By + u_z Bz`` (likewise v):
            the axes' linear-mode change per unit dC.
    """
    pack: np.ndarray
    u: np.ndarray
    v: np.ndarray
    wu: np.ndarray
    wv: np.ndarray

    @classmethod
    def sample(cls, pack: np.ndarray, rows: np.ndarray, u: np.ndarray, v: np.ndarray,
               count: int = ROTATION_PROBE_SPLATS) -> "StretchProbe":
        """At most ``count`` of ``rows`` (basis rows, evenly strided), with
        their axes ``u``, ``v`` ((len(rows), 3) float64)."""
        step = max(1, -(-len(rows) // max(1, count)))
        sel = np.arange(0, len(rows), step)
        pk = np.ascontiguousarray(pack[rows[sel]])
        uu, vv = np.array(u[sel], dtype=np.float64), np.array(v[sel], dtype=np.float64)
        return cls(pk, uu, vv, np.einsum("nj,njk->nk", uu, pk[:, 1:, :]),
                   np.einsum("nj,njk->nk", vv, pk[:, 1:, :]))

    def stretch(self, rot, blocks) -> float:
        """ROTATION_PROBE_PERCENTILE-th percentile of the splat stretch
        ``max(|u'|/|u|, |u|/|u'|, |v'|/|v|, |v|/|v'|)`` over the probe
        splats under ``rot`` (a RotationDisplacement: residual dC and blended
        rotations; ``blocks`` the handles' column slices)."""
        dc = rot.dC
        _, (du, dv) = blend_terms(rot, self.pack, blocks, (self.u, self.v))
        rs = []
        for a, w, d in ((self.u, self.wu, du), (self.v, self.wv, dv)):
            r = np.linalg.norm(a + w @ dc + d, axis=1) / np.linalg.norm(a, axis=1)
            with np.errstate(divide="ignore"):
                rs.append(np.maximum(r, 1.0 / r))
        return float(np.percentile(np.maximum(*rs), ROTATION_PROBE_PERCENTILE))


def _key(handle: int, axis: np.ndarray, centre: np.ndarray, radius: float) -> tuple:
    scale = 10.0 ** _KEY_DIGITS
    return (handle, tuple(np.round(axis * scale).astype(np.int64)),
            tuple(np.round(centre / radius * scale).astype(np.int64)))


def choose_centre(basis, handle: int, axis: np.ndarray, pivot: np.ndarray) -> np.ndarray:
    """The arc centre of handle ``handle`` of ``basis`` turning about the
    line through ``pivot`` (3,) (its point nearest the handle's centroid)
    along the unit ``axis`` (3,): ``pivot`` or the handle's centroid, the
    one whose rigid turn by ROTATION_PROBE_DEGREES stretches the probe's
    splats less (:meth:`StretchProbe.stretch`), or a point between them
    while the two stretch within ROTATION_PROBE_BLEND of each other.  The probe
    turns the way ``axis`` points (bending a part forwards and backwards
    differ); a rotation vector's axis flips where the angle passes 180
    degrees, where the blend itself flips to the short way round.  Without a
    probe (a basis not built by ``fit``): ``pivot``."""
    probe = getattr(basis, "stretch_probe", None)
    ctl = basis.constraints.groups[handle].controls
    g = ctl[0]
    radius = float(np.linalg.norm(ctl[1] - ctl[0]))
    if probe is None or not np.linalg.norm(pivot - g) > 0.0:
        return pivot
    axis = np.asarray(axis, dtype=np.float64)
    cache = basis.__dict__.setdefault("_rotation_centres", {})
    key = _key(handle, axis, pivot, radius)
    if key in cache:
        return cache[key]
    blocks = handle_blocks(basis)
    still = HandleRotation(np.zeros(3), g.copy(), np.zeros((4, 3)))
    scores = []
    m = rotate(axis, ROTATION_PROBE_DEGREES, pivot)
    for c in (pivot, g):
        rot, res = decompose(m, ctl, centre=c)
        inputs = [None] * basis.n_groups
        inputs[handle] = res
        rotations = tuple(rot if j == handle else still for j in range(len(blocks)))
        scores.append(probe.stretch(RotationDisplacement(basis.displacement(inputs), rotations), blocks))
    # smooth switch: the two deformations blend (the result is affine in the
    # centre) while the scores are within ROTATION_PROBE_BLEND of each other,
    # so a pivot line that moves during a drag (a grab after a turn) never
    # makes the surface jump
    ratio = scores[1] / scores[0] if np.isfinite(scores).all() else np.inf    # a degenerate probe: the pivot
    t = min(1.0, max(0.0, (ratio - 1.0 + ROTATION_PROBE_BLEND) / (2.0 * ROTATION_PROBE_BLEND)))
    share = t * t * (3.0 - 2.0 * t)                  # of the pivot
    best = pivot if share == 1.0 else g + share * (pivot - g)
    if len(cache) >= _CACHE_SIZE:
        cache.clear()
    cache[key] = best
    return best


def rotation_displacement(basis, transforms: list):
    """``DeformationBasis.displacement(transforms, mode=ROTATION)``: each
    handle's (4, 4) map (None: identity) decomposed about the centre
    :func:`choose_centre` picks, the
    residual maps (and the curves' inputs) through the linear ``displacement``.  Returns a
    RotationDisplacement, or the plain (K, 3) dC when no handle rotates (then
    bitwise the linear mode's)."""
    rotations, inputs = [], []
    for i, (t, kind) in enumerate(zip(transforms, basis.group_kinds)):
        if kind == "handle":
            m = np.eye(4) if t is None else as_affine(t, name=f"transforms[{i}]")
            ctl = basis.constraints.groups[i].controls
            _, w, pivot = screw_axis(m, ctl)
            centre = None if pivot is None else choose_centre(basis, i, w / np.linalg.norm(w), pivot)
            rot, res = decompose(m, ctl, centre)
            rotations.append(rot)
            t = None if t is None else res
        inputs.append(t)
    dc = basis.displacement(inputs)
    if any(r.w.any() for r in rotations):
        return RotationDisplacement(dc, tuple(rotations))
    return dc
