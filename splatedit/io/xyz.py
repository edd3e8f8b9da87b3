"""XYZ text point clouds: ``x y z`` or ``x y z nx ny nz`` per line.

Whitespace separated; ``#`` starts a comment; blank lines are allowed.  Every
data line must have the column count of the first one (3 or 6).  A first data
line holding a single integer equal to the number of remaining data lines (the
``.pts`` point-count header) is skipped.  Write: ``x y z nx ny nz`` with 17
significant digits (positions round-trip exactly; splat sizes are not stored).
"""

from __future__ import annotations

import numpy as np

from splatedit.errors import InputError
from splatedit.io._build import build_cloud, check_finite
from splatedit.io._text import read_bytes, scan_numbers
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
    tab = scan_numbers(read_bytes(path), src, progress=progress)
    if len(tab) == 0:
        raise InputError("empty file: no data lines (zero vertices)", path=src)
    start = 0
    if tab.count[0] == 1 and len(tab) > 1:
        val = tab.values[tab.start[0]]
        if val == len(tab) - 1:
            start = 1
    count, line = tab.count[start:], tab.line[start:]
    ncol = int(count[0])
    if ncol not in (3, 6):
        err = InputError(f"expected 3 columns (x y z) or 6 (x y z nx ny nz), got {ncol} "
                         f"(line {line[0]})", path=src, row=0)
        err.line = int(line[0])
        raise err
    bad = count != ncol
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        err = InputError(f"wrong column count: expected {ncol} like line {line[0]}, got "
                         f"{count[row]} (line {line[row]})", path=src, row=row)
        err.line = int(line[row])
        raise err
    vals = tab.values[tab.start[start]:].reshape(-1, ncol)
    check_finite({_NAMES[j]: vals[:, j] for j in range(ncol)}, src, None, line)
    normals = vals[:, 3:6] if ncol == 6 else None
    return build_cloud(path, np.ascontiguousarray(vals[:, :3]), normals=normals,
                       progress=progress)


def write_xyz(fh, cloud: SplatCloud) -> None:
    """Write ``x y z nx ny nz`` lines to the open binary file ``fh``."""
    np.savetxt(fh, np.hstack([cloud.world_positions(), cloud.normals]), fmt="%.17g")
