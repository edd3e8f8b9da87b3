"""``splatedit info`` of a large binary PLY with splat axes: one pass
through the body keeping the centres and the splat radii only (320 MB at
10M splats instead of the 720 MB of positions and axes), with the checks
:class:`~splatedit.model.cloud.SplatCloud` makes; normals of the few
sampled splats are read back from the file afterwards."""

from __future__ import annotations

import numpy as np

from splatedit.errors import InputError
from splatedit.io._build import check_extent, colors_from_columns, local_origin, rebase
from splatedit.io._plybinary import (AXIS_FIELDS, columns_view, grow_bounds, body_chunks, in_range,
                                     vertex_columns)
from splatedit.model.summary import CloudSummary
from splatedit.progress import report
from splatedit.tolerances import MAX_COORDINATE_ABS, MIN_AXIS_LENGTH_REL, MIN_AXIS_SINE


def _triple(buf, rec, dtype, names, m) -> np.ndarray:
    """(m, k) float64 of k properties of the chunk (a strided view where
    the file lays them out consecutively as doubles, else a copy)."""
    view = columns_view(buf, dtype, names, m)
    if view is not None and view.dtype == np.float64:
        return view
    return np.column_stack([rec[p] for p in names]).astype(np.float64, copy=False)


def read_ply_summary(path, layout, progress=None, stored_origin=None) -> CloudSummary | None:
    """A :class:`CloudSummary` of a binary PLY with our splat axes ``ux..vz``
    (``layout`` from :func:`splatedit.io._plycheck.binary_layout`).

    Returns:
        the summary (``cloud`` None), or None when the file is not of that
        kind (no axes, float colours) or any value fails a check (NaN,
        magnitude, degenerate axes, colours out of range): the full reader
        then reads it and names the row at fault.
    """
    src = str(path)
    spec = vertex_columns(layout, src)
    body, n, dtype = layout
    if spec.colors and not spec.int_colors:
        return None
    if not spec.axes:
        if spec.normals and "radius" in spec.names:
            return _normals_radius_summary(path, layout, spec, progress, stored_origin)
        return None
    # x y z, the axes and the normals are checked through their bounds and
    # squared lengths (a NaN or a value beyond MAX_COORDINATE_ABS makes a
    # squared length NaN or above MAX_COORDINATE_ABS^2); the rest column by column
    vectors = ("x", "y", "z") + AXIS_FIELDS + (spec.normals or ())
    others = [p for p in spec.checked if p not in vectors]
    others += [p for p in ("intensity", "classification") if p in spec.names and dtype[p].kind == "f"]
    limit2 = MAX_COORDINATE_ABS ** 2
    positions = np.empty((n, 3))
    radii = np.empty(n)
    lo_b, hi_b = np.full(3, np.inf), np.full(3, -np.inf)
    shortest = np.inf           # squared length of the shortest axis
    axes_buf = None
    for lo, hi, buf in body_chunks(path, layout):
        m = hi - lo
        rec = np.frombuffer(buf, dtype=dtype, count=m)
        if axes_buf is None:
            axes_buf = np.empty((m, 6))
        blk = positions[lo:hi]
        blk[...] = _triple(buf, rec, dtype, ("x", "y", "z"), m)
        # one aligned copy of the axes (the file's 84-byte records leave
        # doubles unaligned: numpy's reductions on them ran 1.7x slower)
        axes = axes_buf[:m]
        axes[...] = _triple(buf, rec, dtype, AXIS_FIELDS, m)
        u, v = axes[:, :3], axes[:, 3:]
        uu = np.einsum("ij,ij->i", u, u)
        vv = np.einsum("ij,ij->i", v, v)
        ok = grow_bounds(blk, lo_b, hi_b) and uu.max() <= limit2 and vv.max() <= limit2
        if ok and spec.normals:
            nrm = columns_view(buf, dtype, spec.normals, m)
            nrm = np.column_stack([rec[p] for p in spec.normals]) if nrm is None else nrm
            ok = bool(np.einsum("ij,ij->i", nrm, nrm).max() <= limit2)
        if not (ok and all(in_range(rec[p]) for p in others)):
            return None
        # SplatCloud.validate's sine of the axes' angle >= MIN_AXIS_SINE, as
        # (u.v)^2 <= (1 - MIN_AXIS_SINE^2) |u|^2 |v|^2 (no division)
        uv = np.einsum("ij,ij->i", u, v)
        uv *= uv
        both = uu * vv
        both *= 1.0 - MIN_AXIS_SINE ** 2
        if not (uv <= both).all():
            return None
        shortest = min(shortest, float(uu.min()), float(vv.min()))
        np.maximum(uu, vv, out=uu)
        np.sqrt(uu, out=radii[lo:hi])
        if spec.colors:
            try:
                colors_from_columns([rec[p] for p in spec.colors], spec.colors, src)
            except InputError:
                return None
        del rec
        report(progress, "reading", hi / n)
    def normals_of(rec) -> np.ndarray:
        u = np.column_stack([rec[p] for p in AXIS_FIELDS[:3]]).astype(np.float64)
        v = np.column_stack([rec[p] for p in AXIS_FIELDS[3:]]).astype(np.float64)
        return np.cross(u, v)

    return _summary(path, layout, spec, positions, radii, (lo_b, hi_b), float(np.sqrt(shortest)),
                    stored_origin, normals_of)


