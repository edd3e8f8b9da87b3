"""JSON edit scripts: parse, validate and run a sequence of RBF edits headlessly.

Format (version 1)::

    {"version": 1,
     "solver": {"method": "auto"|"iqr"|"lu", "tol": 1e-7, "max_centers": null},
     "edits": [
       {"support": REGION,
        "handle": REGION,                    # or "handles": [REGION, ...]
        "transform": TRANSFORM,              # or "transforms": [TRANSFORM, ...]
        "curves": [CURVE, ...],              # optional; see below
        "deformation": "rotation"}]}         # optional: "rotation" (default) | "linear" | "detail"

    REGION    = {"sphere": {"center": [x,y,z], "radius": r}}      (a support region may add
                                                                "fill_holes": false)
              | {"box": {"min": [x,y,z], "max": [x,y,z]}}
              | {"indices": [i, ...]}
    TRANSFORM = {"matrix": [[4 numbers] x 4]}                      (row-major, acts on column vectors)
              | {"translate": [dx,dy,dz],
                 "rotate": {"axis": [ax,ay,az], "degrees": a, "center": [x,y,z]},
                 "scale": s | {"factor": s, "center": [x,y,z]}}     (any subset)

    CURVE     = {"points": [[x,y,z], ...],      (k + 1 >= 2 picked points, consecutive ones distinct)
                 "move": [[dx,dy,dz], ...],      (one displacement per picked point)
                 "samples": n}                   (optional integer >= 2; default: one per point spacing)

An edit needs at least one handle or curve: exactly one of ``handle`` /
``handles`` (with ``transform`` / ``transforms``), and/or ``curves``.  A curve
is the centripetal Catmull-Rom curve through its ``points`` (no overshoot; a
segment through 2; see splatedit.deform.curves); the edit moves the *picked
points* by ``move`` and every curve sample by a non-negative, smooth blend of
the moves of the two picked points around it, so the moved curve passes
through ``points + move`` and no part of it moves against the drags.  The curve need not lie on the surface; only its samples
over the free part of the support constrain the edit.  Curves take the
column blocks after the handles.

A handle region is intersected with its support.  A TRS transform applies
scale, then rotation, then translation; the rotation and scale centres default
to the handle's centroid.  Edits run one after another: each edit's result is
the base of the next (the paper's Bunny: ears, then head).  Every error names
the JSON path of the bad value, e.g. ``$.edits[0].transform.rotate.axis`` or
``$.edits[1].curves[0].move[2]``.

``deformation`` picks how the handles' maps spread over the support
(:class:`~splatedit.deform.modes.DeformationMode`): ``"rotation"`` (the
default) blends each handle's rotation over the support, so bends and twists
of 90 degrees and more keep their cross-sections; ``"linear"`` is the paper's
deformation (exact for translations, large rotations shrink the middle);
``"detail"`` splits the support into a smooth base surface plus normal
offsets, deforms the base rotation-aware and re-attaches the offsets along
the deformed normals (relief keeps its height and stays upright; see
:mod:`splatedit.deform.detail`).  Curves are displacements in every mode.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from splatedit.deform.distortion import DistortionStats, distortion_from_axes
from splatedit.deform.modes import DeformationMode
from splatedit.errors import EditScriptError, InputError, SplatEditError
from splatedit.select.regions import Box, Indices, Region, Sphere
from splatedit.tolerances import AFFINE_MIN_SINGULAR_REL, IQR_DEFAULT_TOL, MAX_COORDINATE_ABS, MAX_SCRIPT_BYTES

SCRIPT_VERSION = 1
METHODS = ("auto", "iqr", "lu")


# ----------------------------------------------------------------- data model
@dataclass(frozen=True)
class TRS:
    """Scale about a centre, rotate about an axis through a centre, translate.

    ``None`` centres mean "the handle's centroid" and are resolved at run time.
    """
    translate: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotate_axis: tuple[float, float, float] | None = None
    rotate_degrees: float = 0.0
    rotate_center: tuple[float, float, float] | None = None
    scale: float = 1.0
    scale_center: tuple[float, float, float] | None = None

    def matrix(self, handle_centroid: np.ndarray) -> np.ndarray:
        """(4, 4) float64 affine matrix acting on column vectors (x, y, z, 1)."""
        from splatedit.deform import transform as tf
        m = np.eye(4)
        if self.scale != 1.0:
            c = handle_centroid if self.scale_center is None else np.asarray(self.scale_center)
            m = tf.scale(self.scale, c) @ m
        if self.rotate_axis is not None and self.rotate_degrees != 0.0:
            c = handle_centroid if self.rotate_center is None else np.asarray(self.rotate_center)
            m = tf.rotate(self.rotate_axis, self.rotate_degrees, c) @ m
        return tf.translate(self.translate) @ m


@dataclass(frozen=True)
class Matrix:
    """An explicit (4, 4) affine matrix."""
    values: tuple[tuple[float, ...], ...]

    def matrix(self, handle_centroid: np.ndarray) -> np.ndarray:
        return np.array(self.values, dtype=np.float64)


Transform = TRS | Matrix


@dataclass(frozen=True)
class Curve:
    """A control curve of an edit: picked points, their displacements, and
    an optional sample count (None = one sample per point spacing)."""
    points: tuple[tuple[float, float, float], ...]
    move: tuple[tuple[float, float, float], ...]
    samples: int | None = None

    def control_curve(self):
        """The :class:`~splatedit.deform.curves.ControlCurve` through ``points``."""
        from splatedit.deform.curves import ControlCurve
        return ControlCurve.through(np.array(self.points, dtype=np.float64), samples=self.samples)


@dataclass(frozen=True)
class Edit:
    """One edit: a support region, zero or more handles with their transforms,
    and zero or more control curves (at least one handle or curve)."""
    support: Region
    handles: tuple[Region, ...]
    transforms: tuple[Transform, ...]
    json_path: str = "$"
    curves: tuple[Curve, ...] = ()
    #: close the selection before fitting (``"fill_holes": false`` on the
    #: support region turns it off; see splatedit.select.closure)
    fill_holes: bool = True
    #: how the handles' maps spread over the support (``"deformation"``)
    deformation: DeformationMode = DeformationMode.ROTATION


@dataclass(frozen=True)
class SolverSettings:
    method: str = "auto"
    tol: float = IQR_DEFAULT_TOL
    max_centers: int | None = None


@dataclass(frozen=True)
class EditScript:
    edits: tuple[Edit, ...]
    solver: SolverSettings = field(default_factory=SolverSettings)

    # ---------------------------------------------------------------- output
    def to_json(self) -> dict:
        """The script as a JSON-ready dict in the documented format."""
        def region(r: Region) -> dict:
            if isinstance(r, Sphere):
                return {"sphere": {"center": list(r.center), "radius": r.radius}}
            if isinstance(r, Box):
                return {"box": {"min": list(r.min), "max": list(r.max)}}
            return {"indices": list(r.indices)}

        def transform(t: Transform) -> dict:
            if isinstance(t, Matrix):
                return {"matrix": [list(row) for row in t.values]}
            out: dict[str, Any] = {"translate": list(t.translate)}
            if t.rotate_axis is not None:
                rot: dict[str, Any] = {"axis": list(t.rotate_axis), "degrees": t.rotate_degrees}
                if t.rotate_center is not None:
                    rot["center"] = list(t.rotate_center)
                out["rotate"] = rot
            if t.scale != 1.0:
                out["scale"] = (t.scale if t.scale_center is None
                                else {"factor": t.scale, "center": list(t.scale_center)})
            return out

        solver: dict[str, Any] = {"method": self.solver.method, "tol": self.solver.tol}
        if self.solver.max_centers is not None:
            solver["max_centers"] = self.solver.max_centers
        def curve(c: Curve) -> dict:
            out: dict[str, Any] = {"points": [list(p) for p in c.points],
                                   "move": [list(d) for d in c.move]}
            if c.samples is not None:
                out["samples"] = c.samples
            return out

        edits = []
        for e in self.edits:
            item: dict[str, Any] = {"support": region(e.support)}
            if not e.fill_holes:
                item["support"]["fill_holes"] = False
            if len(e.handles) == 1:
                item["handle"] = region(e.handles[0])
                item["transform"] = transform(e.transforms[0])
            elif e.handles:
                item["handles"] = [region(h) for h in e.handles]
                item["transforms"] = [transform(t) for t in e.transforms]
            if e.curves:
                item["curves"] = [curve(c) for c in e.curves]
            item["deformation"] = DeformationMode(e.deformation).value
            edits.append(item)
        return {"version": SCRIPT_VERSION, "solver": solver, "edits": edits}

    def save(self, path: str | Path) -> None:
        """Write the script as JSON (atomic: temp file + rename)."""
        from splatedit.io.atomic import atomic_write_text
        atomic_write_text(path, json.dumps(self.to_json(), indent=1) + "\n")


# -------------------------------------------------------------------- parsing
class _Ctx:
    def __init__(self, source: str | None):
        self.source = source

    def fail(self, json_path: str, message: str) -> EditScriptError:
        return EditScriptError(message, json_path=json_path, path=self.source)

    def obj(self, value, jp: str, required: tuple[str, ...] = (), allowed: tuple[str, ...] | None = None) -> dict:
        if not isinstance(value, dict):
            raise self.fail(jp, f"must be an object, got {_kind(value)}")
        for key in required:
            if key not in value:
                raise self.fail(jp, f"missing key {key!r}")
        if allowed is not None:
            extra = sorted(set(value) - set(allowed))
            if extra:
                raise self.fail(f"{jp}.{extra[0]}", f"unknown key (allowed: {', '.join(allowed)})")
        return value

    def number(self, value, jp: str, *, positive: bool = False, nonnegative: bool = False) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.fail(jp, f"must be a number, got {_kind(value)}")
        try:
            x = float(value)
        except OverflowError:       # an integer literal like 10**400
            x = math.inf
        if not math.isfinite(x):
            raise self.fail(jp, f"must be finite, got {x}" + (" (beyond 1.8e308)" if isinstance(value, int) else ""))
        if abs(x) > MAX_COORDINATE_ABS:
            raise self.fail(jp, f"{x:.6g} is beyond the supported magnitude {MAX_COORDINATE_ABS:g}")
        if positive and x <= 0:
            raise self.fail(jp, f"must be > 0, got {x:g}")
        if nonnegative and x < 0:
            raise self.fail(jp, f"must be >= 0, got {x:g}")
        return x

    def vec3(self, value, jp: str, *, nonzero: bool = False) -> tuple[float, float, float]:
        if not isinstance(value, list) or len(value) != 3:
            raise self.fail(jp, f"must be a list of 3 numbers, got {_kind(value)}")
        v = tuple(self.number(x, f"{jp}[{i}]") for i, x in enumerate(value))
        if nonzero and not any(v):
            raise self.fail(jp, "must not be the zero vector")
        return v  # type: ignore[return-value]


def _kind(value) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, (int, float)):
        return f"the number {value!r}"
    if isinstance(value, str):
        return f"the string {value!r}"
    if isinstance(value, list):
        return f"a list of {len(value)}"
    return "an object"


def _region(ctx: _Ctx, value, jp: str) -> Region:
    obj = ctx.obj(value, jp, allowed=("sphere", "box", "indices"))
    if len(obj) != 1:
        raise ctx.fail(jp, "must have exactly one of 'sphere', 'box', 'indices'")
    kind, body = next(iter(obj.items()))
    jp = f"{jp}.{kind}"
    if kind == "sphere":
        body = ctx.obj(body, jp, required=("center", "radius"), allowed=("center", "radius"))
        return Sphere(ctx.vec3(body["center"], f"{jp}.center"),
                      ctx.number(body["radius"], f"{jp}.radius", positive=True))
    if kind == "box":
        body = ctx.obj(body, jp, required=("min", "max"), allowed=("min", "max"))
        lo = ctx.vec3(body["min"], f"{jp}.min")
        hi = ctx.vec3(body["max"], f"{jp}.max")
        for i in range(3):
            if lo[i] > hi[i]:
                raise ctx.fail(f"{jp}.min[{i}]", f"is greater than max[{i}] ({lo[i]:g} > {hi[i]:g})")
        return Box(lo, hi)
    if not isinstance(body, list) or not body:
        raise ctx.fail(jp, f"must be a non-empty list of splat indices, got {_kind(body)}")
    out = []
    for i, x in enumerate(body):
        if isinstance(x, bool) or not isinstance(x, int) or x < 0:
            raise ctx.fail(f"{jp}[{i}]", f"must be a non-negative integer, got {_kind(x)}")
        out.append(x)
    return Indices(tuple(out))


def _transform(ctx: _Ctx, value, jp: str) -> Transform:
    obj = ctx.obj(value, jp, allowed=("matrix", "translate", "rotate", "scale"))
    if not obj:
        raise ctx.fail(jp, "is empty: give 'matrix' or any of 'translate', 'rotate', 'scale'")
    if "matrix" in obj:
        if len(obj) != 1:
            raise ctx.fail(jp, "'matrix' cannot be combined with 'translate', 'rotate' or 'scale'")
        rows = obj["matrix"]
        if not isinstance(rows, list) or len(rows) != 4:
            raise ctx.fail(f"{jp}.matrix", f"must be 4 rows of 4 numbers, got {_kind(rows)}")
        vals = []
        for r, row in enumerate(rows):
            if not isinstance(row, list) or len(row) != 4:
                raise ctx.fail(f"{jp}.matrix[{r}]", f"must be a list of 4 numbers, got {_kind(row)}")
            vals.append(tuple(ctx.number(x, f"{jp}.matrix[{r}][{c}]") for c, x in enumerate(row)))
        m = np.array(vals)
        if not np.array_equal(m[3], [0, 0, 0, 1]):
            raise ctx.fail(f"{jp}.matrix[3]", "the last row of an affine matrix must be [0, 0, 0, 1]")
        sv = np.linalg.svd(m[:3, :3], compute_uv=False)
        if sv[-1] <= AFFINE_MIN_SINGULAR_REL * sv[0]:
            raise ctx.fail(f"{jp}.matrix", "is singular (it would flatten the handle)")
        if np.linalg.det(m[:3, :3]) < 0:
            raise ctx.fail(f"{jp}.matrix", "mirrors the handle (negative determinant), which would turn "
                           "its splats inside out")
        return Matrix(tuple(vals))
    translate = ctx.vec3(obj["translate"], f"{jp}.translate") if "translate" in obj else (0.0, 0.0, 0.0)
    axis, degrees, rcenter = None, 0.0, None
    if "rotate" in obj:
        rjp = f"{jp}.rotate"
        rot = ctx.obj(obj["rotate"], rjp, required=("axis", "degrees"), allowed=("axis", "degrees", "center"))
        axis = ctx.vec3(rot["axis"], f"{rjp}.axis", nonzero=True)
        degrees = ctx.number(rot["degrees"], f"{rjp}.degrees")
        rcenter = ctx.vec3(rot["center"], f"{rjp}.center") if "center" in rot else None
    scale, scenter = 1.0, None
    if "scale" in obj:
        sjp = f"{jp}.scale"
        s = obj["scale"]
        if isinstance(s, dict):
            s = ctx.obj(s, sjp, required=("factor",), allowed=("factor", "center"))
            scale = ctx.number(s["factor"], f"{sjp}.factor", positive=True)
            scenter = ctx.vec3(s["center"], f"{sjp}.center") if "center" in s else None
        else:
            scale = ctx.number(s, sjp, positive=True)
    return TRS(translate, axis, degrees, rcenter, scale, scenter)


def _curves(ctx: _Ctx, value, jp: str) -> tuple[Curve, ...]:
    from splatedit.deform.curves import first_coincident_point
    if not isinstance(value, list) or not value:
        raise ctx.fail(jp, f"must be a non-empty list of curves, got {_kind(value)}")
    out = []
    for j, c in enumerate(value):
        cjp = f"{jp}[{j}]"
        c = ctx.obj(c, cjp, required=("points", "move"), allowed=("points", "move", "samples"))
        pts_in = c["points"]
        if not isinstance(pts_in, list) or len(pts_in) < 2:
            raise ctx.fail(f"{cjp}.points", f"must be a list of at least 2 points [x, y, z], "
                           f"got {_kind(pts_in)}")
        pts = tuple(ctx.vec3(p, f"{cjp}.points[{k}]") for k, p in enumerate(pts_in))
        k = first_coincident_point(pts)
        if k is not None:
            raise ctx.fail(f"{cjp}.points[{k}]", f"coincides with points[{k - 1}]; "
                           "consecutive curve points must be distinct")
        mv = c["move"]
        if not isinstance(mv, list) or len(mv) != len(pts):
            raise ctx.fail(f"{cjp}.move", f"must be a list with one [dx, dy, dz] per point "
                           f"({len(pts)}), got {_kind(mv)}")
        move = tuple(ctx.vec3(d, f"{cjp}.move[{k}]") for k, d in enumerate(mv))
        samples = None
        if c.get("samples") is not None:
            n = c["samples"]
            if isinstance(n, bool) or not isinstance(n, int) or n < 2:
                raise ctx.fail(f"{cjp}.samples", f"must be an integer >= 2, got {_kind(n)}")
            samples = n
        out.append(Curve(pts, move, samples))
    return tuple(out)


def parse_script(data: Any, source: str | None = None) -> EditScript:
    """Validate a decoded JSON document and build an :class:`EditScript`.

    Raises:
        EditScriptError: naming the JSON path of the first bad value.
    """
    ctx = _Ctx(source)
    top = ctx.obj(data, "$", required=("version", "edits"), allowed=("version", "solver", "edits"))
    if top["version"] != SCRIPT_VERSION:
        raise ctx.fail("$.version", f"unsupported version {top['version']!r} (this splatedit reads {SCRIPT_VERSION})")
    solver = SolverSettings()
    if "solver" in top:
        s = ctx.obj(top["solver"], "$.solver", allowed=("method", "tol", "max_centers"))
        method = s.get("method", "auto")
        if method not in METHODS:
            raise ctx.fail("$.solver.method", f"must be one of {', '.join(METHODS)}, got {_kind(method)}")
        tol = ctx.number(s["tol"], "$.solver.tol", positive=True) if "tol" in s else IQR_DEFAULT_TOL
        max_centers = None
        if s.get("max_centers") is not None:
            mc = s["max_centers"]
            if isinstance(mc, bool) or not isinstance(mc, int) or mc < 1:
                raise ctx.fail("$.solver.max_centers", f"must be a positive integer, got {_kind(mc)}")
            max_centers = mc
        solver = SolverSettings(method, tol, max_centers)
    edits_in = top["edits"]
    if not isinstance(edits_in, list) or not edits_in:
        raise ctx.fail("$.edits", f"must be a non-empty list of edits, got {_kind(edits_in)}")
    edits = []
    for i, e in enumerate(edits_in):
        jp = f"$.edits[{i}]"
        e = ctx.obj(e, jp, required=("support",),
                    allowed=("support", "handle", "handles", "transform", "transforms", "curves",
                             "deformation"))
        sup_in, fill_holes = e["support"], True
        if isinstance(sup_in, dict) and "fill_holes" in sup_in:
            fill_holes = sup_in["fill_holes"]
            if not isinstance(fill_holes, bool):
                raise ctx.fail(f"{jp}.support.fill_holes", f"must be true or false, got {_kind(fill_holes)}")
            sup_in = {k: v for k, v in sup_in.items() if k != "fill_holes"}
        support = _region(ctx, sup_in, f"{jp}.support")
        curves = _curves(ctx, e["curves"], f"{jp}.curves") if "curves" in e else ()
        if "handle" in e and "handles" in e:
            raise ctx.fail(jp, "needs exactly one of 'handle' or 'handles'")
        if "handle" not in e and "handles" not in e:
            if not curves:
                raise ctx.fail(jp, "needs at least one handle or curve: exactly one of 'handle' or "
                               "'handles', and/or 'curves'")
            for key in ("transform", "transforms"):
                if key in e:
                    raise ctx.fail(f"{jp}.{key}", "is given without 'handle' or 'handles'")
            handles, transforms = (), ()
        elif "handle" in e:
            handles = (_region(ctx, e["handle"], f"{jp}.handle"),)
            if "transform" not in e:
                raise ctx.fail(jp, "missing key 'transform'")
            if "transforms" in e:
                raise ctx.fail(f"{jp}.transforms", "use 'transform' with a single 'handle'")
            transforms = (_transform(ctx, e["transform"], f"{jp}.transform"),)
        else:
            hs = e["handles"]
            if not isinstance(hs, list) or not hs:
                raise ctx.fail(f"{jp}.handles", f"must be a non-empty list of regions, got {_kind(hs)}")
            handles = tuple(_region(ctx, h, f"{jp}.handles[{k}]") for k, h in enumerate(hs))
            ts = e.get("transforms")
            if not isinstance(ts, list) or len(ts) != len(hs):
                raise ctx.fail(f"{jp}.transforms", f"must be a list with one transform per handle ({len(hs)})")
            transforms = tuple(_transform(ctx, t, f"{jp}.transforms[{k}]") for k, t in enumerate(ts))
        mode = DeformationMode.ROTATION
        if "deformation" in e:
            if not isinstance(e["deformation"], str):
                raise ctx.fail(f"{jp}.deformation", f"must be one of \"rotation\", \"linear\", \"detail\", "
                               f"got {_kind(e['deformation'])}")
            try:
                mode = DeformationMode.parse(e["deformation"])
            except ValueError as exc:
                raise ctx.fail(f"{jp}.deformation", str(exc)) from None
        edits.append(Edit(support, handles, transforms, jp, curves, fill_holes, mode))
    return EditScript(tuple(edits), solver)


def load_script(path: str | Path) -> EditScript:
    """Read and validate an edit script file (errors name the file and JSON path)."""
    p = Path(path)
    try:
        if not p.is_file():     # a FIFO would block, a directory cannot be read
            raise EditScriptError("not a regular file" if p.exists() else "cannot read: No such file or directory",
                                  path=str(p))
        raw = read_limited(p, MAX_SCRIPT_BYTES)
    except (OSError, ValueError) as exc:     # ValueError: a NUL byte in the name
        raise EditScriptError(f"cannot read: {getattr(exc, 'strerror', None) or exc}", path=str(p)) from None
    if raw is None:
        raise EditScriptError(f"larger than {MAX_SCRIPT_BYTES // 2**20} MiB: not an edit script",
                              path=str(p))
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        raise EditScriptError(f"not UTF-8 text: byte 0x{raw[exc.start]:02x} at offset {exc.start} "
                              f"(line {line})", path=str(p)) from None
    return parse_script(decode_json(text, str(p)), source=str(p))


def _int_or_float(digits: str):
    """JSON integer literals: Python ints up to 18 digits, longer ones as
    floats (inf beyond 1e308), so int('9' * 5000)'s ValueError and
    float(10**400)'s OverflowError cannot happen; number checks then name
    the JSON path."""
    return int(digits) if len(digits.lstrip("-")) <= 18 else float(digits)


def decode_json(text: str, source: str | None = None):
    """``json.loads`` with errors as :class:`EditScriptError`: syntax errors
    with line and column, nesting too deep for Python's recursion limit."""
    try:
        return json.loads(text, parse_int=_int_or_float)
    except json.JSONDecodeError as exc:
        raise EditScriptError(f"invalid JSON at line {exc.lineno} column {exc.colno}: {exc.msg}",
                              path=source) from None
    except RecursionError:
        raise EditScriptError("invalid JSON: nested too deeply", path=source) from None


