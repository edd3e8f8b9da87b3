"""Which world axis is "up" for a model (for the editor's numpad views).

Scans are often Z-up (scanner and GIS formats, many photogrammetry tools)
while meshes from graphics tools are Y-up.  :func:`detect_up_axis` decides
from, in order:

1. the file: a PLY header comment naming the up axis (``comment up_axis
   Z``, ``comment Z-up``, ``comment up: -y`` ...: :func:`header_up_hint`),
   else the format: LAS/LAZ and E57 are defined in a Z-up frame
   (georeferenced / scanner coordinates) -> +Z;
2. a ground signal in the model: a floor (or terrain, a flat underside):
   many normals facing one signed axis whose points lie in a thin band at
   the bottom of the model along that axis (a one-sided scan taken from
   one side has many normals facing the scanner too, but spread over the
   whole depth: that is no floor), and the model is not tallest along it;
3. a standing shape: a model ``UP_AXIS_TALL_Z_RATIO`` times taller along Z
   than along X and Y (a figure exported from a Z-up tool) -> +Z;
4. otherwise +Y (the graphics convention of PLY / OFF / OBJ meshes: the
   Stanford models, the bundled bunny).
"""

from __future__ import annotations

import enum
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from splatedit.tolerances import (FRONT_VIEW_Z_UP_COS, UP_AXIS_ALIGNED_COS, UP_AXIS_FLOOR_BAND,
                                  UP_AXIS_FLOOR_MIN_IN_BAND, UP_AXIS_GROUND_MIN_FRACTION, UP_AXIS_SAMPLE,
                                  UP_AXIS_TALL_Z_RATIO)

class UpSource(enum.Enum):
    """Where a model's up axis came from (shown to the user beside the axis)."""
    FILE_HEADER = "file header"
    FILE_FORMAT = "file format"
    GROUND = "ground normals"
    SHAPE = "tall along Z"
    DEFAULT = "default"
    USER = "set by the user"


@dataclass(frozen=True)
class UpAxis:
    """A signed world axis: ``axis`` 0/1/2 (X/Y/Z), ``sign`` +1/-1."""
    axis: int
    sign: int
    source: UpSource = UpSource.DEFAULT

    @property
    def vector(self) -> np.ndarray:
        """(3,) float64 unit vector."""
        v = np.zeros(3)
        v[self.axis] = float(self.sign)
        return v

    @property
    def label(self) -> str:
        return ("+" if self.sign > 0 else "-") + "XYZ"[self.axis]


#: the order U cycles through
CYCLE = ((1, 1), (2, 1), (0, 1), (1, -1), (2, -1), (0, -1))


def next_up(current: UpAxis) -> UpAxis:
    """The up axis after ``current`` in :data:`CYCLE` (set by the user)."""
    i = CYCLE.index((current.axis, current.sign)) if (current.axis, current.sign) in CYCLE else -1
    a, s = CYCLE[(i + 1) % len(CYCLE)]
    return UpAxis(a, s, UpSource.USER)


#: "up_axis Z", "up: -y", "upaxis=+Z"  /  "Z-up", "z_up", "+Y up"
_UP_FIRST = re.compile(r"\bup[ _-]?(?:axis|vector|direction)?\s*[:= ]\s*([+-]?)([xyz])\b", re.I)
_AXIS_FIRST = re.compile(r"(?<![\w+-])([+-]?)([xyz])[ _-]?up\b", re.I)
#: a PLY header is read up to this many bytes (end_header comes much earlier)
_HEADER_BYTES = 65536


def header_up_hint(path) -> UpAxis | None:
    """The up axis a PLY file's header comments name, or None (not a PLY,
    unreadable, or no such comment)."""
    p = Path(path)
    if p.suffix.lower() != ".ply":
        return None
    try:
        with open(p, "rb") as f:
            head = f.read(_HEADER_BYTES)
    except OSError:
        return None
    text = head.split(b"end_header", 1)[0].decode("ascii", "replace")
    for line in text.splitlines():
        words = line.split(None, 1)
        if len(words) < 2 or words[0] not in ("comment", "obj_info"):
            continue
        m = _UP_FIRST.search(words[1]) or _AXIS_FIRST.search(words[1])
        if m:
            return UpAxis("xyz".index(m.group(2).lower()), -1 if m.group(1) == "-" else 1, UpSource.FILE_HEADER)
    return None


