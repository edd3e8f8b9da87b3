"""Leica PTS text: an optional point-count line, then ``x y z``,
``x y z intensity``, ``x y z r g b`` or ``x y z intensity r g b`` per line.

Intensity: PTS writers use -2048..2047 (Leica) or 0..255/0..65535; a file
with negative values is shifted by 2048.  Colours are 0..255.  Files without
colours get grey colours from the intensity.  Write: ``x y z intensity r g b``
(17 significant digits; intensity 0 and colour 255 where the cloud has none).
"""

from __future__ import annotations

import numpy as np

from splatedit.io._build import build_cloud, check_finite, colors_from_columns
from splatedit.io._text import line_error, point_rows
from splatedit.io.las import grey_from_intensity
from splatedit.model.cloud import SplatCloud

_LAYOUTS = {3: ("x", "y", "z"), 4: ("x", "y", "z", "intensity"), 6: ("x", "y", "z", "r", "g", "b"),
            7: ("x", "y", "z", "intensity", "r", "g", "b")}


def read_pts(path, *, progress=None) -> SplatCloud:
    """Read a ``.pts`` file (see the module docstring)."""
    src = str(path)
    vals, line = point_rows(path, columns=tuple(_LAYOUTS), noun="points", check_count=True,
                            expected="3, 4, 6 or 7 columns (x y z [intensity] [r g b])",
                            progress=progress)
    names = _LAYOUTS[vals.shape[1]]
    cols = {nm: vals[:, j] for j, nm in enumerate(names)}
    check_finite(cols, src, None, line)
    intensity = colors = None
    if "intensity" in cols:
        raw = cols["intensity"]
        if raw.min() < 0:
            raw = raw + 2048.0
        bad = (raw < 0) | (raw > 65535) | (raw != np.floor(raw))
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            raise line_error(f"intensity {cols['intensity'][row]:g} is not an integer in -2048..65535",
                             src, row, line[row])
        intensity = raw.astype(np.uint16)
    if "r" in cols:
        rgb = [np.rint(cols[c]).astype(np.int64) for c in "rgb"]
        colors = colors_from_columns(rgb, ["r", "g", "b"], src, None, line)
    elif intensity is not None:
        colors = grey_from_intensity(intensity)
    return build_cloud(path, np.ascontiguousarray(vals[:, :3]), colors=colors, progress=progress,
                       intensity=intensity)


def write_pts(fh, cloud: SplatCloud) -> None:
    """Write the count line and ``x y z intensity r g b`` lines to ``fh``."""
    n = cloud.n
    inten = np.zeros(n) if cloud.intensity is None else cloud.intensity.astype(np.float64)
    rgb = np.full((n, 3), 255.0) if cloud.colors is None else cloud.colors[:, :3].astype(np.float64)
    fh.write(f"{n}\n".encode("ascii"))
    np.savetxt(fh, np.column_stack([cloud.world_positions(), inten, rgb]),
               fmt=["%.17g"] * 3 + ["%d"] * 4)
