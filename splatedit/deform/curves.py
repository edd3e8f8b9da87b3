"""Non-rigid control curves (paper Sect. 3 end, Sect. 6 end; Fig. 3 and 7).

The user picks k + 1 >= 2 points ``q_0 .. q_k`` on or near the surface and
drags them.  Two things are built from them, deliberately separately:

* the **shape** ``c(t)``, ``t in [0, 1]``: the centripetal Catmull-Rom spline
  through the picked points (Barry-Goldman pyramid, knot intervals
  ``|q_{j+1} - q_j|^(1/2)``; the end tangents come from reflected phantom
  points ``2 q_0 - q_1`` and ``2 q_k - q_{k-1}``).  It is local (segment j
  depends on ``q_{j-1} .. q_{j+2}``), C^1, and, unlike a global interpolating
  cubic, does not overshoot: a curve picked from shoulder to hand does not
  dip below its first point.  Two points give the straight segment.
* the **displacement weights** ``W(t)`` (k + 1 per t): on segment j, with
  ``s`` the fraction of the segment's knot interval, ``W_j = 1 - h(s)``,
  ``W_{j+1} = h(s)``, all others 0, where ``h(s) = 6 s^5 - 15 s^4 + 10 s^3``
  (quintic smoothstep).  They are non-negative, sum to 1 (affine), are 1 at
  their own picked point and 0 at the others, and are C^2 (h' and h'' vanish
  at the picked points).  A move ``dq`` (k + 1, 3) of the picked points
  moves the curve to ``c'(t) = c(t) + W(t) dq``: it passes through
  ``q_j + dq_j``, a common translation translates it, and dragging one
  point moves every sample in the drag direction only (never backwards,
  as the negative weights of an interpolating spline would).

Why not displace with the shape's own weights: Catmull-Rom (like any
interpolating spline) gives the far points negative weights on a middle
segment, so moving the tip up would pull part of the curve down.  A smooth
non-negative interpolating partition of unity must have zero slope at the
picked points (each weight is 1 = its maximum there and 0 = its minimum at
the neighbours), so the moved curve keeps its original tangent direction at
each picked point; that is the price of never moving backwards.

Constraint group: the controls are the **picked points** themselves (the
basis has k + 1 columns per curve and ``dC`` of a curve is ``dq``);
:meth:`ControlCurve.control_displacement` is therefore the identity (kept
for callers that convert picked-point moves).  The samples ``c(t_i)`` are
constraint points whose displacement is ``W(t_i) dq``; note that
``c(t_i) != W(t_i) q`` in general (the shape is not the weights' curve).

Sampling: ``t_i`` equally spaced in arc length of ``c``, both ends included;
``n = ceil(length / spacing) + 1`` samples by default (spacing = the cloud's
point spacing), or an explicit count.  Samples are constraint points only,
not splats; the curve need not lie on the surface.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from splatedit.errors import ParameterError
from splatedit.tolerances import CURVE_MIN_CHORD_REL

#: knot-interval exponent of the Catmull-Rom shape (0.5: centripetal, which
#: has no cusps or self-intersections within a segment; 0 uniform, 1 chordal)
CURVE_ALPHA = 0.5
#: polyline points per segment used to measure arc length
_ARC_POINTS_PER_SPAN = 64


def first_coincident_point(points) -> int | None:
    """Index j >= 1 of the first picked point that coincides with point j - 1
    (closer than CURVE_MIN_CHORD_REL of the points' extent), or None.

    Args:
        points: (k + 1, 3) picked curve points.
    """
    q = np.asarray(points, dtype=np.float64)
    chords = np.linalg.norm(np.diff(q, axis=0), axis=1)
    extent = max(float(np.ptp(q, axis=0).max()), float(np.abs(q).max()), 1e-300)
    small = np.flatnonzero(chords <= CURVE_MIN_CHORD_REL * extent)
    return int(small[0]) + 1 if len(small) else None


def _segments(tau: np.ndarray, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(tt, seg, s)``: knot values ``tt = t * tau[-1]`` of the parameters
    ``t`` (clamped into [0, 1]), their segment ``seg`` (0 .. k - 1) and the
    fraction ``s`` (0 .. 1) of that segment's knot interval."""
    tt = np.clip(np.atleast_1d(np.asarray(t, dtype=np.float64)), 0.0, 1.0) * tau[-1]
    seg = np.clip(np.searchsorted(tau, tt, side="right") - 1, 0, len(tau) - 2)
    s = (tt - tau[seg]) / (tau[seg + 1] - tau[seg])
    return tt, seg, np.clip(s, 0.0, 1.0)


def segment_index(tau: np.ndarray, t) -> np.ndarray:
    """(len(t),) the segment 0 .. k - 1 of each parameter ``t`` (clamped into
    [0, 1]) over the knots ``tau`` (k + 1,)."""
    return _segments(tau, t)[1]


def smoothstep5(s) -> np.ndarray:
    """``6 s^5 - 15 s^4 + 10 s^3``: 0 -> 1 on [0, 1] with zero first and second
    derivatives at both ends (the displacement weights' blend)."""
    s = np.asarray(s, dtype=np.float64)
    return s * s * s * (s * (6.0 * s - 15.0) + 10.0)


def displacement_weights(tau: np.ndarray, t) -> np.ndarray:
    """(len(t), k + 1) displacement weights ``W(t)`` over the knots ``tau``
    (k + 1,) of the picked points (see the module docstring): non-negative,
    rows sum to 1, ``W(t_j) = e_j``."""
    _, seg, s = _segments(tau, t)
    h = smoothstep5(s)
    w = np.zeros((len(seg), len(tau)))
    rows = np.arange(len(seg))
    w[rows, seg] = 1.0 - h
    w[rows, seg + 1] += h
    return w


def catmull_rom_weights(tau: np.ndarray, t) -> np.ndarray:
    """(len(t), k + 1) weights ``S(t)`` of the centripetal Catmull-Rom shape:
    ``c(t) = S(t) @ q`` (rows sum to 1; entries may be negative).

    ``tau`` (k + 1,) are the knots of the picked points; the phantom points
    ``2 q_0 - q_1`` and ``2 q_k - q_{k-1}`` (knot intervals copied from the
    first / last segment) are folded into the real points' weights.
    """
    k = len(tau) - 1
    tt, seg, _ = _segments(tau, t)
    # knots of the four pyramid points of each segment, phantoms included
    ext = np.concatenate([[tau[0] - (tau[1] - tau[0])], tau, [tau[-1] + (tau[-1] - tau[-2])]])
    t0, t1, t2, t3 = (ext[seg + i] for i in range(4))

    def lerp(ta, tb):  # weights (n, 2) of the two points at knots ta, tb
        f = (tt - ta) / (tb - ta)
        return np.column_stack([1.0 - f, f])

    a1, a2, a3 = lerp(t0, t1), lerp(t1, t2), lerp(t2, t3)
    b1, b2, c = lerp(t0, t2), lerp(t1, t3), lerp(t1, t2)
    # Barry-Goldman pyramid, as weights on the four points P0..P3
    n = len(tt)
    A1 = np.zeros((n, 4)); A1[:, 0:2] = a1
    A2 = np.zeros((n, 4)); A2[:, 1:3] = a2
    A3 = np.zeros((n, 4)); A3[:, 2:4] = a3
    B1 = b1[:, :1] * A1 + b1[:, 1:] * A2
    B2 = b2[:, :1] * A2 + b2[:, 1:] * A3
    p4 = c[:, :1] * B1 + c[:, 1:] * B2
    # P_i = q_{seg - 1 + i}, with the phantoms expressed in real points
    w = np.zeros((n, k + 1))
    rows = np.arange(n)
    for i in range(4):
        j = seg - 1 + i
        low, high = j < 0, j > k
        mid = ~(low | high)
        np.add.at(w, (rows[mid], j[mid]), p4[mid, i])
        np.add.at(w, (rows[low], 0), 2.0 * p4[low, i])        # 2 q_0 - q_1
        np.add.at(w, (rows[low], 1), -p4[low, i])
        np.add.at(w, (rows[high], k), 2.0 * p4[high, i])      # 2 q_k - q_{k-1}
        np.add.at(w, (rows[high], k - 1), -p4[high, i])
    return w


def _points(name: str, value) -> np.ndarray:
    try:
        q = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ParameterError(name, "must be a numeric (k + 1, 3) array") from None
    if q.ndim != 2 or q.shape[1] != 3:
        raise ParameterError(name, f"must have shape (k + 1, 3), got {q.shape}")
    if len(q) < 2:
        raise ParameterError(name, f"a curve needs at least 2 points, got {len(q)}")
    if not np.isfinite(q).all():
        bad = int(np.flatnonzero(~np.isfinite(q).all(axis=1))[0])
        raise ParameterError(name, f"point {bad} is not finite")
    return q


@dataclass(frozen=True, eq=False)
class ControlCurve:
    """A control curve through picked points (see the module docstring).

    Build with :meth:`through`.  Attributes:
        points: (k + 1, 3) picked points ``q_j`` (model units); also the
            curve group's control points.
        params: (k + 1,) parameters ``t_j`` of the picked points in [0, 1]
            (centripetal knots ``sum |q_{i+1} - q_i|^(1/2)``, normalised).
        samples: number of constraint samples, or None for one per point
            spacing of the cloud (decided when the constraints are built).
    """

    points: np.ndarray
    params: np.ndarray
    samples: int | None = None

    # ------------------------------------------------------------ building
    @classmethod
    def through(cls, points, *, samples: int | None = None) -> "ControlCurve":
        """The curve through ``points`` (k + 1, 3), k >= 1.

        Raises:
            ParameterError: fewer than 2 points, non-finite values, two
                consecutive points coinciding, ``samples`` < 2.
        """
        q = _points("points", points)
        if samples is not None:
            if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 2:
                raise ParameterError("samples", f"must be an integer >= 2 or None, got {samples!r}")
            samples = int(samples)
        j = first_coincident_point(q)
        if j is not None:
            raise ParameterError("points", f"points {j - 1} and {j} coincide; consecutive "
                                 "curve points must be distinct")
        steps = np.linalg.norm(np.diff(q, axis=0), axis=1) ** CURVE_ALPHA
        params = np.concatenate([[0.0], np.cumsum(steps)]) / steps.sum()
        params[-1] = 1.0
        return cls(points=q, params=params, samples=samples)

    # ----------------------------------------------------------- accessors
    @property
    def n_controls(self) -> int:
        """k + 1: the number of control points (= picked points = columns)."""
        return len(self.points)

    @property
    def controls(self) -> np.ndarray:
        """(k + 1, 3) the group's control points: the picked points."""
        return self.points

    def shape_weights(self, t) -> np.ndarray:
        """(len(t), k + 1) Catmull-Rom weights: ``c(t) = shape_weights(t) @ points``."""
        return catmull_rom_weights(self.params, t)

    def basis(self, t) -> np.ndarray:
        """(len(t), k + 1) displacement weights ``W(t)`` (>= 0, rows sum to 1)."""
        return displacement_weights(self.params, t)

    def evaluate(self, t, controls=None) -> np.ndarray:
        """Curve points ``c(t)`` (len(t), 3); with ``controls`` (k + 1, 3), the
        moved picked points ``q + dq``, the moved curve
        ``c'(t) = c(t) + W(t) dq`` -- exactly the targets the deformation
        gives its samples (what the editor draws)."""
        c = self.shape_weights(t) @ self.points
        if controls is None:
            return c
        return c + self.basis(t) @ (self._check_moves("controls", controls) - self.points)

    def _check_moves(self, name: str, value) -> np.ndarray:
        d = np.asarray(value, dtype=np.float64)
        if d.shape != (self.n_controls, 3):
            raise ParameterError(name, f"expected shape ({self.n_controls}, 3), got {d.shape}")
        if not np.isfinite(d).all():
            raise ParameterError(name, "must be finite")
        return d

    def control_displacement(self, point_moves) -> np.ndarray:
        """Control-point displacements (k + 1, 3) that move the picked points
        by ``point_moves`` (k + 1, 3): the same array (checked, copied), since
        the controls are the picked points."""
        return self._check_moves("point_moves", point_moves).copy()

    def length(self) -> float:
        """Arc length (polyline with 64 points per segment)."""
        _, s = self._arc_table()
        return float(s[-1])

    def _arc_table(self):
        k = self.n_controls - 1
        f = np.linspace(0.0, 1.0, _ARC_POINTS_PER_SPAN + 1)[:-1]
        p = self.params
        t = np.concatenate([p[j] + f * (p[j + 1] - p[j]) for j in range(k)] + [[1.0]])
        c = self.evaluate(t)
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(c, axis=0), axis=1))])
        return t, s

    def sample_count(self, spacing: float | None = None) -> float:
        """The number of samples :meth:`sample_parameters` would make
        (``self.samples``, else ``ceil(length / spacing) + 1``), computed without
        allocating them; a float (inf for a zero spacing) so a caller can refuse
        absurd counts first."""
        if self.samples is not None:
            return float(self.samples)
        if spacing is None or not (np.isfinite(spacing) and spacing > 0):
            return math.inf
        return max(2.0, math.ceil(self._arc_table()[1][-1] / spacing) + 1.0)

    def sample_parameters(self, spacing: float | None = None, count: int | None = None) -> np.ndarray:
        """Parameters ``t_i`` equally spaced in arc length, 0 and 1 included:
        ``count`` of them, else ``self.samples``, else
        ``ceil(length / spacing) + 1`` (at least 2)."""
        count = self.samples if count is None else count
        t_tab, s_tab = self._arc_table()
        if count is None:
            if spacing is None or not (np.isfinite(spacing) and spacing > 0):
                raise ParameterError("spacing", f"must be > 0 when no sample count is given, got {spacing}")
            count = max(2, math.ceil(s_tab[-1] / spacing) + 1)
        if count < 2:
            raise ParameterError("count", f"must be >= 2, got {count}")
        s = np.linspace(0.0, s_tab[-1], count)
        t = np.interp(s, s_tab, t_tab)
        t[0], t[-1] = 0.0, 1.0
        return t

    def sample(self, spacing: float | None = None, count: int | None = None):
        """``(t, weights, points)``: parameters (see :meth:`sample_parameters`),
        displacement weights ``W(t_i)`` (p, k + 1) and the points ``c(t_i)``
        (p, 3)."""
        t = self.sample_parameters(spacing, count)
        return t, self.basis(t), self.evaluate(t)

    def __repr__(self) -> str:
        return f"ControlCurve(points={self.n_controls}, samples={self.samples})"


def as_curve(value, name: str = "curve") -> ControlCurve:
    """A :class:`ControlCurve`, or picked points (k + 1, 3) made into one."""
    if isinstance(value, ControlCurve):
        return value
    try:
        return ControlCurve.through(value)
    except ParameterError as exc:
        raise ParameterError(name, str(exc).split(": ", 1)[-1]) from None