def _summary(path, layout, spec, positions, radii, box, smallest_axis: float, stored_origin,
             normals_of_records) -> CloudSummary | None:
    """The common end of both lean passes: the smallest splat axis checked
    against the diagonal (None: the full reader names the row), the extent
    checked, the positions rebased, the summary built.  ``normals_of_records``
    turns rows of the file's records into (m, 3) normals (any length)."""
    body, n, dtype = layout
    lo_b, hi_b = box
    diag = float(np.linalg.norm(hi_b - lo_b))
    if not smallest_axis > MIN_AXIS_LENGTH_REL * max(diag, 1e-300):
        return None
    check_extent(lo_b, hi_b, path)
    origin = local_origin(positions, bounds=(lo_b, hi_b), stored=stored_origin)
    positions = rebase(positions, origin)

    def normals_of(rows: np.ndarray) -> np.ndarray:
        mm = np.memmap(path, dtype=dtype, mode="r", offset=body, shape=(n,))
        nrm = normals_of_records(mm[rows])
        del mm
        return nrm / np.linalg.norm(nrm, axis=1, keepdims=True)

    names = spec.names
    # rounding is monotonic: the rebased extremes are the extremes rebased
    bounds = (lo_b - origin, hi_b - origin) if origin.any() else (lo_b, hi_b)
    return CloudSummary(positions, radii, origin, None, bool(spec.colors), "intensity" in names,
                        "classification" in names, normals_of, known_bounds=bounds)


def _normals_radius_summary(path, layout, spec, progress, stored_origin) -> CloudSummary | None:
    """:func:`read_ply_summary` of a binary PLY holding normals and a radius
    per point (as scanner pipelines and Open3D write them): the radii are the
    file's, nothing is estimated; None when a value fails a check (a zero or
    non-finite normal, a radius not > 0) so that the full reader names the row
    or fills the normal."""
    src = str(path)
    body, n, dtype = layout
    vectors = ("x", "y", "z") + spec.normals + ("radius",)
    others = [p for p in spec.checked if p not in vectors]
    others += [p for p in ("intensity", "classification") if p in spec.names and dtype[p].kind == "f"]
    limit2 = MAX_COORDINATE_ABS ** 2
    positions = np.empty((n, 3))
    radii = np.empty(n)
    lo_b, hi_b = np.full(3, np.inf), np.full(3, -np.inf)
    smallest = np.inf
    for lo, hi, buf in body_chunks(path, layout):
        m = hi - lo
        rec = np.frombuffer(buf, dtype=dtype, count=m)
        blk = positions[lo:hi]
        blk[...] = _triple(buf, rec, dtype, ("x", "y", "z"), m)
        r = radii[lo:hi]
        r[...] = rec["radius"]
        nrm = _triple(buf, rec, dtype, spec.normals, m)
        nn = np.einsum("ij,ij->i", nrm, nrm)
        # NaN fails every comparison below, so a NaN anywhere returns None
        ok = (grow_bounds(blk, lo_b, hi_b) and (nn > 0).all() and (nn <= limit2).all()
              and (r > 0).all() and (r <= MAX_COORDINATE_ABS).all())
        if not (ok and all(in_range(rec[p]) for p in others)):
            return None
        smallest = min(smallest, float(r.min()))
        if spec.colors:
            try:
                colors_from_columns([rec[p] for p in spec.colors], spec.colors, src)
            except InputError:
                return None
        del rec
        report(progress, "reading", hi / n)
    return _summary(path, layout, spec, positions, radii, (lo_b, hi_b), smallest, stored_origin,
                    lambda rec: np.column_stack([rec[p] for p in spec.normals]).astype(np.float64))
