"""Displacement constraints of the modeling metaphor (paper Sect. 3, 4 and 6).

The user partitions the cloud into

* the *support* (the splats the edit may move),
* inside it one or more disjoint *handles* (moved by an affine map each),
* the *free* region = support minus handles (moved by the RBF), and
* everything else, *fixed*.

The RBF displacement field is constrained on two kinds of bands, each
``rings * spacing`` thick (``BAND_RINGS`` = 3: a finite-difference C^2
boundary condition, "three rings of vertices" in the paper):

* the **fixed band**: splats *outside* the support whose distance to the
  nearest support splat is at most ``rings * spacing``; displacement 0;
* the **handle band** of every handle: handle splats whose distance to the
  nearest free splat is at most ``rings * spacing``.  Its displacement is
  ``M dC`` where ``M`` are the affine coordinates of the splats w.r.t. the
  handle's control frame ``C`` (4 points) and ``dC = m(C) - C``.

The fitted right-hand sides are therefore not displacements but the columns
of ``M`` (paper Sect. 6): ``values`` is (m, 4h), one 4-column block per
handle, zero in other handles' blocks and in the fixed band.

Constraint groups.  A handle is one *group*: a set of constraint points, a
(p, k) matrix of affine weight rows (each sums to 1) and k control points; a
move ``dC`` (k, 3) of the controls displaces point i by ``weights[i] @ dC``.
A rigid handle has k = 4 (its affine frame, and ``points == weights @
controls``).  A non-rigid **control curve** (paper Sect. 3 end and Sect. 6
end; see :mod:`splatedit.deform.curves`) is a group of curve samples
``c(t_i)`` with the non-negative displacement weights ``W(t_i)`` (p, k + 1)
and its k + 1 picked points as controls (its samples lie on the Catmull-Rom
shape, not at ``W @ q``).
Groups are ordered handles first, then curves; their column blocks follow
the same order.  The fixed band is not a group (its value is 0).

Curves (decisions).  Curve samples are extra constraint points (not splats)
anywhere in space; they do not change the free region (support minus
handles), and a curve with the fixed band alone defines an edit.  A sample
is **dropped** (counted in ``ConstraintGroup.n_dropped``) when

* its nearest splat is not a free splat (it sits over the fixed part of the
  model, or on a handle, whose splats do not follow the curve), or
* a splat outside the support, a handle splat, or a kept sample of an earlier
  curve lies within one point spacing of it: two different displacements
  almost at one point make an ill-conditioned, oscillating fit.

So a curve may run past the support boundary or over a handle: only its part
over the free region constrains the edit.  A curve that loses every sample
raises SolverError.  Self-intersecting curves are left to the solver's
duplicate check.

Control frame (decision): see :mod:`splatedit.deform.frames`.

Whole-model support (decision).  When no splat lies within the band width
outside the support (the support is the whole cloud, or a separate
component), there is no fixed band.  This is allowed: the field then only
interpolates the handle bands (quadratic polynomial precision means one
handle moves the whole support rigidly, two handles blend between their
transforms).  ``Constraints.has_fixed_band`` tells the caller, which may
warn.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from splatedit.deform.frames import affine_coordinates, handle_frame
from splatedit.errors import ParameterError, SolverError
from splatedit.model.spacing import point_spacing
from splatedit.tolerances import (BAND_RINGS, BAND_SLACK_REL, CONFLICT_RINGS, CURVE_MAX_SAMPLES_FLOOR,
                                  SPACING_SAMPLE)


class CurveSamplesError(SolverError):
    """A curve asks for more samples than the model can use (see
    ``CURVE_MAX_SAMPLES_FLOOR``); ``curve`` is its index, ``given`` whether
    the count was given (else it follows from the curve's length)."""

    def __init__(self, curve: int, given: bool, message: str):
        super().__init__(message)
        self.curve = curve
        self.given = given


# ------------------------------------------------------------- structures
@dataclass
class ConstraintGroup:
    """Constraint points that are an affine combination of control points.

    Attributes:
        kind: ``"handle"`` (rigid control handle, k = 4) or ``"curve"``
            (control curve, k = its number of control points).
        points: (p, 3) constraint positions (model units).
        weights: (p, k) rows of affine weights (sum 1): a move ``dC`` (k, 3)
            of the controls displaces ``points[i]`` by ``weights[i] @ dC``;
            for a handle also ``points == weights @ controls``.
        controls: (k, 3) control points (the handle's frame C, or the curve's
            picked points q_j).
        band_index: (p,) cloud indices of the constraint points (the handle
            band), or None for samples that are not splats (curves).
        member_index: (q,) cloud indices of every splat that moves with the
            group as a whole (all handle splats), empty for curves.
        curve: the :class:`~splatedit.deform.curves.ControlCurve` (curves only).
        params: (p,) curve parameters ``t_i`` of the kept samples (curves only).
        n_dropped: curve samples dropped next to other constraints.
    """

    kind: str
    points: np.ndarray
    weights: np.ndarray
    controls: np.ndarray
    band_index: np.ndarray | None = None
    member_index: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    curve: object = None
    params: np.ndarray | None = None
    n_dropped: int = 0

    @property
    def n_columns(self) -> int:
        return self.weights.shape[1]


@dataclass(frozen=True)
class Conflict:
    """Fixed splats that lay too close to a handle and were left out of the fit
    (two different displacements almost at one place: an ill-conditioned fit
    next to the handle's band, a tear anywhere).

    Attributes:
        handle: index of the handle (group) they touch.
        fixed_index: (c,) cloud indices of the dropped fixed-band splats.
        center: (3,) centroid of those splats (model units), to say where.
        min_distance: smallest fixed-to-handle distance (model units).
    """
    handle: int
    fixed_index: np.ndarray
    center: np.ndarray
    min_distance: float

    @property
    def count(self) -> int:
        return len(self.fixed_index)

    def describe(self, spacing: float) -> str:
        c = ", ".join(f"{x:.4g}" for x in self.center)
        return (f"{self.count} fixed splats lie within {CONFLICT_RINGS:g} point spacings of handle "
                f"{self.handle} (closest {self.min_distance / spacing:.2g} spacings, around ({c})); "
                "they were left out of the fit and do not move: add them to the support")


@dataclass
class Constraints:
    """Everything the RBF fit and the basis precomputation need.

    Attributes:
        points: (m, 3) constraint points: fixed band first, then each group's
            band in order.
        values: (m, K) right-hand sides, K = sum of group columns (4 per
            handle, k + 1 per curve); block column ``columns(g)`` holds group
            g's weights on its own rows, zeros elsewhere.
        fixed_index: (f,) cloud indices of the fixed band.
        groups: the constraint groups: the handles, then the curves, each in
            the order given.
        spacing: point spacing used (model units).
        band_width: ``rings * spacing`` (model units).
        support_index: (N,) sorted cloud indices of the support.
        free_index: (N_free,) sorted cloud indices of support minus handles.
        n_points: number of splats of the cloud the masks refer to.
        conflicts: fixed-band splats dropped next to handles (see
            :class:`Conflict`), one entry per handle that had any.
    """

    points: np.ndarray
    values: np.ndarray
    fixed_index: np.ndarray
    groups: list[ConstraintGroup]
    spacing: float
    band_width: float
    support_index: np.ndarray
    free_index: np.ndarray
    n_points: int
    conflicts: list[Conflict] = field(default_factory=list)

    @property
    def n_constraints(self) -> int:
        return len(self.points)

    @property
    def n_columns(self) -> int:
        return self.values.shape[1]

    @property
    def has_fixed_band(self) -> bool:
        return len(self.fixed_index) > 0

    @property
    def handles(self) -> list[ConstraintGroup]:
        return [g for g in self.groups if g.kind == "handle"]

    @property
    def curves(self) -> list[ConstraintGroup]:
        return [g for g in self.groups if g.kind == "curve"]

    @property
    def n_handles(self) -> int:
        return len(self.handles)

    @property
    def n_curves(self) -> int:
        return len(self.curves)

    @property
    def handle_band_index(self) -> list[np.ndarray]:
        """Cloud indices of each handle's band."""
        return [g.band_index for g in self.handles]

    @property
    def handle_index(self) -> list[np.ndarray]:
        """Cloud indices of all splats of each handle."""
        return [g.member_index for g in self.handles]

    @property
    def control_frames(self) -> np.ndarray:
        """(h, 4, 3) control frames of the handles."""
        hs = self.handles
        if not hs:
            return np.zeros((0, 4, 3))
        return np.stack([g.controls for g in hs])

    def columns(self, group: int) -> slice:
        """Column block of ``values`` belonging to group ``group``."""
        if not 0 <= group < len(self.groups):
            raise ParameterError("group", f"index {group} out of range 0..{len(self.groups) - 1}")
        start = sum(g.n_columns for g in self.groups[:group])
        return slice(start, start + self.groups[group].n_columns)

    def rows(self, group: int) -> slice:
        """Rows of ``points``/``values`` holding group ``group``'s band."""
        self.columns(group)  # range check
        start = len(self.fixed_index) + sum(len(g.points) for g in self.groups[:group])
        return slice(start, start + len(self.groups[group].points))


# --------------------------------------------------------------- building
def as_mask(name: str, sel, n: int) -> np.ndarray:
    """(n,) bool mask from a mask or an index array (ParameterError naming ``name``)."""
    arr = np.asarray(sel)
    if arr.dtype == bool:
        if arr.shape != (n,):
            raise ParameterError(name, f"mask must have shape ({n},), got {arr.shape}")
        return arr
    if arr.ndim != 1 or (arr.size and not np.issubdtype(arr.dtype, np.integer)):
        raise ParameterError(name, "must be a boolean mask or a 1-D array of splat indices")
    idx = arr.astype(np.int64)
    if idx.size and (idx.min() < 0 or idx.max() >= n):
        raise ParameterError(name, f"splat index out of range 0..{n - 1}")
    mask = np.zeros(n, dtype=bool)
    mask[idx] = True
    return mask


def _unique_rows(index: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Drop splats whose position exactly repeats an earlier one (duplicate
    vertices make the interpolation matrix singular); returns kept indices."""
    if len(index) < 2:
        return index
    _, first = np.unique(points, axis=0, return_index=True)
    if len(first) == len(index):
        return index
    return index[np.sort(first)]


def _support_spacing(sup_pts: np.ndarray, tree: cKDTree) -> float:
    """:func:`point_spacing` of the support; above SPACING_SAMPLE splats the
    median is taken over an evenly strided sample of them (nearest neighbours
    still among all support splats): the median of 65k samples is within
    about 1% of the full one, and a 400k-splat support's k-NN query over every
    splat took 0.26 s of CPU of its 0.62 s constraints."""
    n = len(sup_pts)
    if n <= SPACING_SAMPLE:
        return point_spacing(sup_pts, tree=tree)
    sample = sup_pts[::-(-n // SPACING_SAMPLE)]
    d, _ = tree.query(sample, k=2, workers=-1)
    if (d[:, 1] > 0).mean() < 0.5:   # mostly duplicates: the full rule
        return point_spacing(sup_pts, tree=tree)
    return point_spacing(sample, nearest=d[:, 1])


def _near(query: np.ndarray, reference: np.ndarray, width: float,
          tree: cKDTree | None = None) -> np.ndarray:
    """Mask of ``query`` points within ``width`` of any ``reference`` point."""
    if len(query) == 0 or len(reference) == 0:
        return np.zeros(len(query), dtype=bool)
    lo = reference.min(axis=0) - width
    hi = reference.max(axis=0) + width
    inbox = np.all((query >= lo) & (query <= hi), axis=1)
    out = np.zeros(len(query), dtype=bool)
    cand = np.flatnonzero(inbox)
    if len(cand):
        tree = cKDTree(reference) if tree is None else tree
        d, _ = tree.query(query[cand], k=1, distance_upper_bound=width, workers=-1)
        out[cand] = np.isfinite(d)
    return out


def build_constraints(cloud, support, handles=(), *, curves=(), rings: float = BAND_RINGS,
                      spacing: float | None = None) -> Constraints:
    """Constraints of an edit (see the module docstring).

    Args:
        cloud: the :class:`~splatedit.model.cloud.SplatCloud` being edited.
        support: (n,) bool mask (or index array) of the splats the edit may move.
        handles: list of (n,) bool masks (or index arrays), each inside the
            support, pairwise disjoint, in the order of their column blocks.
        curves: list of :class:`~splatedit.deform.curves.ControlCurve` (or
            (k + 1, 3) arrays of picked points); their groups follow the
            handles.  Sampled at the point spacing unless the curve fixes
            its sample count.
        rings: band thickness in point spacings (default ``BAND_RINGS`` = 3).
        spacing: point spacing in model units; default: median nearest-
            neighbour distance of the support splats.
    Raises:
        ParameterError: bad masks (shape, empty support or handle, neither
            handles nor curves, handle outside the support, overlapping
            handles, no free splats, rings <= 0), bad curve points.
        SolverError: a handle with no splat within the band width of the free
            region (the handle is not next to anything the edit can bend); a
            curve all of whose samples lie within a point spacing of other
            constraints.
    """
    pos = cloud.positions
    n = len(pos)
    if not (np.isfinite(rings) and rings > 0):
        raise ParameterError("rings", f"must be > 0, got {rings}")
    sup = as_mask("support", support, n)
    if not sup.any():
        raise ParameterError("support", "selects no splats (empty support region)")
    if isinstance(handles, np.ndarray) and handles.ndim == 1:
        handles = [handles]
    handles = list(handles)
    from splatedit.deform.curves import as_curve  # curves imports nothing from here
    curve_objs = [as_curve(c, f"curves[{i}]") for i, c in enumerate(curves)]
    if not handles and not curve_objs:
        raise ParameterError("handles", "at least one handle or curve is needed")
    hmasks = []
    covered = np.zeros(n, dtype=bool)
    for i, h in enumerate(handles):
        m = as_mask(f"handles[{i}]", h, n)
        if not m.any():
            raise ParameterError(f"handles[{i}]", "selects no splats (empty handle)")
        outside = m & ~sup
        if outside.any():
            raise ParameterError(f"handles[{i}]", f"{int(outside.sum())} handle splats lie "
                                 f"outside the support (first: splat {int(np.flatnonzero(outside)[0])}); "
                                 "a handle must be inside the support")
        both = m & covered
        if both.any():
            other = next(j for j, hm in enumerate(hmasks) if (hm & m).any())
            raise ParameterError(f"handles[{i}]", f"overlaps handles[{other}] in {int(both.sum())} "
                                 "splats; handles must be disjoint")
        covered |= m
        hmasks.append(m)
    free = sup & ~covered
    if not free.any():
        raise ParameterError("handles", "cover the whole support: no free splats are left "
                             "for the deformation to bend")

    support_index = np.flatnonzero(sup)
    free_index = np.flatnonzero(free)
    sup_pts = pos[support_index]
    sup_tree = cKDTree(sup_pts)
    if spacing is None:
        h = _support_spacing(sup_pts, sup_tree) if len(sup_pts) > 1 else 0.0
        if h <= 0.0:
            h = point_spacing(pos)
        if h <= 0.0:
            raise SolverError("cannot determine the point spacing: the splats coincide")
    else:
        h = float(spacing)
        if not (np.isfinite(h) and h > 0):
            raise ParameterError("spacing", f"must be > 0, got {spacing}")
    width = rings * h
    w_query = width * (1.0 + BAND_SLACK_REL)

    # fixed band: outside the support, within the width of a support splat
    out_index = np.flatnonzero(~sup)
    fixed_index = out_index[_near(pos[out_index], sup_pts, w_query, sup_tree)]
    fixed_index = _unique_rows(fixed_index, pos[fixed_index])

    # handle bands: handle splats within the width of a free splat (the free
    # splats' tree is built only when curves need it; a handle's band needs
    # only the free splats within its bounding box grown by the width)
    free_pts = pos[free_index]
    free_tree = cKDTree(free_pts) if curve_objs else None
    groups = []
    for i, m in enumerate(hmasks):
        hidx = np.flatnonzero(m)
        frame = handle_frame(pos[hidx], h)
        hp = pos[hidx]
        lo, hi = hp.min(axis=0) - w_query, hp.max(axis=0) + w_query
        near_free = free_pts[np.all((free_pts >= lo) & (free_pts <= hi), axis=1)]
        band = hidx[_near(hp, near_free, w_query)]
        band = _unique_rows(band, pos[band])
        if len(band) == 0:
            raise SolverError(f"handle {i} has no splat within {rings:g} point spacings "
                              f"({width:.4g} model units) of the free region; a handle must "
                              "touch the part of the support that can bend")
        groups.append(ConstraintGroup(kind="handle", points=pos[band],
                                      weights=affine_coordinates(pos[band], frame),
                                      controls=frame, band_index=band, member_index=hidx))

    # conflicts: fixed-band splats within CONFLICT_RINGS spacings of a handle
    # splat get a different displacement almost at the same place (next to
    # its band: an ill-conditioned fit; anywhere: a tear): drop and report them
    conflicts = []
    conflict_width = CONFLICT_RINGS * h * (1.0 + BAND_SLACK_REL)
    for i, g in enumerate(groups):
        if len(fixed_index) == 0:
            break
        d, _ = cKDTree(pos[g.member_index]).query(pos[fixed_index], k=1,
                                                  distance_upper_bound=conflict_width, workers=-1)
        bad = np.isfinite(d)
        if bad.any():
            idx = fixed_index[bad]
            conflicts.append(Conflict(handle=i, fixed_index=idx, center=pos[idx].mean(axis=0),
                                      min_distance=float(d[bad].min())))
            fixed_index = fixed_index[~bad]

    # curves: keep the samples whose nearest splat is free and that have no
    # outside splat, handle splat or earlier curve sample within one spacing
    drop_width = h * (1.0 + BAND_SLACK_REL)
    held = np.flatnonzero(~free)  # outside the support, or in a handle
    held_pts = pos[held]
    previous: list[np.ndarray] = []
    max_samples = max(len(pos), CURVE_MAX_SAMPLES_FLOOR)
    for i, curve in enumerate(curve_objs):
        count = curve.sample_count(spacing=h)
        if count > max_samples:
            why = ("given" if curve.samples is not None
                   else f"one per point spacing of {h:.4g} model units along the curve")
            raise CurveSamplesError(i, curve.samples is not None,
                                    f"curve {i}: {count:.4g} samples ({why}) are more than the model "
                                    f"can use: at most {max_samples} (one per splat)")
        t, w, samples = curve.sample(spacing=h)
        d_free, _ = free_tree.query(samples, k=1, workers=-1)
        reach = max(float(d_free.max()), drop_width)
        lo, hi = samples.min(axis=0) - reach, samples.max(axis=0) + reach
        cand = held_pts[np.all((held_pts >= lo) & (held_pts <= hi), axis=1)]
        if len(cand):
            d_held, _ = cKDTree(cand).query(samples, k=1, workers=-1)
        else:
            d_held = np.full(len(samples), np.inf)
        keep = (d_free < d_held) & (d_held > drop_width)
        if previous:
            keep &= ~_near(samples, np.concatenate(previous, axis=0), drop_width)
        if not keep.any():
            raise SolverError(f"curve {i}: none of its {len(samples)} samples is over the free "
                              f"region (nearest splat free, no fixed or handle splat or earlier "
                              f"curve within one point spacing = {h:.4g} model units); move the "
                              "curve into the free part of the support")
        near = ~keep
        groups.append(ConstraintGroup(kind="curve", points=samples[keep], weights=w[keep],
                                      controls=curve.controls.copy(), curve=curve,
                                      params=t[keep], n_dropped=int(near.sum())))
        previous.append(samples[keep])

    pts = np.concatenate([pos[fixed_index]] + [g.points for g in groups], axis=0)
    if len(np.unique(pts, axis=0)) != len(pts):
        raise SolverError("two splats at the same position get different constraints "
                          "(duplicate vertices on either side of a selection boundary); "
                          "remove duplicate points or change the selection")
    k_total = sum(g.n_columns for g in groups)
    values = np.zeros((len(pts), k_total))
    row, col = len(fixed_index), 0
    for g in groups:
        values[row:row + len(g.points), col:col + g.n_columns] = g.weights
        row += len(g.points)
        col += g.n_columns
    return Constraints(points=pts, values=values, fixed_index=fixed_index, groups=groups,
                       spacing=h, band_width=width, support_index=support_index,
                       free_index=free_index, n_points=n, conflicts=conflicts)
