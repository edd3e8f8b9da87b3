"""Non-rigid control curves (paper Sect. 3 end, Sect. 6 end; Fig. 3 and 7).

The user picks k + 1 >= 2 points ``q_0 .. q_k`` on or near the surface.  An
interpolating B-spline ``c(t) = sum_j b_j N_j(t)``, ``t in [0, 1]``, is built
through them; moving its control points ``b_j`` gives ``c'(t)``.  A dense
sampling ``c(t_i)`` gives displacement constraints whose values are affine
combinations of the control-point displacements, so the precomputed basis has
k + 1 columns per curve and every frame is still ``p' = p + B dC``.

Construction (decisions):

* **Degree** ``p = min(3, k)``: cubic from 4 points on, quadratic through 3
  points, a straight segment through 2.
* **Parameters** ``tbar_j``: chord length (cumulative distance between
  consecutive picked points, scaled to [0, 1]).  Consecutive picked points
  must be distinct.
* **Knots**: clamped (``p + 1`` zeros and ones) with the interior knots the
  averages of ``p`` consecutive parameters (de Boor's averaging), which makes
  the interpolation matrix ``A[i, j] = N_j(tbar_i)`` square (k + 1 control
  points for k + 1 picked points), banded and non-singular (Schoenberg-
  Whitney).  For ``p = k`` this is the Bezier curve through the points.
* **Control points** ``b = A^-1 q``.  The B-spline basis is a partition of
  unity, so every row of ``A``, of ``A^-1`` and of the sample weights
  ``N(t_i)`` sums to 1: samples are affine combinations of the control points
  (weights ``N(t_i)`` >= 0) and also of the picked points
  (``W = N(t_i) A^-1``).
* **What moves**: the constraint group's controls are the B-spline control
  points ``b_j`` (the paper's "moving its spline control points"; what the
  editor drags).  Edit scripts move the *picked* points instead (friendlier:
  the curve then passes through the moved points); :meth:`ControlCurve.
  control_displacement` converts picked-point moves ``dq`` into control-point
  moves ``db = A^-1 dq`` -- the same deformation either way.
* **Sampling**: ``t_i`` equally spaced in arc length, both ends included;
  ``n = ceil(length / spacing) + 1`` samples by default (spacing = the cloud's
  point spacing), or an explicit count.  Samples are constraint points only,
  not splats; the curve need not lie on the surface.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from splatedit.errors import ParameterError
from splatedit.tolerances import CURVE_MIN_CHORD_REL

#: highest spline degree (cubic)
CURVE_DEGREE = 3
#: polyline points per knot span used to measure arc length
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


def bspline_basis(t, knots, degree: int) -> np.ndarray:
    """(len(t), len(knots) - degree - 1) values ``N_j^degree(t)`` of the
    B-splines over ``knots`` (Cox-de Boor recursion, 0/0 := 0).

    ``t`` outside [knots[degree], knots[-degree-1]] is clamped into the last
    (or first) non-empty knot span, so ``t = 1`` of a clamped vector gives the
    last basis function 1.
    """
    u = np.asarray(knots, dtype=np.float64)
    tt = np.atleast_1d(np.asarray(t, dtype=np.float64))
    n_span = len(u) - 1
    nonempty = np.flatnonzero(u[1:] > u[:-1])
    if len(nonempty) == 0:
        raise ParameterError("knots", "all knots coincide")
    span = np.searchsorted(u, tt, side="right") - 1
    span = np.clip(span, nonempty[0], nonempty[-1])
    n = np.zeros((len(tt), n_span))
    n[np.arange(len(tt)), span] = 1.0
    for d in range(1, degree + 1):
        nxt = np.zeros((len(tt), n_span - d))
        for j in range(n_span - d):
            left = u[j + d] - u[j]
            right = u[j + d + 1] - u[j + 1]
            if left > 0.0:
                nxt[:, j] += (tt - u[j]) / left * n[:, j]
            if right > 0.0:
                nxt[:, j] += (u[j + d + 1] - tt) / right * n[:, j + 1]
        n = nxt
    return n


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
    """An interpolating B-spline through picked points (see module docstring).

    Build with :meth:`through`.  Attributes:
        points: (k + 1, 3) picked (interpolation) points ``q_j``.
        degree: ``min(3, k)``.
        params: (k + 1,) chord-length parameters ``tbar_j`` (0 .. 1).
        knots: (k + degree + 2,) clamped knot vector.
        controls: (k + 1, 3) B-spline control points ``b_j``.
        interpolation: (k + 1, k + 1) ``A[i, j] = N_j(tbar_i)``.
        samples: number of constraint samples, or None for one per point
            spacing of the cloud (decided when the constraints are built).
    """

    points: np.ndarray
    degree: int
    params: np.ndarray
    knots: np.ndarray
    controls: np.ndarray
    interpolation: np.ndarray
    samples: int | None = None
    _inverse: np.ndarray = field(default=None, repr=False)

    # ------------------------------------------------------------ building
    @classmethod
    def through(cls, points, *, samples: int | None = None) -> "ControlCurve":
        """The interpolating spline through ``points`` (k + 1, 3), k >= 1.

        Raises:
            ParameterError: fewer than 2 points, non-finite values, two
                consecutive points coinciding, ``samples`` < 2.
        """
        q = _points("points", points)
        if samples is not None:
            if isinstance(samples, bool) or not isinstance(samples, (int, np.integer)) or samples < 2:
                raise ParameterError("samples", f"must be an integer >= 2 or None, got {samples!r}")
            samples = int(samples)
        k = len(q) - 1
        j = first_coincident_point(q)
        if j is not None:
            raise ParameterError("points", f"points {j - 1} and {j} coincide; consecutive "
                                 "curve points must be distinct")
        chords = np.linalg.norm(np.diff(q, axis=0), axis=1)
        params = np.concatenate([[0.0], np.cumsum(chords)]) / chords.sum()
        params[-1] = 1.0
        p = min(CURVE_DEGREE, k)
        interior = [params[j:j + p].mean() for j in range(1, k - p + 1)]
        knots = np.concatenate([np.zeros(p + 1), interior, np.ones(p + 1)])
        a = bspline_basis(params, knots, p)
        inv = np.linalg.inv(a)
        controls = inv @ q
        return cls(points=q, degree=p, params=params, knots=knots, controls=controls,
                   interpolation=a, samples=samples, _inverse=inv)

    # ----------------------------------------------------------- accessors
    @property
    def n_controls(self) -> int:
        """k + 1: the number of control points (= picked points = columns)."""
        return len(self.controls)

    def basis(self, t) -> np.ndarray:
        """(len(t), k + 1) B-spline weights ``N_j(t)``; rows sum to 1."""
        return bspline_basis(t, self.knots, self.degree)

    def evaluate(self, t, controls=None) -> np.ndarray:
        """Curve points ``c(t)`` (len(t), 3); with ``controls`` (k + 1, 3) the
        moved curve ``c'(t)`` (e.g. ``curve.controls + db``)."""
        b = self.controls if controls is None else self._check_moves("controls", controls)
        return self.basis(t) @ b

    def _check_moves(self, name: str, value) -> np.ndarray:
        d = np.asarray(value, dtype=np.float64)
        if d.shape != (self.n_controls, 3):
            raise ParameterError(name, f"expected shape ({self.n_controls}, 3), got {d.shape}")
        if not np.isfinite(d).all():
            raise ParameterError(name, "must be finite")
        return d

    def control_displacement(self, point_moves) -> np.ndarray:
        """Control-point displacements ``db = A^-1 dq`` (k + 1, 3) that move the
        picked points by ``point_moves`` ``dq`` (k + 1, 3)."""
        return self._inverse @ self._check_moves("point_moves", point_moves)

    def length(self) -> float:
        """Arc length (polyline with 64 points per knot span)."""
        _, s = self._arc_table()
        return float(s[-1])

    def _arc_table(self):
        spans = max(1, len(self.knots) - 2 * self.degree - 1)
        t = np.linspace(0.0, 1.0, spans * _ARC_POINTS_PER_SPAN + 1)
        c = self.evaluate(t)
        s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(c, axis=0), axis=1))])
        return t, s

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
        weights ``N(t_i)`` (p, k + 1) and points ``weights @ controls`` (p, 3)."""
        t = self.sample_parameters(spacing, count)
        w = self.basis(t)
        return t, w, w @ self.controls

    def __repr__(self) -> str:
        return (f"ControlCurve(points={self.n_controls}, degree={self.degree}, "
                f"samples={self.samples})")


def as_curve(value, name: str = "curve") -> ControlCurve:
    """A :class:`ControlCurve`, or picked points (k + 1, 3) made into one."""
    if isinstance(value, ControlCurve):
        return value
    try:
        return ControlCurve.through(value)
    except ParameterError as exc:
        raise ParameterError(name, str(exc).split(": ", 1)[-1]) from None
