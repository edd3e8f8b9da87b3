"""SplatCloud: elliptical surface splats as plain numpy arrays.

A splat i is the ellipse ``{p_i + s u_i + t v_i : s^2 + t^2 <= 1}``: the
tangent axes ``u``, ``v`` carry the ellipse's semi-axes as their lengths and
the normal is ``normalize(u x v)``.

Precision (a deliberate choice, see docs/files.md "Precision"): positions and axes
are float64 on the CPU.  The fitting (RBF solves, Jacobians applied to the
axes) needs float64, and our PLY stores both bit-exactly; float32 axes would
save 240 MB per 10M splats but break that round trip and make every
deformation convert.  Colours are uint8, intensity uint16, classification
uint8 (the scanner formats' own widths).  The renderer converts to float32
when it uploads, which is why positions are *local*: a georeferenced scan
(UTM x ~ 500,000 m) is rebased on load to ``origin`` (float64), so float32
keeps sub-millimetre steps, and writers add ``origin`` back.
"""

from __future__ import annotations

from dataclasses import InitVar, dataclass, field
from typing import Optional

import numpy as np

from splatedit.errors import InputError
from splatedit.tolerances import (MAX_COORDINATE_ABS, MIN_AXIS_LENGTH_REL, MIN_AXIS_POSITION_FACTOR,
                                  MIN_AXIS_SINE, MIN_EXTENT_ABS, VALIDATE_CHUNK_ROWS)


def min_axis_lengths(positions: np.ndarray, diag: float) -> np.ndarray:
    """(m,) float64: the length a splat axis must exceed at each of the (m, 3)
    local ``positions`` of a cloud whose bounding-box diagonal is ``diag``:
    ``MIN_AXIS_LENGTH_REL`` of the diagonal or, where smaller, of
    ``MIN_AXIS_POSITION_FACTOR`` times the splat's distance from the origin
    (at least ``MIN_EXTENT_ABS``).  One glitch point 1e9 away (diagonal 1e9)
    made the main body's 0.15-unit splats near the origin "degenerate"
    (refused as "row 0: property 'u'"); splats farther than diag / factor
    from the origin keep the diagonal rule."""
    if not len(positions):
        return np.zeros(0)
    here = np.sqrt(np.einsum("ij,ij->i", positions, positions))
    return MIN_AXIS_LENGTH_REL * np.minimum(max(diag, 1e-300),
                                            MIN_AXIS_POSITION_FACTOR * np.maximum(here, MIN_EXTENT_ABS))


def _as_array(name, value, shape_tail, dtype, source):
    arr = np.asarray(value)
    if arr.ndim != 1 + len(shape_tail) or tuple(arr.shape[1:]) != shape_tail:
        raise InputError(f"expected shape (n, {', '.join(map(str, shape_tail))}), "
                         f"got {arr.shape}", path=source, prop=name)
    return np.ascontiguousarray(arr, dtype=dtype)