def detect_up_axis(normals: np.ndarray, positions: np.ndarray, path=None, *,
                   z_up_format: bool = False) -> UpAxis:
    """The up axis of a model.

    Args:
        normals: (n, 3) float64 unit normals (zero rows allowed).
        positions: (n, 3) float64, model units.
        path: the file the model came from (its header may name the up
            axis), or None.
        z_up_format: the file's format is Z-up by definition (the callers
            ask :func:`splatedit.io.formats.is_z_up`; model sits below io).
    """
    if path is not None:
        hint = header_up_hint(path)
        if hint is not None:
            return hint
    if z_up_format:
        return UpAxis(2, 1, UpSource.FILE_FORMAT)
    n = np.asarray(normals, float)
    p = np.asarray(positions, float)
    if len(n) and len(p):
        lo, hi = p.min(0), p.max(0)
        extent = hi - lo
        best = None                                             # (count, axis, sign)
        for k in range(3):
            if not extent[k] < extent.max() or extent[k] <= 0.0:
                continue
            for sign in (1, -1):
                facing = n[:, k] * sign >= UP_AXIS_ALIGNED_COS
                count = int(facing.sum())
                if count < UP_AXIS_GROUND_MIN_FRACTION * len(n):
                    continue
                height = (p[facing, k] - lo[k]) if sign > 0 else (hi[k] - p[facing, k])
                in_band = float(np.mean(height <= UP_AXIS_FLOOR_BAND * extent[k]))
                if in_band >= UP_AXIS_FLOOR_MIN_IN_BAND and (best is None or count > best[0]):
                    best = (count, k, sign)
        if best is not None:
            return UpAxis(best[1], best[2], UpSource.GROUND)
        if extent[2] > 0 and extent[2] >= UP_AXIS_TALL_Z_RATIO * max(extent[0], extent[1]):
            return UpAxis(2, 1, UpSource.SHAPE)
    return UpAxis(1, 1, UpSource.DEFAULT)


def detect_cloud_up_axis(cloud, path=None, *, z_up_format: bool = False) -> UpAxis:
    """:func:`detect_up_axis` of a :class:`~splatedit.model.cloud.SplatCloud`:
    the file's word first (no normals needed), else the floor rule on every
    ``n // UP_AXIS_SAMPLE``-th splat (its tests are shares of points, which a
    sample of that size gives to well under a percent; the normals of all
    10M splats alone cost 2.8 s)."""
    hint = detect_up_axis(np.zeros((0, 3)), np.zeros((0, 3)), path, z_up_format=z_up_format)
    if hint.source is not UpSource.DEFAULT:
        return hint
    step = max(1, -(-cloud.n // UP_AXIS_SAMPLE))
    rows = slice(0, cloud.n, step)
    return detect_up_axis(cloud.normals_at(rows), cloud.positions[rows], path)


def front_direction(up) -> np.ndarray:
    """(3,) float64 unit vector from a model's centre towards the eye of its
    front view about the up vector ``up`` (3,): horizontal (perpendicular
    to ``up``), towards +Z for a Y-up model, towards -Y for a Z-up one (the
    front of a Z-up scan faces -Y: X right, Z up on screen, like Blender's
    front view).  The editor's first view (yaw 0, pitch 0) and ``splatedit
    render``'s default camera both look along minus this."""
    u = np.asarray(up, dtype=np.float64)
    u = u / np.abs(u).max()             # unit-size first: |up| of 1e-300 must not underflow
    u = u / np.linalg.norm(u)
    ref = np.array([0.0, 0.0, 1.0]) if abs(u[2]) < FRONT_VIEW_Z_UP_COS else np.array([0.0, -1.0, 0.0])
    ref = ref - u * (ref @ u)
    return ref / np.linalg.norm(ref)
