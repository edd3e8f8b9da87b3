"""Frame-carrying control curves (issue 19 item 4): a curve edit that bends.

The paper's curve edit (:mod:`splatedit.deform.curves`) interpolates the
picked points' displacements linearly: dragging the tip of a curve laid
along a trunk pulls the splats next to the curve and leaves the rest of the
cross-section behind (a beak at the tip, a knob at the old end).  Curve
deformers (a curve modifier, a wire deformer) instead carry a *frame* along
the curve.  In ``DeformationMode.ROTATION`` a moved curve does that:

* the old shape ``c(t)`` is the centripetal Catmull-Rom spline through the
  picked points ``q_j``; the new shape ``c'(t)`` is the same spline (same
  knots) through the moved points ``q'_j = q_j + dq_j``, so it passes
  through them and its tangent turns with them;
* along both, a **rotation-minimising frame** (tangent, normal, binormal)
  by the double-reflection method (W. Wang, B. Jüttler, D. Zheng, Y. Liu,
  "Computation of rotation minimizing frames", ACM TOG 27(1), 2008) on a
  table of :data:`FRAME_TABLE_PER_SPAN` points per segment; the new frame
  starts from the old one turned by the smallest rotation taking the old
  start tangent to the new.  ``R(t) = F'(t) F(t)^T`` takes the old frame to
  the new one; its rotation vector ``omega(t)`` is tabulated and interpolated
  linearly (each picked point's rotation is ``R(t_j)``);
* each support splat gets a **curve parameter** ``t(p)``: its projection on
  the old curve (the nearest point of the table's polyline; past the ends 0
  or 1), and an **influence** ``s(p)`` in [0, 1]: ``smoothstep(d_f /
  max(ramp, d_c))`` of its distance d_f to the nearest splat that must not
  follow the curve (the fixed band and the handles' splats) over its
  distance d_c to the moved curve (``ramp``: the distance from there to the
  curve's first point, at least CURVE_FRAME_MIN_RAMP_SPACINGS spacings).
  Its displacement is

      D(p) = s (c'(t) - c(t)) + (exp(s [omega(t)]x) - I)(p - c(t))

  i.e. where ``s = 1`` the splat keeps its offset from the curve point
  ``c(t)`` in the moving frame (``p' = c'(t) + R(t)(p - c(t))``: a rigid
  placement, so cross-sections turn instead of shearing), and both parts
  fade out towards the fixed band (the curve's own weight fields cannot
  serve here: fitted to a line of samples, they grow far beyond 1 across a
  thick part -- up to 40 on the trunk's far side);
* the Jacobian is exact for this map (chain rule through ``s`` and ``t``;
  the derivatives of the rotation in ``s`` and ``t`` by forward differences
  of Rodrigues' formula, step :data:`_ROT_STEP`): axes follow ``u' = J u``;
* the **residual** goes through the basis: the curve's columns of ``dC``
  are solved (a (k + 1) x (k + 1) system of the basis at the picked points,
  nearly the identity) so that the whole deformation -- frame term, other
  groups' columns, rotating handles -- moves every picked point exactly to
  ``q'_j`` (up to round-off).

What does not depend on the move (projections, influence, shape weights) is
kept on the basis for its support, so a frame costs the frame table
(:class:`CurveFrame`, about 15 ms) and a few vector passes over the support
(about 60 ms for 23,000 splats on this 2-core machine under load).

A curve none of whose points moves keeps the linear path.  The linear mode
keeps the paper's curve edit unchanged.  The detail mode's base deformation
keeps the linear curve edit (not done here).

The GPU deformation pass cannot draw the frames: for code that only knows a
``dC`` (the GPU pass, a Gaussian scene's GPU preview) a
:class:`CurveFrameDisplacement` carries the paper's linear displacement of the
same moves as its ``dC``; the editor draws such a pose from a CPU-deformed
copy and ``splatedit render --edit`` deforms on the CPU, so what is shown is
what ``DeformationBasis.apply`` commits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from splatedit.deform.curves import ControlCurve, catmull_rom_weights, segment_index
from splatedit.deform.modes import DeformationMode
from splatedit.deform.rotation import HandleRotation, RotationDisplacement, blend_terms, handle_blocks
from splatedit.deform.rotation_centre import rotation_displacement
from splatedit.tolerances import CURVE_FRAME_MIN_RAMP_SPACINGS

#: frame table points per curve segment (the rotation between them is
#: interpolated linearly in its rotation vector)
FRAME_TABLE_PER_SPAN = 32
#: step of the forward differences of the rotation in s and t (error about
#: the step times the second derivative plus 1e-16 / step: about 1e-8 here)
_ROT_STEP = 1e-7
#: rows per chunk of the dense shape weights when a curve's static terms are built
_STATIC_CHUNK = 65536


# ------------------------------------------------------------------ frames
def _unit(x: np.ndarray) -> np.ndarray:
    return x / np.maximum(np.linalg.norm(x, axis=-1, keepdims=True), 1e-300)


def double_reflection(points: np.ndarray, tangents: np.ndarray, r0: np.ndarray) -> np.ndarray:
    """(n, 3) reference vectors of the rotation-minimising frame along a
    polyline (Wang et al. 2008, double reflection).

    Args:
        points: (n, 3) curve points; tangents: (n, 3) unit tangents there;
        r0: (3,) unit vector normal to ``tangents[0]`` (the first frame).
    """
    n = len(points)
    r = np.empty((n, 3))
    r[0] = r0
    v1s = np.diff(points, axis=0)
    c1s = (v1s * v1s).sum(axis=1)
    for i in range(n - 1):                 # sequential by nature; small (3,) steps
        v1, c1 = v1s[i], c1s[i]
        ri, ti = r[i], tangents[i]
        if c1 > 0.0:
            rl = ri - (2.0 / c1) * v1.dot(ri) * v1
            tl = ti - (2.0 / c1) * v1.dot(ti) * v1
        else:
            rl, tl = ri, ti
        t1 = tangents[i + 1]
        v2 = t1 - tl
        c2 = v2.dot(v2)
        rn = rl - (2.0 / c2) * v2.dot(rl) * v2 if c2 > 1e-300 else rl
        rn = rn - rn.dot(t1) * t1                                   # round-off drift
        r[i + 1] = rn / math.sqrt(rn.dot(rn))
    return r


def _align(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(3, 3) smallest rotation taking unit vector a to unit vector b."""
    axis = np.cross(a, b)
    sn, cs = float(np.linalg.norm(axis)), float(a @ b)
    if sn < 1e-12:
        if cs > 0.0:
            return np.eye(3)
        p = np.eye(3)[int(np.argmin(np.abs(a)))]
        axis = _unit(np.cross(a, p))
        return 2.0 * np.outer(axis, axis) - np.eye(3)        # half turn
    return rotvec_matrix(axis / sn * np.arctan2(sn, cs))


