"""The edit script data model (:mod:`splatedit.script` documents the JSON
format): regions, transforms, curves, edits, solver settings, and the
script's JSON output."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from splatedit.deform.modes import DeformationMode
from splatedit.select.regions import Box, Region, Sphere
from splatedit.tolerances import IQR_DEFAULT_TOL

SCRIPT_VERSION = 1
METHODS = ("auto", "iqr", "lu")


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
class Removal:
    """A ``delete`` item (``keep`` False: remove the splats of ``region``) or
    a ``crop`` item (``keep`` True: keep only them).  The splats left keep
    their order; later items index the smaller model."""
    region: Region
    keep: bool = False
    json_path: str = "$"

    @property
    def key(self) -> str:
        return "crop" if self.keep else "delete"

    def kept(self, positions: np.ndarray) -> np.ndarray:
        """(n,) bool: the splats left after this item on a model with
        ``positions`` (n, 3)."""
        m = self.region.mask(positions)
        return m if self.keep else ~m


@dataclass(frozen=True)
class SolverSettings:
    """The script's ``solver`` object: fitting method (``auto``, ``lu``, ``iqr``), the IQR tolerance and an
    optional cap on the number of centres."""
    method: str = "auto"
    tol: float = IQR_DEFAULT_TOL
    max_centers: int | None = None


@dataclass(frozen=True)
class EditScript:
    """A whole edit script: its edits and removals in order, and the solver settings; ``to_json`` writes
    the documented format."""
    edits: tuple[Edit | Removal, ...]
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
            if isinstance(e, Removal):
                edits.append({e.key: region(e.region)})
                continue
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
        from splatedit.atomic import atomic_write_text
        atomic_write_text(path, json.dumps(self.to_json(), indent=1) + "\n")
