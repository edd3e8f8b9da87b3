"""The registry of file formats: one :class:`Format` record per format, and
every other part of splatedit asks it (which extensions :func:`splatedit.io.read`
and :func:`splatedit.io.write` take, which formats hold faces, which are Z-up
by definition, which the editor saves in their own format).

Adding a format is one reader/writer module and one row in :data:`FORMATS`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from splatedit.io.copc import write_copc_cloud
from splatedit.io.e57 import read_e57, write_e57
from splatedit.io.gaussians import is_gaussian_ply, read_gaussian_ply
from splatedit.io.las import read_las, write_las
from splatedit.io.off import read_off, write_off
from splatedit.io.pcd import read_pcd, write_pcd
from splatedit.io.ply import read_ply, write_ply
from splatedit.io.pts import read_pts, write_pts
from splatedit.io.ptx import read_ptx
from splatedit.io.xyz import read_xyz, write_xyz


@dataclass(frozen=True)
class Format:
    """One file format.

    Attributes:
        name: what the docs and messages call it.
        extensions: lower-case suffixes with the dot, the first the usual one.
        reader: ``reader(path, *, progress=None) -> SplatCloud`` (E57 also
            takes ``scan=``), or None for a format that is only written.
        writer: ``writer(fh, cloud, path, *, binary, axes, comment)`` writing
            to the open binary file ``fh``, or None for a read-only format.
        faces: the written file holds triangle faces.
        colours, intensity, classification, normals, splat_axes, origin:
            what of a cloud the format stores (written and read back).
        gaussians: Gaussian splatting scenes live in this format (PLY).
        z_up: coordinates are Z-up by the format's definition (scanner
            formats); the up-axis detection trusts it.
        keep_on_save: the editor saves a model read from this format in the
            same format (its scanner dimensions survive), not as PLY.
        write_extensions: the extensions the writer takes when not all of
            ``extensions`` (XYZ text is read from .txt, written as .xyz only).
    """

    name: str
    extensions: tuple[str, ...]
    reader: Callable | None
    writer: Callable | None = None
    faces: bool = False
    colours: bool = False
    intensity: bool = False
    classification: bool = False
    normals: bool = False
    splat_axes: bool = False
    origin: bool = False
    gaussians: bool = False
    z_up: bool = False
    keep_on_save: bool = False
    write_extensions: tuple[str, ...] | None = None

    @property
    def writes(self) -> tuple[str, ...]:
        """The extensions :func:`splatedit.io.write` takes for this format."""
        if self.writer is None:
            return ()
        return self.extensions if self.write_extensions is None else self.write_extensions


def _read_ply(path, *, progress=None):
    """A PLY: Gaussian splatting PLYs (sniffed from the header) give their
    proxy splats, anything else our splat / point / mesh reader."""
    if is_gaussian_ply(path):
        return read_gaussian_ply(path, progress=progress).proxy_splats()
    return read_ply(path, progress=progress)


def _write_ply(fh, cloud, path, *, binary, axes, comment):
    write_ply(fh, cloud, binary=binary, axes=axes, comment=comment)


def _write_las(fh, cloud, path, *, binary, axes, comment):
    write_las(fh, cloud, path, compress=Path(path).suffix.lower() == ".laz")


def _write_copc(fh, cloud, path, *, binary, axes, comment):
    write_copc_cloud(fh, cloud, path)


def _write_e57(fh, cloud, path, *, binary, axes, comment):
    write_e57(fh, cloud, path)


def _plain(writer):
    """A writer ``writer(fh, cloud)`` in the registry's signature."""
    def write(fh, cloud, path, *, binary, axes, comment):
        writer(fh, cloud)
    write.__doc__ = writer.__doc__
    return write


#: every format, in the order the extension lists give them
FORMATS: tuple[Format, ...] = (
    Format("PLY (splatedit's lossless splats, meshes, Gaussian splats)", (".ply",), _read_ply, _write_ply,
           faces=True, colours=True, normals=True, splat_axes=True, origin=True, gaussians=True),
    Format("XYZ text", (".xyz", ".txt"), read_xyz, _plain(write_xyz), normals=True,
           write_extensions=(".xyz",)),
    Format("Leica PTS", (".pts",), read_pts, _plain(write_pts), colours=True, intensity=True),
    Format("OFF mesh", (".off",), read_off, _plain(write_off), faces=True),
    # before LAS/LAZ: a '.copc.laz' name is COPC (see suffix_of); COPC files are
    # read whole by the LAS reader (a COPC file is a LAZ 1.4 file); out of core
    # by splatedit.io.copc.CopcFile
    Format("COPC (cloud-optimized point cloud: LAZ 1.4 in octree order)", (".copc.laz",), read_las,
           _write_copc, colours=True, intensity=True, classification=True, origin=True, z_up=True,
           keep_on_save=True),
    Format("LAS/LAZ", (".las", ".laz"), read_las, _write_las, colours=True, intensity=True,
           classification=True, origin=True, z_up=True, keep_on_save=True),
    Format("E57", (".e57",), read_e57, _write_e57, colours=True, intensity=True, origin=True,
           z_up=True, keep_on_save=True),
    Format("PCD", (".pcd",), read_pcd, _plain(write_pcd), colours=True, intensity=True, normals=True),
    Format("Leica PTX", (".ptx",), read_ptx, colours=True, intensity=True),
)

_BY_EXT = {ext: f for f in FORMATS for ext in f.extensions}


#: suffixes of two parts ('.copc.laz'), tried before the last suffix alone
_DOUBLE = tuple(ext for ext in _BY_EXT if ext.count(".") > 1)


def suffix_of(path) -> str:
    """The format suffix of ``path``, lower case: a registered two-part
    suffix (``.copc.laz``) when the name ends with one, else the last
    suffix (``.laz``)."""
    name = Path(str(path)).name.lower()
    for ext in _DOUBLE:
        if name.endswith(ext) and len(name) > len(ext):
            return ext
    return Path(name).suffix


def by_extension(ext: str) -> Format | None:
    """The format of suffix ``ext`` (".las", any case), or None."""
    return _BY_EXT.get(ext.lower())


def format_of(path) -> Format | None:
    """The format of ``path`` by its suffix (case-insensitive, see
    :func:`suffix_of`), or None."""
    return by_extension(suffix_of(path))


def extensions(**capabilities: bool) -> tuple[str, ...]:
    """The extensions of the formats whose capabilities match, e.g.
    ``extensions(faces=True)``; ``readable`` / ``writable`` select formats
    with a reader / writer."""
    readable = capabilities.pop("readable", None)
    writable = capabilities.pop("writable", None)
    out = []
    for f in FORMATS:
        if readable is not None and (f.reader is not None) != readable:
            continue
        if writable is not None and (f.writer is not None) != writable:
            continue
        if all(getattr(f, k) == v for k, v in capabilities.items()):
            out.extend(f.writes if writable else f.extensions)
    return tuple(out)


def is_z_up(path) -> bool:
    """True when ``path``'s format is Z-up by definition (LAS/LAZ, E57)."""
    f = None if path is None else format_of(path)
    return f is not None and f.z_up
