"""XYZ text point clouds: ``x y z`` or ``x y z nx ny nz`` per line.

Whitespace separated; ``#`` starts a comment; blank lines are allowed.  Every
data line must have the column count of the first one (3 or 6).  A first data
line holding a single integer equal to the number of remaining data lines (the
``.pts`` point-count header) is skipped.  Write: ``x y z nx ny nz`` with 17
significant digits (positions round-trip exactly; splat sizes are not stored).
"""

from __future__ import annotations

import numpy as np

from splatedit.io._build import build_cloud, check_finite
from splatedit.io._text import point_rows
from splatedit.model.cloud import SplatCloud

_NAMES = ("x", "y", "z", "nx", "ny", "nz")


def read_xyz(path, *, progress=None) -> SplatCloud:
    """Read an XYZ file.

    Returns:
        SplatCloud; normals from the file or estimated, sizes from spacing.
    Raises:
        InputError naming the file, the 0-based data row and the 1-based line.
    """
    src = str(path)
    vals, line = point_rows(path, columns=(3, 6), expected="3 columns (x y z) or 6 (x y z nx ny nz)",
                            noun="vertices", check_count=False, progress=progress)
    ncol = vals.shape[1]
    check_finite({_NAMES[j]: vals[:, j] for j in range(ncol)}, src, None, line)
    normals = vals[:, 3:6] if ncol == 6 else None
    return build_cloud(path, np.ascontiguousarray(vals[:, :3]), normals=normals,
                       progress=progress)


def write_xyz(fh, cloud: SplatCloud) -> None:
    """Write ``x y z nx ny nz`` lines to the open binary file ``fh``."""
    np.savetxt(fh, np.hstack([cloud.world_positions(), cloud.normals]), fmt="%.17g")
