"""Running edit scripts on a splat cloud (CPU path): each edit's regions
resolved to masks and matrices, its deformation basis fitted and committed,
and the :class:`EditReport` the CLI prints."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from splatedit.deform.distortion import DistortionStats, distortion_from_axes
from splatedit.deform.modes import DeformationMode
from splatedit.deform.refine import refine_committed
from splatedit.errors import EditScriptError, InputError, SplatEditError
from splatedit.script.model import Edit, EditScript, Removal, SolverSettings
from splatedit.script.parse import ParseContext
from splatedit.select.regions import Box, Indices, Region, Sphere
from splatedit.tolerances import CLOSURE_ONE_SIDED_SHARE


@dataclass
class EditReport:
    """What one edit did (printed by the CLI)."""
    index: int
    support: int
    handles: list[int]
    constraints: int
    centers: int
    residual: float
    method: str
    fit_seconds: float
    basis_seconds: float
    max_displacement: float
    notes: list[str] = field(default_factory=list)
    #: per curve: (picked points, kept samples)
    curves: list[tuple[int, int]] = field(default_factory=list)
    #: splats the selection closure added (support and handles)
    closure_added: int = 0
    #: warnings for the user (conflicting constraints), one sentence each
    warnings: list[str] = field(default_factory=list)
    #: distortion of the support splats (splatedit.deform.distortion): per-splat
    #: stretch max(s1, 1/s2) and area change s1 s2 of the committed axes
    distortion: DistortionStats | None = None
    #: the edit's deformation mode ("rotation", "linear", "detail")
    mode: str = DeformationMode.ROTATION.value

    def distortion_line(self) -> str:
        """``  distortion: stretch max 1.84x, 0 > 3x, 0 > 4x, area change 0.71..2.30``."""
        if self.distortion is None:
            return ""
        return f"  distortion: {self.distortion.summary()}"

    def distortion_warning(self) -> str | None:
        """The warning text when splats are stretched beyond the warn threshold, else None."""
        d = self.distortion
        if d is None or not d.exceeds_warn:
            return None
        return (f"edit {self.index} stretches {d.n_above_warn} of {d.n} support splats "
                f"({100.0 * d.fraction_above_warn:.1f} %) more than {d.warn:g}x "
                f"({d.n_above_broken} more than {d.broken:g}x, max {d.max_stretch:.2f}x): "
                f"expect blurred detail and holes there; use a larger support or a milder transform")

    def line(self) -> str:
        hs = "+".join(map(str, self.handles))
        notes = f" ({'; '.join(self.notes)})" if self.notes else ""
        closed = f" (closure added {self.closure_added})" if self.closure_added else ""
        groups = [f"handle {hs}"] if self.handles else []
        groups += [f"curve {k} points/{n} samples" for k, n in self.curves]
        return (f"edit {self.index}: {self.mode} deformation, support {self.support} splats{closed}, {', '.join(groups)}, "
                f"{self.constraints} constraints, {self.method} with {self.centers} centers "
                f"(residual {self.residual:.2e}), fit {self.fit_seconds:.2f} s + basis "
                f"{self.basis_seconds:.2f} s, max displacement {self.max_displacement:.4g}{notes}")


@dataclass
class RemovalReport:
    """What a ``delete`` / ``crop`` item did (printed by the CLI like an
    :class:`EditReport`)."""
    index: int
    kind: str          # "delete" or "crop"
    removed: int
    left: int
    warnings: list[str] = field(default_factory=list)
    distortion: DistortionStats | None = None

    def line(self) -> str:
        return f"edit {self.index}: {self.kind}, removed {self.removed} splats, {self.left} left"

    def distortion_line(self) -> str:
        return ""

    def distortion_warning(self) -> str | None:
        return None


def removal_mask(positions: np.ndarray, item: Removal, source: str | None = None) -> np.ndarray:
    """(n,) bool of the splats left after a ``delete`` / ``crop`` item on a
    model with ``positions`` (n, 3).

    Raises:
        EditScriptError: an index past the model, a region that selects no
            splat, or an item that would leave none (the item's JSON path).
    """
    ctx = ParseContext(source)
    n = len(positions)
    jp = f"{item.json_path}.{item.key}"
    r = item.region
    if isinstance(r, Indices) and max(r.indices) >= n:
        bad = next(i for i, x in enumerate(r.indices) if x >= n)
        raise ctx.fail(f"{jp}.indices[{bad}]", f"index {r.indices[bad]} is out of range (the model has {n} splats)")
    inside = r.mask(positions)
    if not inside.any():
        raise ctx.fail(jp, "selects no splat")
    kept = inside if item.keep else ~inside
    if not kept.any():
        raise ctx.fail(jp, "would remove every splat of the model")
    return kept


def remove_splats(cloud, item: Removal, index: int, source: str | None = None):
    """(the cloud without the splats ``item`` removes, its RemovalReport)."""
    kept = removal_mask(cloud.positions, item, source)
    return cloud.subset(kept), RemovalReport(index, item.key, int((~kept).sum()), int(kept.sum()))


def resolve_edit(cloud, edit: Edit, source: str | None = None):
    """Masks and matrices of one edit on ``cloud``.

    Returns:
        (support (n,) bool, handles list of (n,) bool, matrices list of (4,4) float64)
    Raises:
        EditScriptError: a region selects nothing or indexes past the cloud.
    """
    ctx = ParseContext(source)
    n = cloud.n

    def mask(region: Region, jp: str) -> np.ndarray:
        if isinstance(region, Indices) and max(region.indices) >= n:
            bad = next(i for i, x in enumerate(region.indices) if x >= n)
            raise ctx.fail(f"{jp}.indices[{bad}]", f"index {region.indices[bad]} is out of range (the model has {n} splats)")
        return region.mask(cloud.positions)

    support = mask(edit.support, f"{edit.json_path}.support")
    if not support.any():
        raise ctx.fail(f"{edit.json_path}.support", "selects no splat")
    handles, matrices = [], []
    single = len(edit.handles) == 1
    for k, (h, t) in enumerate(zip(edit.handles, edit.transforms)):
        jp = f"{edit.json_path}.handle" if single else f"{edit.json_path}.handles[{k}]"
        hm = mask(h, jp) & support
        if not hm.any():
            raise ctx.fail(jp, "selects no splat inside the support")
        handles.append(hm)
        matrices.append(t.matrix(cloud.positions[hm].mean(axis=0)))
    return support, handles, matrices


@dataclass
class ResolvedEdit:
    """One edit resolved on a cloud: everything ``DeformationBasis.fit`` and
    ``DeformationBasis.displacement`` need.

    Attributes:
        support: (n,) bool mask.
        handles: list of (n,) bool masks (inside the support).
        matrices: one (4, 4) affine matrix per handle.
        curves: one :class:`~splatedit.deform.curves.ControlCurve` per curve.
        curve_moves: per curve, the (k + 1, 3) control-point displacements
            that move its picked points by the script's ``move``.
    """
    support: np.ndarray
    handles: list
    matrices: list
    curves: list
    curve_moves: list
    fill_holes: bool = True
    deformation: DeformationMode = DeformationMode.ROTATION

    @property
    def inputs(self) -> list:
        """Per-group inputs of ``DeformationBasis.displacement`` (handles, then curves)."""
        return list(self.matrices) + list(self.curve_moves)


def resolve_edit_inputs(cloud, edit: Edit, source: str | None = None) -> ResolvedEdit:
    """Masks, matrices and control curves of one edit on ``cloud``.

    Raises:
        EditScriptError: a region selects nothing or indexes past the cloud;
            a bad curve (JSON path of the curve).
    """
    support, handles, matrices = resolve_edit(cloud, edit, source)
    curves, moves = [], []
    for j, c in enumerate(edit.curves):
        try:
            cc = c.control_curve()
            moves.append(cc.control_displacement(np.array(c.move, dtype=np.float64)))
        except SplatEditError as exc:
            raise EditScriptError(str(exc), json_path=f"{edit.json_path}.curves[{j}]",
                                  path=source) from None
        curves.append(cc)
    return ResolvedEdit(support, handles, matrices, curves, moves, edit.fill_holes, edit.deformation)


#: progress stage name of the selection closure
CLOSURE_STAGE = "closing the selection"


def close_edit(cloud, r: ResolvedEdit, progress=None, regions: tuple | None = None):
    """Close an edit's selection inside its regions (unless ``fill_holes`` is
    off, see :mod:`splatedit.select.closure`): whatever closure adds to the
    support lies inside the support's region, and to a handle inside that
    handle's, so no splat outside a region the script gave moves.  A sphere
    or a box selects all it covers, so closure adds nothing there; an index
    list (a one-view stroke) reaches what it encloses or hides: its holes,
    the back side of a thin part and the rim between the two, not its outer
    rim; handle index lists close inside the closed support.

    Args:
        regions: (support Region, handle Regions) of ``r``; None counts
            every region as an index list.
    Returns:
        (support (n,) bool, handles list of (n,) bool, ClosureResult or None, seconds)
    """
    from splatedit.select.closure import close_selection, enclosed_holes
    from splatedit.select.graph import NeighbourGraph
    if not r.fill_holes:
        return r.support, list(r.handles), None, 0.0
    t0 = time.perf_counter()
    if progress is not None:
        progress(CLOSURE_STAGE, 0.0)
    graph = NeighbourGraph.build(cloud.positions)
    sup_region, h_regions = regions if regions is not None else (None, [None] * len(r.handles))

    def support_reach(region, mask):
        """The region the user gave the support, as a mask.  A sphere or box
        selects all it covers.  An index list painted from one view (its
        splats all face one way, CLOSURE_ONE_SIDED_SHARE) reaches what it
        encloses or hides: its holes and islands, the back side of a thin
        part painted from the front and the rim between the two (rules 1-3
        of the list alone, without a handle's margin), never its outer rim;
        a list holding both sides of a part reaches its holes only."""
        if isinstance(region, (Sphere, Box)):
            return mask
        if not one_sided(mask):
            return mask | enclosed_holes(graph, mask)
        return close_selection(cloud, mask, (), graph=graph).support | enclosed_holes(graph, mask)

    def one_sided(mask):
        """All (CLOSURE_ONE_SIDED_SHARE) of the list's splats face one way:
        painted from one view.  A list that holds both sides of a part was
        selected through it and has nothing hidden behind it to add."""
        nrm = cloud.normals_at(np.flatnonzero(mask))
        mean = nrm.sum(axis=0)
        return bool(np.linalg.norm(mean) > 0 and np.mean(nrm @ mean > 0) >= CLOSURE_ONE_SIDED_SHARE)

    def handle_reach(region, mask):
        """A handle's region: a sphere or box as given; an index list closes
        inside the (closed) support like a painted handle (its back side)."""
        return mask if isinstance(region, (Sphere, Box)) else None

    res = close_selection(cloud, r.support, r.handles, graph=graph, reach=support_reach(sup_region, r.support),
                          handle_reach=[handle_reach(g, h) for g, h in zip(h_regions, r.handles)])
    if progress is not None:
        progress(CLOSURE_STAGE, 1.0)
    return res.support, list(res.handles), res, time.perf_counter() - t0


def fit_edit(cloud, edit: Edit, solver: SolverSettings, *, method: str | None = None,
             tol: float | None = None, source: str | None = None, progress=None):
    """Resolve one edit on ``cloud`` and fit its deformation basis.

    ``method``/``tol`` override ``solver`` when given.
    Returns:
        (ResolvedEdit, DeformationBasis, displacement): the displacement is what
        ``DeformationBasis.displacement`` returns in the edit's mode (a (K, 3)
        dC for "linear", a RotationDisplacement for "rotation")
    Raises:
        EditScriptError: bad regions/curves, or a fit that failed (JSON path of the edit).
    """
    from splatedit.deform.basis import DeformationBasis
    from splatedit.deform.constraints import CurveSamplesError

    r = resolve_edit_inputs(cloud, edit, source)
    fit = DeformationBasis.fit
    if r.deformation is DeformationMode.DETAIL:
        from splatedit.deform.detail import DetailBasis
        fit = DetailBasis.fit
    support, handles, closure, t_closure = close_edit(cloud, r, progress, (edit.support, edit.handles))
    try:
        basis = fit(cloud, support, handles, curves=r.curves,
                    method=method or solver.method, tol=solver.tol if tol is None else tol,
                    max_centers=solver.max_centers, progress=progress)
        basis.stats["closure_seconds"] = t_closure
        basis.stats["closure_added"] = 0 if closure is None else closure.n_added
        d_c = basis.displacement(r.inputs, mode=edit.deformation)
    except CurveSamplesError as exc:
        jp = f"{edit.json_path}.curves[{exc.curve}]" + (".samples" if exc.given else ".points")
        raise EditScriptError(str(exc).split(": ", 1)[1], json_path=jp, path=source) from None
    except SplatEditError as exc:
        raise EditScriptError(str(exc), json_path=edit.json_path, path=source) from None
    return r, basis, d_c


def _degenerate_message(cloud, basis, d_c, exc: InputError) -> str:
    """Why committing an edit failed validation.  A splat inside the support
    was squashed by the deformation; a splat outside it was not touched, so
    the model as a whole became too large for it (splat axes must be longer
    than MIN_AXIS_LENGTH_REL of the diagonal) or beyond MAX_COORDINATE_ABS:
    say how far the edit moves things instead of blaming that splat."""
    from splatedit.tolerances import MIN_AXIS_LENGTH_REL, MIN_AXIS_POSITION_FACTOR
    row = exc.row
    d_c = getattr(d_c, "dC", d_c)    # a RotationDisplacement: its residual dC
    move = float(np.linalg.norm(d_c, axis=1).max()) if len(d_c) else 0.0
    # a splat moved so far that its (unchanged) axes fall below the minimum
    # length there (MIN_AXIS_LENGTH_REL of MIN_AXIS_POSITION_FACTOR times its
    # distance from the origin): the move is the cause, not a squashed splat
    too_far = (row is not None and 0 <= row < cloud.n and move * MIN_AXIS_LENGTH_REL * MIN_AXIS_POSITION_FACTOR
               >= min(float(np.linalg.norm(cloud.u[row])), float(np.linalg.norm(cloud.v[row]))))
    if row is not None and not too_far and row in set(np.asarray(basis.indices).tolist()):
        return (f"the edit makes splats degenerate ({exc.reason}, splat {row}); "
                "use a milder transform")
    return (f"the edit moves its controls up to {move:.3g} model units, {move / max(cloud.diagonal, 1e-300):.3g} "
            f"times the model's size ({cloud.diagonal:.3g}): the result cannot be stored "
            f"({exc.reason}); use a milder transform")


def run_script(cloud, script: EditScript, *, method: str | None = None, tol: float | None = None,
               source: str | None = None, progress=None,
               on_edit: Callable[[EditReport], None] | None = None):
    """Apply every edit of ``script`` to ``cloud`` in order (CPU path).

    ``method``/``tol`` override the script's solver settings when given.
    Returns:
        (deformed SplatCloud, list of EditReport)
    """
    reports = []
    for i, edit in enumerate(script.edits):
        if isinstance(edit, Removal):
            cloud, rep = remove_splats(cloud, edit, i, source)
            reports.append(rep)
            if on_edit is not None:
                on_edit(rep)
            continue
        r, basis, d_c = fit_edit(cloud, edit, script.solver, method=method, tol=tol,
                                 source=source, progress=progress)
        t0 = time.perf_counter()
        try:   # commit validates: an extreme edit must not write an unreadable model
            new = basis.commit(cloud, d_c)
        except InputError as exc:
            raise EditScriptError(_degenerate_message(cloud, basis, d_c, exc), json_path=edit.json_path,
                                  path=source) from None
        i_sup = basis.indices
        dist = distortion_from_axes(cloud.u[i_sup], cloud.v[i_sup], new.u[i_sup], new.v[i_sup])
        new, dist, refined = refine_committed(basis, cloud, new, edit.deformation, r.matrices, dist)
        disp = float(np.sqrt(((new.positions - cloud.positions) ** 2).sum(1)).max())
        stats = basis.stats
        con = basis.constraints
        rep = EditReport(i, len(con.support_index), [len(h) for h in con.handle_index], stats["n_constraints"],
                         stats["n_centers"], stats["residual"], stats["method"], stats["fit_seconds"],
                         stats["basis_seconds"] + (time.perf_counter() - t0), disp,
                         ([stats["message"]] if stats.get("message") else []) + ([refined] if refined else []),
                         [(c.n_controls, n) for c, n in zip(r.curves, stats.get("n_curve_samples", []))],
                         stats.get("closure_added", 0),
                         [f"edit {i}: {c.describe(con.spacing)}" for c in con.conflicts],
                         dist, DeformationMode(edit.deformation).value)
        reports.append(rep)
        if on_edit is not None:
            on_edit(rep)
        cloud = new
    return cloud, reports
