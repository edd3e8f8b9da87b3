"""Converting any readable file into COPC, and the cache of conversions
(the formats the registry reads, :mod:`splatedit.io.formats`; the COPC
writing itself is :mod:`splatedit.io.copc`).  A module of its own because it
reads through :func:`splatedit.io.read`, whose package imports the registry,
which imports :mod:`splatedit.io.copc` for its COPC writer."""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numpy as np

from splatedit.errors import InputError
from splatedit.io.copc import (LEAF_POINTS, NODE_POINTS, WriteReport, build_copc, is_copc, las_records,
                               write_copc)


def convert_to_copc(src_path, dst_path, progress=None, *, chunk_points: int = 2_000_000,
                    node_points: int = NODE_POINTS, leaf_points: int = LEAF_POINTS) -> WriteReport:
    """Convert any file :func:`splatedit.io.read` reads into COPC.

    LAS/LAZ is streamed (laspy's chunk iterator, ``chunk_points`` at a
    time; the file's scale, offset, integers, returns, classes, GPS times
    and RGB are kept; point format 7 when the file has RGB, else 6, 8 when
    it has NIR); a COPC source is laid out anew the same way.  Other formats
    are read whole (they are held in memory anyway) and written with
    :func:`write_copc`: positions on a grid of ``LAS_DEFAULT_SCALE``, RGB
    colours and intensity.
    """
    src = str(src_path)
    suffix = Path(src).suffix.lower()
    if suffix in (".las", ".laz"):
        from splatedit.io.las import check_las_header
        check_las_header(src_path)
        import laspy
        from splatedit.io._guard import library_call
        with library_call(src, "not a readable LAS/LAZ file"):
            with laspy.open(src) as rd:
                hdr = rd.header
                names = set(hdr.point_format.dimension_names)
                fmt = 8 if "nir" in names else 7 if {"red", "green", "blue"} <= names else 6
                scale, offset = np.asarray(hdr.scales, float), np.asarray(hdr.offsets, float)
                mins, maxs = np.asarray(hdr.mins, float), np.asarray(hdr.maxs, float)
                crs = [(v.user_id.encode(), v.record_id, v.description.encode() if isinstance(v.description, str)
                        else bytes(v.description), bytes(v.record_data_bytes()))
                       for v in hdr.vlrs if v.user_id in ("LASF_Projection",)]

        def chunks():
            with library_call(src, "not a readable LAS/LAZ file"):
                with laspy.open(src) as rd:
                    for pts in rd.chunk_iterator(chunk_points):
                        yield las_records(pts, fmt)

        # the header's box may be stale; a pass over the points is cheap next to compression
        return build_copc(dst_path, chunks, point_format=fmt, scale=scale, offset=offset,
                          mins=mins, maxs=maxs, node_points=node_points, leaf_points=leaf_points,
                          vlrs=crs, progress=progress, count=int(hdr.point_count))
    from splatedit.io import read
    cloud = read(src, progress=progress)
    xyz = cloud.positions.astype(np.float64) + np.asarray(cloud.origin, np.float64)
    colour = None if cloud.colors is None else np.asarray(cloud.colors)[:, :3]
    return write_copc(dst_path, xyz, colour, cloud.intensity, progress=progress,
                      node_points=node_points, leaf_points=leaf_points)


def cache_dir() -> Path:
    """``$XDG_CACHE_HOME/splatedit/copc`` (default ``~/.cache``)."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "splatedit" / "copc"


def cached_copc(src_path, progress=None) -> Path:
    """A COPC file of ``src_path``: the file itself when it is COPC, else its
    conversion (:func:`convert_to_copc`), made once into :func:`cache_dir`
    under a hash of the resolved path, size and modification time (a changed
    file gets a new conversion)."""
    p = Path(src_path)
    if is_copc(p):
        return p
    try:
        st = p.stat()
    except OSError as exc:
        raise InputError(f"cannot read file: {exc.strerror or exc}", path=str(p)) from None
    h = hashlib.sha256(f"{p.resolve()}\0{st.st_size}\0{st.st_mtime_ns}".encode()).hexdigest()[:24]
    out = cache_dir() / f"{h}.copc.laz"
    if out.exists():
        return out
    out.parent.mkdir(parents=True, exist_ok=True)
    convert_to_copc(p, out, progress=progress)
    return out