def column_bounds(arr: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(min, max) per column of an (n, k) array: one strided reduction per
    column, 3x faster than numpy's ``min(axis=0)`` on (10M, 3) here."""
    return (np.array([arr[:, j].min() for j in range(arr.shape[1])]),
            np.array([arr[:, j].max() for j in range(arr.shape[1])]))


@dataclass(frozen=True)
class Quantization:
    """The integer grid of a scanner file's coordinates (LAS/LAZ): world
    coordinate = integer * ``scale`` + ``offset``.  Kept with a cloud read
    from such a file so writing it back to LAS reproduces the same integers.

    Attributes:
        scale: (3,) float64, the resolution per axis (world units).
        offset: (3,) float64, the file's offset (world units).
        point_format: the LAS point format id read (None if unknown).
    """

    scale: tuple
    offset: tuple
    point_format: Optional[int] = None


@dataclass(eq=False)
class SplatCloud:
    """A cloud of elliptical splats.

    Attributes:
        positions: (n, 3) float64, splat centres (model units).
        u: (n, 3) float64, first tangent semi-axis (model units).
        v: (n, 3) float64, second tangent semi-axis (model units).
        colors: (n, 4) uint8 RGBA, or None for the default material.
        faces: (f, 3) int64 vertex indices, or None; kept when the input was a
            triangle mesh so a deformed mesh can be written back.
        name: a human-readable name (usually the file name).
        source: the path it was read from, used in error messages.
        origin: (3,) float64, the local origin in the file's frame: world
            coordinates are ``positions + origin`` (zeros unless the file's
            coordinates were far from 0, see :func:`splatedit.io._build.local_origin`).
        intensity: (n,) uint16 scanner return intensity, or None.
        classification: (n,) uint8 (ASPRS LAS classes), or None.
        quantization: the source file's integer coordinate grid
            (:class:`Quantization`), or None.
        point_fields: other per-splat fields of the source file, kept so a
            writer of the same format can put them back (LAS: GPS time,
            return numbers, scan angle, extra bytes, ...): name -> (n,) array,
            or None.
    """

    positions: np.ndarray
    u: np.ndarray
    v: np.ndarray
    colors: np.ndarray | None = None
    faces: np.ndarray | None = None
    name: str = ""
    source: str | None = field(default=None, repr=False)
    origin: np.ndarray = field(default_factory=lambda: np.zeros(3))
    intensity: Optional[np.ndarray] = field(default=None, repr=False)
    classification: Optional[np.ndarray] = field(default=None, repr=False)
    quantization: Optional[Quantization] = field(default=None, repr=False)
    point_fields: Optional[dict] = field(default=None, repr=False)
    #: the caller (a reader) has already checked every position and axis
    #: value for NaN / magnitude: the constructor's validate skips that scan
    values_checked: InitVar[bool] = False

    def __post_init__(self, values_checked: bool = False):
        src = self.source
        self.origin = np.array(self.origin, dtype=np.float64).reshape(-1)
        if self.intensity is not None:
            self.intensity = np.ascontiguousarray(self.intensity, dtype=np.uint16)
        if self.classification is not None:
            self.classification = np.ascontiguousarray(self.classification, dtype=np.uint8)
        self.positions = _as_array("positions", self.positions, (3,), np.float64, src)
        n = len(self.positions)
        self.u = _as_array("u", self.u, (3,), np.float64, src)
        self.v = _as_array("v", self.v, (3,), np.float64, src)
        for nm, arr in (("u", self.u), ("v", self.v)):
            if len(arr) != n:
                raise InputError(f"has {len(arr)} rows but positions has {n}", path=src, prop=nm)
        if self.colors is not None:
            self.colors = _as_array("colors", self.colors, (4,), np.uint8, src)
            if len(self.colors) != n:
                raise InputError(f"has {len(self.colors)} rows but positions has {n}",
                                 path=src, prop="colors")
        if self.faces is not None:
            self.faces = _as_array("faces", self.faces, (3,), np.int64, src)
        self.validate(values_checked=values_checked)

    # ------------------------------------------------------------------ checks
    def validate(self, *, values_checked: bool = False) -> None:
        """Check the invariants; raise :class:`InputError` naming the first bad row.

        Invariants: at least one splat; finite positions and axes, at most
        ``MAX_COORDINATE_ABS`` in magnitude (positions are local, after the
        ``origin`` is taken off); axes longer than ``MIN_AXIS_LENGTH_REL`` of
        the bounding-box diagonal or, where smaller, of a multiple of the
        splat's distance from the origin (:func:`min_axis_lengths`), and not
        parallel; faces index existing
        splats.  Runs over ``VALIDATE_CHUNK_ROWS`` rows at a time, so its
        temporaries stay small for 10M splats.  ``values_checked``: skip
        the NaN / magnitude scan (a reader did it column by column).
        """
        src = self.source
        n = len(self.positions)
        if n == 0:
            raise InputError("no splats (empty point set)", path=src)
        if self.origin.shape != (3,) or not (np.abs(self.origin) <= MAX_COORDINATE_ABS).all():
            raise InputError(f"origin {self.origin.tolist()} is not 3 finite numbers of at most "
                             f"{MAX_COORDINATE_ABS:g}", path=src, prop="origin")
        step = min(VALIDATE_CHUNK_ROWS, max(4096, -(-n // 8)))     # temporaries << the arrays
        for nm, arr in () if values_checked else (("positions", self.positions), ("u", self.u),
                                                  ("v", self.v)):
            # NaN propagates through max/min: the row search runs only on failure
            if arr.max() <= MAX_COORDINATE_ABS and arr.min() >= -MAX_COORDINATE_ABS:
                continue
            first_nan = first_big = None
            for lo in range(0, n, step):
                blk = arr[lo:lo + step]
                fin = np.isfinite(blk).all(axis=1)
                if first_nan is None and not fin.all():
                    first_nan = lo + int(np.flatnonzero(~fin)[0])
                with np.errstate(invalid="ignore"):
                    big = (np.abs(blk) > MAX_COORDINATE_ABS).any(axis=1)
                if first_big is None and big.any():
                    first_big = lo + int(np.flatnonzero(big)[0])
            if first_nan is not None:
                raise InputError(f"non-finite value {arr[first_nan].tolist()}", path=src,
                                 element="vertex", row=first_nan, prop=nm)
            raise InputError(f"value {arr[first_big].tolist()} beyond the supported magnitude "
                             f"{MAX_COORDINATE_ABS:g} (rescale the model)", path=src,
                             element="vertex", row=first_big, prop=nm)
        lo_c, hi_c = column_bounds(self.positions)
        diag = float(np.linalg.norm(hi_c - lo_c))
        for lo in range(0, n, step):
            bu, bv = self.u[lo:lo + step], self.v[lo:lo + step]
            min_len = min_axis_lengths(self.positions[lo:lo + step], diag)
            uu = np.einsum("ij,ij->i", bu, bu)
            vv = np.einsum("ij,ij->i", bv, bv)
            lu, lv = np.sqrt(uu), np.sqrt(vv)
            for nm, ln in (("u", lu), ("v", lv)):
                bad = ~(ln > min_len)
                if bad.any():
                    row = int(np.flatnonzero(bad)[0])
                    raise InputError(f"degenerate splat axis (length {ln[row]:.3g}, the least "
                                     f"there is {min_len[row]:.3g})", path=src,
                                     element="vertex", row=lo + row, prop=nm)
            # |u x v|^2 = |u|^2 |v|^2 - (u.v)^2 (Lagrange): no (n, 3) cross
            # product; at the 1e-6 threshold sine^2 = 1e-12 is far above the
            # 1e-16 rounding of the difference
            uv = np.einsum("ij,ij->i", bu, bv)
            sine = np.sqrt(np.maximum(1.0 - uv * uv / (uu * vv), 0.0))
            bad = ~(sine >= MIN_AXIS_SINE)     # NaN-safe: a NaN sine is degenerate too
            if bad.any():
                row = int(np.flatnonzero(bad)[0])
                raise InputError("degenerate splat: axes u and v are parallel", path=src,
                                 element="vertex", row=lo + row, prop="u")
        extra = [(f"point_fields[{k!r}]", a) for k, a in (self.point_fields or {}).items()]
        for nm, arr in [("intensity", self.intensity), ("classification", self.classification)] + extra:
            if arr is not None and len(arr) != n:
                raise InputError(f"has {len(arr)} rows but positions has {n}", path=src, prop=nm)
        if self.faces is not None and len(self.faces):
            lo, hi = int(self.faces.min()), int(self.faces.max())
            if lo < 0 or hi >= n:
                row = int(np.flatnonzero((self.faces < 0).any(1) | (self.faces >= n).any(1))[0])
                raise InputError(f"vertex index out of range 0..{n - 1}: {self.faces[row].tolist()}",
                                 path=src, element="face", row=row, prop="vertex_indices")

    # ------------------------------------------------------------- derived data
    def __len__(self) -> int:
        return len(self.positions)

    @property
    def n(self) -> int:
        """Number of splats."""
        return len(self.positions)

    @property
    def normals(self) -> np.ndarray:
        """(n, 3) float64 unit normals, ``normalize(u x v)``."""
        nrm = np.cross(self.u, self.v)
        return nrm / np.linalg.norm(nrm, axis=1, keepdims=True)

    def normals_at(self, rows) -> np.ndarray:
        """(m, 3) float64 unit normals of the splats ``rows`` (indices or a mask)."""
        nrm = np.cross(self.u[rows], self.v[rows])
        return nrm / np.linalg.norm(nrm, axis=1, keepdims=True)

    @property
    def radii(self) -> np.ndarray:
        """(n,) float64, the larger semi-axis of every splat (model units)."""
        return np.sqrt(np.maximum(np.einsum("ij,ij->i", self.u, self.u),
                                  np.einsum("ij,ij->i", self.v, self.v)))

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(min, max) corners of the axis-aligned bounding box of the centres."""
        return column_bounds(self.positions)

    @property
    def diagonal(self) -> float:
        """Length of the bounding-box diagonal (model units)."""
        lo, hi = self.bounds()
        return float(np.linalg.norm(hi - lo))

    def world_positions(self, rows=slice(None)) -> np.ndarray:
        """(m, 3) float64 centres in the file's frame (``positions + origin``;
        the positions themselves when the origin is 0, so -0.0 stays -0.0)."""
        if not self.origin.any():
            return self.positions[rows]
        return self.positions[rows] + self.origin

    def _scan_fields(self, index=None) -> dict:
        def pick(a):
            return None if a is None else (a.copy() if index is None else a[index])
        fields = (None if self.point_fields is None else
                  {k: pick(a) for k, a in self.point_fields.items()})
        return dict(origin=self.origin.copy(), intensity=pick(self.intensity),
                    classification=pick(self.classification), quantization=self.quantization,
                    point_fields=fields)

    def with_scan_fields(self, other: "SplatCloud") -> "SplatCloud":
        """This cloud with ``other``'s origin, per-splat scan attributes and
        quantization (same splats in the same order); returns self."""
        for k, val in other._scan_fields().items():
            setattr(self, k, val)
        self.validate()
        return self

    # --------------------------------------------------------------- copies
    def copy(self) -> "SplatCloud":
        return SplatCloud(self.positions.copy(), self.u.copy(), self.v.copy(),
                          None if self.colors is None else self.colors.copy(),
                          None if self.faces is None else self.faces.copy(),
                          name=self.name, source=self.source, **self._scan_fields())

    def replace(self, *, positions=None, u=None, v=None) -> "SplatCloud":
        """A new cloud with some geometry arrays replaced (colours, faces and
        name are shared, they are never modified in place)."""
        return SplatCloud(self.positions if positions is None else positions,
                          self.u if u is None else u,
                          self.v if v is None else v,
                          self.colors, self.faces, name=self.name, source=self.source,
                          origin=self.origin, intensity=self.intensity,
                          classification=self.classification, quantization=self.quantization,
                          point_fields=self.point_fields)

    def subset(self, index) -> "SplatCloud":
        """A new cloud with only the splats selected by ``index`` (mask or
        indices); faces are dropped (they would need re-indexing)."""
        return SplatCloud(self.positions[index], self.u[index], self.v[index],
                          None if self.colors is None else self.colors[index],
                          None, name=self.name, source=self.source, **self._scan_fields(index))
