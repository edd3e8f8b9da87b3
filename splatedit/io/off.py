"""OFF meshes (Geomview Object File Format).

Header keyword ``OFF`` with optional prefixes ``C`` (vertex colours, 3 or 4
values after the coordinates, 0..1 floats or 0..255 integers) and ``N``
(vertex normals), then ``nv nf ne`` (on the keyword line or the next), then
``nv`` vertex lines and ``nf`` face lines ``k i_1 .. i_k [colour]``.
Polygons are fan-triangulated.  ``#`` comments and blank lines are allowed.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from splatedit.errors import InputError
from splatedit.io._build import check_finite, colors_from_columns, local_origin, rebase, triangulate
from splatedit.io._text import read_bytes, scan_numbers
from splatedit.model.cloud import SplatCloud

_KEYWORD = re.compile(r"^(C?)(N?)OFF$")


def _error(msg, path, line=None, **kw) -> InputError:
    if line is not None:
        msg = f"{msg} (line {line})"
    err = InputError(msg, path=path, **kw)
    err.line = line
    return err


def _next_line(data: bytes, pos: int):
    """Tokens of the next line (comment stripped) and the position after it."""
    end = data.find(b"\n", pos)
    end = len(data) if end < 0 else end + 1
    return data[pos:end].split(b"#", 1)[0].decode("latin-1").split(), end


def _header(data: bytes, path):
    """Keyword flags, nv, nf, and the byte offset and line count of the header.

    The counts ``nv nf [ne]`` follow the keyword on its own line or on the
    next non-blank line.
    """
    pos, lineno, keyword, words = 0, 0, None, []
    while not words:
        if pos >= len(data):
            if keyword is None:
                raise _error("empty file: no OFF header (zero vertices)", path)
            raise _error("header ends before the counts 'nv nf ne'", path, lineno)
        words, pos = _next_line(data, pos)
        lineno += 1
        if words and keyword is None:
            keyword = _KEYWORD.match(words[0])
            if not keyword:
                raise _error(f"not an OFF file: expected 'OFF' (or COFF, NOFF, CNOFF), "
                             f"got {words[0]!r}", path, lineno)
            words = words[1:]
    if len(words) not in (2, 3):
        raise _error(f"expected the counts 'nv nf ne', got {' '.join(words)!r}", path, lineno)
    try:
        counts = [int(w) for w in words]
    except ValueError:
        raise _error(f"counts must be integers, got {' '.join(words)!r}", path, lineno) from None
    if min(counts) < 0:
        raise _error(f"negative count in {' '.join(words)!r}", path, lineno)
    return bool(keyword.group(1)), bool(keyword.group(2)), counts[0], counts[1], pos, lineno


def read_off(path, *, progress=None) -> SplatCloud:
    """Read an OFF mesh as vertex splats with faces (see
    :func:`splatedit.model.mesh.cloud_from_mesh`).

    Raises:
        InputError naming the file and line for wrong counts, truncation,
        non-numeric tokens, NaN/inf and out-of-range face indices.
    """
    src = str(path)
    data = read_bytes(path)
    has_color, has_normal, nv, nf, body, nlines = _header(data, src)
    if nv == 0:
        raise _error("zero vertices", src, element="vertex")
    tab = scan_numbers(data[body:], src, first_line=nlines + 1, progress=progress)
    if len(tab) < nv + nf:
        raise _error(f"truncated: header announces {nv} vertices and {nf} faces but only "
                     f"{len(tab)} data lines follow", src)
    if len(tab) > nv + nf:
        raise _error(f"{len(tab) - nv - nf} data lines after the last face: wrong counts "
                     f"'{nv} {nf}' in the header?", src, int(tab.line[nv + nf]))
    # vertices
    base = 6 if has_normal else 3
    vcount = tab.count[:nv]
    ok = (vcount == base) if not has_color else ((vcount == base + 3) | (vcount == base + 4))
    if not ok.all():
        row = int(np.flatnonzero(~ok)[0])
        want = f"{base}" if not has_color else f"{base + 3} or {base + 4}"
        raise _error(f"vertex line has {vcount[row]} numbers, expected {want}", src,
                     int(tab.line[row]), element="vertex", row=row)
    vstart = tab.start[:nv]
    cols = {p: tab.values[vstart + j] for j, p in enumerate(("x", "y", "z"))}
    if has_normal:
        cols.update({p: tab.values[vstart + 3 + j] for j, p in enumerate(("nx", "ny", "nz"))})
    check_finite(cols, src, "vertex", tab.line[:nv])
    positions = np.column_stack([cols["x"], cols["y"], cols["z"]])
    normals = np.column_stack([cols["nx"], cols["ny"], cols["nz"]]) if has_normal else None
    colors = None
    if has_color:
        names = ["red", "green", "blue", "alpha"]
        ccols = [tab.values[vstart + base + j] for j in range(3)]
        alpha_at = np.minimum(vstart + base + 3, len(tab.values) - 1)
        has_alpha = vcount == base + 4
        ccols.append(np.where(has_alpha, tab.values[alpha_at], 0.0))
        check_finite(dict(zip(names, ccols)), src, "vertex", tab.line[:nv])
        big = max(float(c.max()) for c in ccols) > 1.0
        ccols[3] = np.where(has_alpha, ccols[3], 255.0 if big else 1.0)
        colors = colors_from_columns(ccols, names, src, "vertex", tab.line[:nv])
    # faces
    fstart, fcount, fline = tab.start[nv:], tab.count[nv:], tab.line[nv:]
    k = tab.values[fstart] if nf else np.zeros(0)
    finite = np.isfinite(k)
    bad = ~finite | (k != np.floor(k)) | (k < 3) | (fcount < k + 1) | (fcount > k + 5)
    if bad.any():
        row = int(np.flatnonzero(bad)[0])
        if not finite[row] or k[row] != np.floor(k[row]) or k[row] < 3:
            msg = f"face vertex count must be an integer >= 3, got {k[row]:g}"
        else:
            msg = f"face line has {fcount[row] - 1} numbers after its count {int(k[row])}"
        raise _error(msg, src, int(fline[row]), element="face", row=row)
    k = k.astype(np.int64)
    tot = int(k.sum())
    kstart = np.zeros(nf, dtype=np.int64)
    np.cumsum(k[:-1], out=kstart[1:])
    owner = np.repeat(np.arange(nf), k)
    flat = tab.values[fstart[owner] + 1 + (np.arange(tot) - kstart[owner])]
    nonint = flat != np.floor(flat)
    if nonint.any():
        row = int(owner[np.flatnonzero(nonint)[0]])
        raise _error("face vertex index is not an integer", src, int(fline[row]),
                     element="face", row=row)
    faces = triangulate(flat, k, nv, src, "face", "vertex_indices", fline)
    origin = local_origin(positions)
    from splatedit.model.mesh import cloud_from_mesh
    cloud = cloud_from_mesh(rebase(positions, origin), faces, normals=normals, colors=colors,
                            name=Path(path).name, source=src, progress=progress)
    cloud.origin = origin
    return cloud


def write_off(fh, cloud: SplatCloud) -> None:
    """Write the mesh (positions and faces; a cloud without faces gives an
    OFF with zero faces) to the open binary file ``fh``."""
    faces = cloud.faces if cloud.faces is not None else np.zeros((0, 3), dtype=np.int64)
    fh.write(f"OFF\n{cloud.n} {len(faces)} 0\n".encode("ascii"))
    np.savetxt(fh, cloud.world_positions(), fmt="%.17g")
    np.savetxt(fh, faces, fmt="3 %d %d %d")