def read_limited(path: Path, limit: int) -> bytes | None:
    """The file's bytes, or None when it holds more than ``limit`` bytes (read
    no further: a FIFO or /dev/zero must not fill the memory)."""
    with open(path, "rb") as fh:
        data = fh.read(limit + 1)
    return None if len(data) > limit else data


# -------------------------------------------------------------------- running
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


def resolve_edit(cloud, edit: Edit, source: str | None = None):
    """Masks and matrices of one edit on ``cloud``.

    Returns:
        (support (n,) bool, handles list of (n,) bool, matrices list of (4,4) float64)
    Raises:
        EditScriptError: a region selects nothing or indexes past the cloud.
    """
    ctx = _Ctx(source)
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
    try:
        basis = fit(cloud, r.support, r.handles, curves=r.curves,
                                     method=method or solver.method,
                                     tol=solver.tol if tol is None else tol,
                                     max_centers=solver.max_centers, fill_holes=r.fill_holes,
                                     progress=progress)
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
    row = exc.row
    if row is not None and row in set(np.asarray(basis.indices).tolist()):
        return (f"the edit makes splats degenerate ({exc.reason}, splat {row}); "
                "use a milder transform")
    d_c = getattr(d_c, "dC", d_c)    # a RotationDisplacement: its residual dC
    move = float(np.linalg.norm(d_c, axis=1).max()) if len(d_c) else 0.0
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
        r, basis, d_c = fit_edit(cloud, edit, script.solver, method=method, tol=tol,
                                 source=source, progress=progress)
        t0 = time.perf_counter()
        try:   # commit validates: an extreme edit must not write an unreadable model
            new = basis.commit(cloud, d_c)
        except InputError as exc:
            raise EditScriptError(_degenerate_message(cloud, basis, d_c, exc), json_path=edit.json_path,
                                  path=source) from None
        disp = float(np.sqrt(((new.positions - cloud.positions) ** 2).sum(1)).max())
        i_sup = basis.indices
        dist = distortion_from_axes(cloud.u[i_sup], cloud.v[i_sup], new.u[i_sup], new.v[i_sup])
        stats = basis.stats
        con = basis.constraints
        rep = EditReport(i, len(con.support_index), [len(h) for h in con.handle_index], stats["n_constraints"],
                         stats["n_centers"], stats["residual"], stats["method"], stats["fit_seconds"],
                         stats["basis_seconds"] + (time.perf_counter() - t0), disp,
                         [stats["message"]] if stats.get("message") else [],
                         [(c.n_controls, n) for c, n in zip(r.curves, stats.get("n_curve_samples", []))],
                         stats.get("closure_added", 0),
                         [f"edit {i}: {c.describe(con.spacing)}" for c in con.conflicts],
                         dist, DeformationMode(edit.deformation).value)
        reports.append(rep)
        if on_edit is not None:
            on_edit(rep)
        cloud = new
    return cloud, reports
