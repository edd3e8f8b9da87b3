"""What ``splatedit info`` reports of a point or splat model, held without
the full :class:`~splatedit.model.cloud.SplatCloud` where that is cheaper
(a large binary PLY: positions and splat radii only, see
:func:`splatedit.io.read_summary`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from splatedit.model.cloud import SplatCloud, column_bounds


def scan_fields_present(cloud: SplatCloud) -> dict[str, bool]:
    """Which scanner dimensions carry data: ``{"intensity": ..., "classification": ...}``,
    True only when the cloud has the dimension and it is not all zero (a LAS
    point record always holds both: a file written from a scan without them
    has zeros there)."""
    return {name: arr is not None and bool(arr.any())
            for name, arr in (("intensity", cloud.intensity), ("classification", cloud.classification))}


def scan_fields_all_zero(cloud: SplatCloud) -> list[str]:
    """The scanner dimensions the cloud holds that are all zero (``info`` lists them)."""
    return [name for name, arr in (("intensity", cloud.intensity), ("classification", cloud.classification))
            if arr is not None and not arr.any()]


@dataclass
class CloudSummary:
    """Centres, splat sizes and attribute presence of a model.

    Attributes:
        positions: (n, 3) float64 centres in local coordinates (model units;
            world = ``positions + origin``).
        radii: (n,) float64, the larger semi-axis of every splat (model units).
        origin: (3,) float64 local origin in the file's frame.
        faces: (f, 3) int64 triangles, or None.
        colors, intensity, classification: whether the model has them.
        normals_of: rows (m,) int -> (m, 3) float64 unit normals of those splats.
        cloud: the whole SplatCloud when it was read, else None.
        known_bounds: (min, max) (3,) corners of ``positions`` when the
            reader found them on the way, else None (see :meth:`bounds`).
    """

    positions: np.ndarray
    radii: np.ndarray
    origin: np.ndarray
    faces: np.ndarray | None
    colors: bool
    intensity: bool
    classification: bool
    normals_of: Callable[[np.ndarray], np.ndarray]
    cloud: SplatCloud | None = None
    known_bounds: tuple | None = None

    @property
    def n(self) -> int:
        """Number of splats."""
        return len(self.positions)

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(min, max) corners of the axis-aligned bounding box of the centres."""
        return self.known_bounds if self.known_bounds is not None else column_bounds(self.positions)

    def normals_at(self, rows) -> np.ndarray:
        """(m, 3) float64 unit normals of the splats ``rows``."""
        return self.normals_of(np.asarray(rows))

    @classmethod
    def of_cloud(cls, cloud: SplatCloud) -> "CloudSummary":
        """The summary of a cloud read whole (``cloud`` kept)."""
        present = scan_fields_present(cloud)       # held and not all zero (LAS always holds both)
        return cls(cloud.positions, cloud.radii, cloud.origin, cloud.faces, cloud.colors is not None,
                   present["intensity"], present["classification"], cloud.normals_at, cloud)
