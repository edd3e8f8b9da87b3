"""Reading edit scripts: the file (size, encoding), the JSON, and every
value checked with errors naming the JSON path of the bad value."""

from __future__ import annotations

import difflib

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from splatedit.deform.modes import DeformationMode
from splatedit.errors import EditScriptError
from splatedit.script.model import (METHODS, SCRIPT_VERSION, TRS, Curve, Edit, EditScript, Matrix,
                                    Removal, SolverSettings, Transform)
from splatedit.select.regions import Box, Indices, Region, Sphere
from splatedit.tolerances import AFFINE_MIN_SINGULAR_REL, IQR_DEFAULT_TOL, MAX_COORDINATE_ABS, MAX_SCRIPT_BYTES


class ParseContext:
    """Where an edit script being parsed came from (``source``: its path, or
    None): :meth:`fail` makes the error for a bad value at a JSON path."""

    def __init__(self, source: str | None):
        self.source = source

    def fail(self, json_path: str, message: str) -> EditScriptError:
        return EditScriptError(message, json_path=json_path, path=self.source)

    def obj(self, value, jp: str, required: tuple[str, ...] = (), allowed: tuple[str, ...] | None = None) -> dict:
        if not isinstance(value, dict):
            raise self.fail(jp, f"must be an object, got {_kind(value)}")
        for key in required:
            if key not in value:
                known = set(allowed if allowed is not None else required)
                typo = difflib.get_close_matches(key, [k for k in value if k not in known], n=1)
                hint = f" (is {typo[0]!r} a misspelling of it?)" if typo else ""
                raise self.fail(jp, f"missing key {key!r}{hint}")
        if allowed is not None:
            extra = sorted(set(value) - set(allowed))
            if extra:
                near = difflib.get_close_matches(extra[0], [k for k in allowed if k not in value], n=1)
                hint = f"; is it a misspelling of {near[0]!r}?" if near else ""
                raise self.fail(f"{jp}.{extra[0]}", f"unknown key (allowed: {', '.join(allowed)}){hint}")
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


def _region(ctx: ParseContext, value, jp: str, flags: tuple[str, ...] = ()) -> Region:
    """One region of ``value``: a sphere, box or index list; ``flags`` are
    further keys the caller reads itself (an edit's support: ``fill_holes``),
    accepted and dropped here so that an unknown key's message lists them."""
    obj = ctx.obj(value, jp, allowed=("sphere", "box", "indices") + flags)
    obj = {k: v for k, v in obj.items() if k not in flags}
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


def _transform(ctx: ParseContext, value, jp: str) -> Transform:
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


def _curves(ctx: ParseContext, value, jp: str) -> tuple[Curve, ...]:
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
    ctx = ParseContext(source)
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
        if isinstance(e, dict) and ("delete" in e or "crop" in e):
            kind = "delete" if "delete" in e else "crop"
            ctx.obj(e, jp, allowed=(kind,))
            edits.append(Removal(_region(ctx, e[kind], f"{jp}.{kind}"), kind == "crop", jp))
            continue
        e = ctx.obj(e, jp, required=("support",),
                    allowed=("support", "handle", "handles", "transform", "transforms", "curves",
                             "deformation"))
        sup_in, fill_holes = e["support"], True
        if isinstance(sup_in, dict) and "fill_holes" in sup_in:
            fill_holes = sup_in["fill_holes"]
            if not isinstance(fill_holes, bool):
                raise ctx.fail(f"{jp}.support.fill_holes", f"must be true or false, got {_kind(fill_holes)}")
        support = _region(ctx, sup_in, f"{jp}.support", flags=("fill_holes",))
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