def rotvec_matrix(w: np.ndarray) -> np.ndarray:
    """(3, 3) rotation of rotation vector w (Rodrigues)."""
    th = float(np.linalg.norm(w))
    if th < 1e-12:
        return np.eye(3)
    k = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]]) / th
    return np.eye(3) + np.sin(th) * k + (1.0 - np.cos(th)) * (k @ k)


def rotate_rows(w: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Row-wise ``exp([w_i]x) x_i`` for (N, 3) rotation vectors and vectors
    (Rodrigues, Taylor series of its coefficients below 1e-4 radians)."""
    th = np.linalg.norm(w, axis=1)
    small = th < 1e-4
    ths = np.where(small, 1.0, th)
    a = np.where(small, 1.0 - th * th / 6.0, np.sin(ths) / ths)
    b = np.where(small, 0.5 - th * th / 24.0, (1.0 - np.cos(ths)) / (ths * ths))
    wx = _cross(w, x)
    return x + a[:, None] * wx + b[:, None] * _cross(w, wx)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of (N, 3) arrays (np.cross is 3-4x slower here)."""
    out = np.empty_like(b)
    out[:, 0] = a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1]
    out[:, 1] = a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2]
    out[:, 2] = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return out


def _tangents(curve: ControlCurve, points: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(n, 3) derivatives dc/dt of the Catmull-Rom shape through ``points``
    (knots of ``curve``) at t (central differences, one-sided at the ends)."""
    h = 1e-6
    ta, tb = np.clip(t - h, 0.0, 1.0), np.clip(t + h, 0.0, 1.0)
    return (catmull_rom_weights(curve.params, tb) - catmull_rom_weights(curve.params, ta)) @ points \
        / (tb - ta)[:, None]


@dataclass(frozen=True, eq=False)
class CurveFrame:
    """The old and new frames of one moved curve (see the module docstring).

    Attributes:
        group: the curve's group index in the basis.
        curve: the :class:`~splatedit.deform.curves.ControlCurve` (old points).
        moved: (k + 1, 3) the moved picked points ``q'``.
        table_t: (n,) table parameters, increasing, 0 .. 1.
        omega: (n, 3) rotation vectors of ``R(t)`` at the table parameters.
        omega_t: (n - 1, 3) the slope of their linear interpolation per table interval.
        table_c: (n, 3) the old curve at the table parameters; tree: their KD-tree.
    """
    group: int
    curve: ControlCurve
    moved: np.ndarray
    table_t: np.ndarray
    omega: np.ndarray
    omega_t: np.ndarray
    table_c: np.ndarray
    tree: cKDTree

    @classmethod
    def build(cls, group: int, curve: ControlCurve, moves: np.ndarray) -> "CurveFrame":
        """Frames of ``curve`` moved by ``moves`` (k + 1, 3)."""
        q, qn = curve.points, curve.points + np.asarray(moves, dtype=np.float64)
        p = curve.params
        f = np.linspace(0.0, 1.0, FRAME_TABLE_PER_SPAN + 1)[:-1]
        t = np.concatenate([p[j] + f * (p[j + 1] - p[j]) for j in range(len(p) - 1)] + [[1.0]])
        s = catmull_rom_weights(p, t)
        c, cn = s @ q, s @ qn
        tg, tgn = _unit(_tangents(curve, q, t)), _unit(_tangents(curve, qn, t))
        r0 = _unit(np.cross(tg[0], np.eye(3)[int(np.argmin(np.abs(tg[0])))]))
        r = double_reflection(c, tg, r0)
        rn = double_reflection(cn, tgn, _align(tg[0], tgn[0]) @ r0)
        old = np.stack([tg, r, np.cross(tg, r)], axis=2)          # columns: t, r, b
        new = np.stack([tgn, rn, np.cross(tgn, rn)], axis=2)
        rel = new @ old.transpose(0, 2, 1)
        omega = Rotation.from_matrix(rel).as_rotvec()
        for i in range(1, len(omega)):                              # continuous past pi
            th = np.linalg.norm(omega[i])
            if th > 0.0 and omega[i] @ omega[i - 1] < 0.0 and th > 0.5 * np.pi:
                omega[i] = omega[i] * (1.0 - 2.0 * np.pi / th)
        omega_t = np.diff(omega, axis=0) / np.diff(t)[:, None]     # slope of the interpolation
        return cls(group, curve, qn, t, omega, omega_t, c, cKDTree(c))

    @property
    def rotations(self) -> np.ndarray:
        """(k + 1, 3) rotation vectors of the picked points' frames (old to new)."""
        return self._interp(self.omega, self.curve.params)

    def _interp(self, table: np.ndarray, t: np.ndarray) -> np.ndarray:
        return np.column_stack([np.interp(t, self.table_t, table[:, i]) for i in range(3)])

    def fields(self, st: "CurveStatic"):
        """At the points of ``st``: ``(d, d_t, omega, omega_t)``, each (N, 3):
        the move ``c' - c`` and its derivative in t, the frame rotation vector
        and its derivative."""
        d, dt = st.combine(self.moved - self.curve.points)
        return d, dt, self._interp(self.omega, st.t), self.omega_t[st.seg]


# ------------------------------------------------------------ the frame
@dataclass(frozen=True)
class CurveFrameDisplacement(RotationDisplacement):
    """A rotation-mode frame with moved curves (``DeformationBasis.displacement``
    returns it).  It is a :class:`~splatedit.deform.rotation.RotationDisplacement`
    whose ``dC`` is the paper's linear displacement of the same moves (what
    code unaware of curve frames, the GPU preview, draws); ``residual`` is the
    dC the frame-carrying deformation adds (:meth:`base`), ``curves`` the
    moved curves' frames."""
    residual: np.ndarray | None = None
    curves: tuple = ()

    def base(self):
        """The residual displacement: a RotationDisplacement with the handles'
        rotations, or the plain (K, 3) residual when no handle rotates."""
        if self.rotating:
            return RotationDisplacement(self.residual, self.rotations)
        return self.residual

    def any(self) -> bool:
        return True

    def tobytes(self) -> bytes:
        return super().tobytes() + np.asarray(self.residual).tobytes() + b"".join(
            f.moved.tobytes() for f in self.curves)


def project(frame: "CurveFrame", positions: np.ndarray):
    """Curve parameters of the points nearest to ``positions`` (N, 3) on the
    old curve and their gradients: ``(t (N,), grad t (N, 3))``.  The nearest
    table point, refined on its two table segments; past the ends t is 0 or 1
    (gradient 0); inside ``grad t = c_t / (|c_t|^2 - (p - c) . c_tt)``."""
    tab_t, tab_c = frame.table_t, frame.table_c
    _, i = frame.tree.query(positions, workers=1)
    best_t = tab_t[i].copy()
    best_d = np.full(len(positions), np.inf)
    grad = np.zeros_like(positions)
    for lo in (np.maximum(i - 1, 0), i):
        hi = np.minimum(lo + 1, len(tab_t) - 1)
        a, e = tab_c[lo], tab_c[hi] - tab_c[lo]
        ee = np.maximum((e * e).sum(1), 1e-300)
        f = np.clip(((positions - a) * e).sum(1) / ee, 0.0, 1.0)
        dist = np.linalg.norm(a + f[:, None] * e - positions, axis=1)
        better = dist < best_d
        best_d[better] = dist[better]
        best_t[better] = (tab_t[lo] + f * (tab_t[hi] - tab_t[lo]))[better]
        slope = ((tab_t[hi] - tab_t[lo]) * ((f > 0.0) & (f < 1.0)) / ee)[:, None] * e
        grad[better] = slope[better]
    return best_t, grad


@dataclass(frozen=True, eq=False)
class CurveStatic:
    """What a curve's frame terms need at N points that does not depend on
    the move: the projection ``t`` (N,) and its gradient (N, 3), the old
    curve point ``c`` and derivative ``c_t`` (N, 3), the shape weights in a
    window of m = min(4, k + 1) consecutive picked points (a Catmull-Rom
    segment depends on at most 4): ``first`` (N,) the window's first point,
    ``shape`` and their t-derivative ``shape_t`` (N, m) (``c' - c =
    sum_i shape[:, i] dq[first + i]``; 8 m bytes per point each instead of
    8 (k + 1)), and the frame table interval ``seg`` (N,) of each t."""
    t: np.ndarray
    grad_t: np.ndarray
    c: np.ndarray
    c_t: np.ndarray
    first: np.ndarray
    shape: np.ndarray
    shape_t: np.ndarray
    seg: np.ndarray

    @classmethod
    def at(cls, frame: CurveFrame, positions: np.ndarray) -> "CurveStatic":
        t, gt = project(frame, positions)
        cv = frame.curve
        k = cv.n_controls - 1
        m = min(4, k + 1)
        n = len(t)
        span = segment_index(cv.params, t)
        first = np.clip(span - 1, 0, k + 1 - m)
        cols = first[:, None] + np.arange(m)
        shape, shape_t = np.empty((n, m)), np.empty((n, m))
        h = 1e-6
        for a in range(0, n, _STATIC_CHUNK):          # the dense (rows, k + 1) weights per chunk
            b = min(n, a + _STATIC_CHUNK)
            tc = t[a:b]
            ta, tb = np.clip(tc - h, 0.0, 1.0), np.clip(tc + h, 0.0, 1.0)
            w = catmull_rom_weights(cv.params, tc)
            wt = (catmull_rom_weights(cv.params, tb) - catmull_rom_weights(cv.params, ta)) / (tb - ta)[:, None]
            shape[a:b] = np.take_along_axis(w, cols[a:b], axis=1)
            shape_t[a:b] = np.take_along_axis(wt, cols[a:b], axis=1)
        pts = cv.points[cols]                           # (N, m, 3)
        c = np.einsum("nm,nmk->nk", shape, pts)
        ct = np.einsum("nm,nmk->nk", shape_t, pts)
        seg = np.clip(np.searchsorted(frame.table_t, t, side="right") - 1, 0, len(frame.table_t) - 2)
        return cls(t, gt, c, ct, first, shape, shape_t, seg)

    def combine(self, dq: np.ndarray):
        """``(shape @ dq, shape_t @ dq)`` (N, 3) each for moves dq (k + 1, 3)."""
        d = dq[self.first[:, None] + np.arange(self.shape.shape[1])]     # (N, m, 3)
        return np.einsum("nm,nmk->nk", self.shape, d), np.einsum("nm,nmk->nk", self.shape_t, d)


def frame_terms(frame: CurveFrame, influence, st: CurveStatic, positions: np.ndarray, vectors=()):
    """Displacement ``D`` of one moved curve at N points and ``(J_D) u`` of
    each (N, 3) array ``u`` in ``vectors``.

    Args:
        frame: the curve's frames.
        influence: ``(s (N,), grad s (N, 3))`` the fade towards the fixed band.
        st: the curve's :class:`CurveStatic` at the points.
        positions: (N, 3) the points (model units).
    Returns:
        ``(D (N, 3), [J_D u ...])``.
    """
    s, gs = influence
    c, ct, gt = st.c, st.c_t, st.grad_t
    d, dt, om, om_t = frame.fields(st)
    o = positions - c
    w = s[:, None] * om
    eo = rotate_rows(w, o)
    disp = s[:, None] * d + (eo - o)
    if not vectors:
        return disp, []
    h = _ROT_STEP
    a_s = (rotate_rows(w + h * om, o) - eo) / h                      # d(E o)/ds
    a_t = (rotate_rows(w + (h * s)[:, None] * om_t, o) - eo) / h     # d(E o)/dt
    out = []
    for u in vectors:
        su = (gs * u).sum(axis=1)[:, None]
        tu = (gt * u).sum(axis=1)[:, None]
        x = u - ct * tu                                     # d o / dx applied to u
        out.append(d * su + s[:, None] * dt * tu + (rotate_rows(w, x) - x) + a_s * su + a_t * tu)
    return disp, out


def influence(basis, frames, positions: np.ndarray):
    """``(s (N,), grad s (N, 3))``: how much of the curves' frame motion the
    points take: ``smoothstep(d_f / max(ramp, d_c))`` of their distance d_f
    to the nearest splat that does not follow the curves (the fixed band and
    the handles' splats, which move by their own maps) and d_c to the nearest
    moved curve (so a part of the support far from the curve, nearer to the
    fixed part, takes less of it); ``ramp`` is the distance from there to the
    nearest first picked point of the moved curves, at least
    CURVE_FRAME_MIN_RAMP_SPACINGS point spacings.  1 with neither."""
    n = len(positions)
    tree = basis.still_tree()
    if tree is None:
        return np.ones(n), np.zeros((n, 3))
    q0 = np.array([f.curve.points[0] for f in frames])
    ramp = max(float(tree.query(q0)[0].min()), CURVE_FRAME_MIN_RAMP_SPACINGS * basis.constraints.spacing)
    dist, j = tree.query(positions, workers=1)
    gd = (positions - tree.data[j]) / np.maximum(dist, 1e-300)[:, None]
    dc = np.full(n, np.inf)
    gc = np.zeros((n, 3))
    for f in frames:
        d, k = f.tree.query(positions, workers=1)
        better = d < dc
        dc[better] = d[better]
        gc[better] = ((positions - f.table_c[k]) / np.maximum(d, 1e-300)[:, None])[better]
    far = dc > ramp
    den = np.where(far, dc, ramp)
    x = dist / den
    gx = gd / den[:, None] - np.where(far, x / den, 0.0)[:, None] * gc
    inside = (x > 0.0) & (x < 1.0)
    x = np.clip(x, 0.0, 1.0)
    s = x * x * (3.0 - 2.0 * x)
    return s, np.where(inside, 6.0 * x * (1.0 - x), 0.0)[:, None] * gx


def frames_terms(disp: CurveFrameDisplacement, basis, positions: np.ndarray, vectors=()):
    """Sum of :func:`frame_terms` over the moved curves of ``disp``."""
    total = np.zeros_like(positions)
    outs = [np.zeros_like(positions) for _ in vectors]
    if not disp.curves:
        return total, outs
    # what does not depend on the move is kept on the basis for its support's positions
    cache = basis.frame_cache if positions is basis.support_positions else None
    groups = tuple(f.group for f in disp.curves)
    inf = None if cache is None else cache.get(("influence", groups))
    if inf is None:
        inf = influence(basis, disp.curves, positions)
        if cache is not None:
            cache[("influence", groups)] = inf
    for f in disp.curves:
        st = None if cache is None else cache.get(("static", f.group))
        if st is None:
            st = CurveStatic.at(f, positions)
            if cache is not None:
                cache[("static", f.group)] = st
        dp, dv = frame_terms(f, inf, st, positions, vectors)
        total += dp
        for o, x in zip(outs, dv):
            o += x
    return total, outs


def _pack_at(basis, points: np.ndarray) -> np.ndarray:
    """(P, 4, K) basis rows (B, Bx, By, Bz) evaluated by the RBF at points."""
    val, grad = basis.rbf.value_and_gradient(points)
    pack = np.empty((len(points), 4, val.shape[1]))
    pack[:, 0, :] = val
    pack[:, 1:, :] = grad.transpose(0, 2, 1)
    return pack


def deform_points(basis, dC, points) -> np.ndarray:
    """(P, 3) the deformation of ``dC`` (any form ``displacement`` returns) at
    points of the free region that need not be splats (the basis rows by the
    RBF there); the check that picked points land."""
    x = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    pack = _pack_at(basis, x)
    frames = dC if isinstance(dC, CurveFrameDisplacement) else None
    d = dC.base() if frames is not None else dC
    if isinstance(d, RotationDisplacement):
        out = x + pack[:, 0, :] @ d.dC
        if d.rotating:
            out += blend_terms(d, pack, handle_blocks(basis))[0]
    else:
        out = x + pack[:, 0, :] @ np.asarray(d, dtype=np.float64)
    if frames is not None:
        out += frames_terms(frames, basis, x)[0]
    return out


def curve_frame_displacement(basis, transforms: list):
    """``DeformationBasis.displacement(transforms, mode=ROTATION)`` with control
    curves: the handles as :func:`~splatedit.deform.rotation_centre.rotation_displacement`
    does; each curve whose points move gets its :class:`CurveFrame` and its
    columns of the residual are solved so that every moved curve's picked
    points land on their targets.  Returns what ``rotation_displacement``
    returns when no curve moves, else a :class:`CurveFrameDisplacement`."""
    linear = rotation_displacement(basis, transforms)
    frames = []
    for g, (t, grp) in enumerate(zip(transforms, basis.constraints.groups)):
        if grp.kind == "curve" and t is not None and np.any(t):
            frames.append(CurveFrame.build(g, grp.curve, np.asarray(t, dtype=np.float64)))
    if not frames:
        return linear
    rot = linear if isinstance(linear, RotationDisplacement) else None
    dc_lin = rot.dC if rot is not None else linear
    res = dc_lin.copy()
    cols = np.concatenate([np.arange(basis.n_columns)[basis.columns_for_group(f.group)] for f in frames])
    res[cols] = 0.0
    q = np.concatenate([f.curve.points for f in frames])
    target = np.concatenate([f.moved - f.curve.points for f in frames])
    probe = CurveFrameDisplacement(dC=dc_lin, rotations=() if rot is None else rot.rotations,
                                   residual=res, curves=tuple(frames))
    got = deform_points(basis, probe, q) - q
    bq = _pack_at(basis, q)[:, 0, :][:, cols]                # (P, P), nearly the identity
    res[cols] = np.linalg.lstsq(bq, target - got, rcond=None)[0]
    return CurveFrameDisplacement(dC=dc_lin, rotations=probe.rotations, residual=res, curves=tuple(frames))
