"""Reading and writing splat clouds: PLY, XYZ text, OFF meshes, and the
scanner formats LAS/LAZ, E57, PCD and PTS.

Public API::

    read(path, *, progress=None) -> SplatCloud
    read_columns(path, *, progress=None) -> PointColumns   (read() before splats are derived)
    cloud_from_columns(columns, *, progress=None) -> SplatCloud
    write(path, cloud, *, overwrite=False, binary=True, axes=True, progress=None) -> Path
    convert(in_path, out_path, *, overwrite=False, binary=True, progress=None) -> SplatCloud
    is_gaussian_file(path) -> bool
    read_gaussians(path, *, progress=None) -> GaussianCloud
    write_gaussians(path, scene, *, overwrite=False, progress=None) -> Path

The format follows the file extension (case-insensitive), looked up in the
registry :data:`splatedit.io.formats.FORMATS` (its readers, writers and
capabilities): ``.ply``; ``.xyz``, ``.txt`` (XYZ text); ``.off``; ``.las``,
``.laz``; ``.e57`` (one scan by index: ``file.e57#2``); ``.pcd``; ``.pts``
(Leica); and the formats added there since.  Splats come from the file
(our ``ux..vz`` PLY properties) or are derived: see
:func:`splatedit.io._build.build_cloud`.  Every problem with an input file is
an :class:`~splatedit.errors.InputError` naming the file.

Gaussian splatting PLYs (3DGS/2DGS, see :mod:`splatedit.io.gaussians`) are
read losslessly by :func:`read_gaussians`; :func:`read` gives their proxy
splats (a disc per Gaussian, :meth:`GaussianCloud.proxy_splats`), so every
splat tool can open them.

Writing is atomic: the data go to a temporary file in the target directory
that replaces the target only when complete, so a failed write leaves any old
file intact.  An existing file is replaced only with ``overwrite=True``.
"""

from __future__ import annotations

import contextlib
import os
import stat
from pathlib import Path

from splatedit.errors import InputError
from splatedit.io._build import PointColumns, cloud_from_columns, columns_only
from splatedit.atomic import atomic_open, check_writable_target
from splatedit.io.e57 import split_scan_index
from splatedit.io.formats import FORMATS, Format, by_extension, extensions, format_of
from splatedit.io.gaussians import is_gaussian_ply, read_gaussian_ply, write_gaussian_ply
from splatedit.model.cloud import SplatCloud
from splatedit.model.gaussians import GaussianCloud
from splatedit.model.summary import CloudSummary
from splatedit.progress import report

__all__ = ["read", "write", "convert", "check_output_path", "check_readable_file", "split_scan_index",
           "READ_EXTENSIONS", "WRITE_EXTENSIONS", "FACE_EXTENSIONS", "is_gaussian_file", "read_gaussians", "write_gaussians",
           "read_summary", "read_columns", "cloud_from_columns", "PointColumns",
           "FORMATS", "Format", "format_of"]

#: extensions :func:`read` understands (from :data:`splatedit.io.formats.FORMATS`)
READ_EXTENSIONS = extensions(readable=True)
#: extensions :func:`write` understands (.ply is the lossless splat format;
#: .xyz keeps positions and normals, .off positions and faces; the scanner
#: formats keep positions, colours, intensity (and LAS classification), .pcd
#: normals too)
WRITE_EXTENSIONS = extensions(writable=True)
#: the written formats that hold triangle faces (the others drop a mesh's faces)
FACE_EXTENSIONS = extensions(writable=True, faces=True)


def _ext(path, allowed, what) -> str:
    ext = Path(path).suffix.lower()
    if ext not in allowed:
        raise InputError(f"unsupported file extension {ext or '(none)'!r} for {what}; "
                         f"supported: {', '.join(allowed)}", path=str(path))
    return ext


def read(path, *, progress=None) -> SplatCloud:
    """Read a splat cloud, point cloud or mesh.

    Args:
        path: a file of one of ``READ_EXTENSIONS``; ``file.e57#N`` reads
            scan N (0-based) of an E57 file, ``file.e57`` all scans merged.
        progress: optional ``progress(stage, fraction)`` callback.
    Returns:
        SplatCloud with ``name`` = file name and ``source`` = path.
    Raises:
        InputError: unknown extension, unreadable or malformed file.
    """
    path, scan = split_scan_index(path)
    if os.path.isdir(path):
        check_readable_file(path)       # "is a directory", not "unsupported extension '(none)'"
    ext = _ext(path, READ_EXTENSIONS, "reading")
    reader = by_extension(ext).reader
    check_readable_file(path)
    with _memory_named(path):
        if scan is not None:                # only an .e57 path splits off a scan index
            return reader(path, scan=scan, progress=progress)
        return reader(path, progress=progress)


@contextlib.contextmanager
def _memory_named(path):
    """A MemoryError while reading ``path`` (a header whose count fits a
    sparse file of that size: the size checks pass, the memory does not)
    becomes an InputError naming the file."""
    try:
        yield
    except MemoryError:
        raise InputError(f"not enough memory to read it ({os.stat(path).st_size:,} bytes on disk)",
                         path=str(path)) from None


def read_columns(path, *, progress=None) -> PointColumns:
    """:func:`read` stopping before splats are derived: the file's columns
    (:class:`PointColumns`); ``cloud_from_columns(read_columns(p))`` equals
    ``read(p)``.  Batch conversion reads tiles this way, so that normals and
    sizes can be estimated over a tile and its neighbours' border points.

    Raises:
        InputError: as :func:`read`.
    """
    with columns_only():
        got = read(path, progress=progress)
    return got if isinstance(got, PointColumns) else PointColumns.of_cloud(got)


def read_summary(path, *, progress=None, lean_above: int = 0) -> CloudSummary:
    """What ``splatedit info`` needs of a model (:class:`CloudSummary`).

    A binary PLY of more than ``lean_above`` splats holding our splat axes
    is read in one pass keeping only the centres and splat radii
    (:mod:`splatedit.io._plysummary`; ``cloud`` is None); anything else, or
    a file failing a check there, is read whole by :func:`read` (whose
    errors name the row at fault).
    """
    src, scan = split_scan_index(path)
    if scan is None and Path(src).suffix.lower() == ".ply":
        check_readable_file(src)
        from splatedit.io._plycheck import binary_layout, check_declared_sizes, stored_origin
        check_declared_sizes(src)
        layout = binary_layout(src)
        if layout is not None and layout[1] > lean_above and not is_gaussian_ply(src):
            from splatedit.io._plysummary import read_ply_summary
            summary = read_ply_summary(src, layout, progress, stored_origin=stored_origin(src))
            if summary is not None:
                return summary
    return CloudSummary.of_cloud(read(path, progress=progress))


def is_gaussian_file(path) -> bool:
    """True for a ``.ply`` whose vertex element holds Gaussian splatting
    properties (``f_dc_0``, or ``scale_0`` and ``rot_0``).  Anything but an
    existing regular file is False (a FIFO is never opened: it could block)."""
    try:
        regular = stat.S_ISREG(os.stat(path).st_mode)
    except (OSError, ValueError):
        return False
    return regular and Path(path).suffix.lower() == ".ply" and is_gaussian_ply(path)


def read_gaussians(path, *, progress=None) -> GaussianCloud:
    """Read a 3DGS/2DGS PLY losslessly (:func:`splatedit.io.gaussians.read_gaussian_ply`).

    Raises:
        InputError: not a .ply, unreadable, or not a valid Gaussian scene
            (the message names the file and the property).
    """
    _ext(path, (".ply",), "reading Gaussians")
    check_readable_file(path)
    if not is_gaussian_ply(path):
        raise InputError("is not a Gaussian splatting PLY (its vertex element has no f_dc_0, "
                         "scale_0 or rot_0 property)", path=str(path))
    with _memory_named(path):
        return read_gaussian_ply(path, progress=progress)


def write_gaussians(path, scene: GaussianCloud, *, overwrite: bool = False, progress=None,
                    up_axis: str | None = None) -> Path:
    """Save a Gaussian scene atomically as a binary little-endian 3DGS/2DGS PLY
    (the scene's own property order and types; unknown properties kept);
    ``up_axis`` ("+Z", "-Y", ...) is recorded as a header comment
    (``comment up_axis +Z``) that the editor and ``render`` read back.

    Raises:
        InputError: not a .ply target, an existing file without ``overwrite``,
            a write failure, or a scene with non-finite values.
    """
    path = Path(path)
    _ext(path, (".ply",), "writing Gaussians")
    check_writable_target(path, overwrite=overwrite)
    from splatedit.io.gaussians import check_gaussians
    check_gaussians(scene)
    report(progress, "writing", 0.0)
    try:
        with atomic_open(path, "wb") as fh:
            write_gaussian_ply(fh, scene, comment=f"written by splatedit from {scene.name or 'a Gaussian scene'}"
                               + _up_comment(up_axis))
    except OSError as exc:
        raise InputError(f"cannot write: {exc.strerror or exc}", path=str(path)) from None
    report(progress, "writing", 1.0)
    return path


def check_readable_file(path) -> None:
    """Raise :class:`InputError` unless ``path`` is an existing regular file:
    a directory, a FIFO (reading it would wait forever for a writer), a
    device, a name too long or with a NUL byte are refused by name."""
    try:
        st = os.stat(path)
    except OSError as exc:
        raise InputError(f"cannot read file: {exc.strerror or exc}", path=str(path)) from None
    except ValueError as exc:
        raise InputError(f"not a usable file name: {exc}", path=repr(str(path))) from None
    if stat.S_ISDIR(st.st_mode):
        raise InputError("is a directory, not a file", path=str(path))
    if not stat.S_ISREG(st.st_mode):
        raise InputError("is not a regular file (a FIFO, device or socket); splatedit reads files",
                         path=str(path))


def check_output_path(path, *, overwrite: bool, protect=None, extensions=WRITE_EXTENSIONS) -> Path:
    """Everything about an output path that can be checked before the work:
    its extension (one of ``extensions``) and :func:`check_writable_target`."""
    _ext(path, extensions, "writing")
    return check_writable_target(path, overwrite=overwrite, protect=protect)


def _up_comment(up_axis: str | None) -> str:
    """The PLY header line recording the model's up axis ("" for None)."""
    if up_axis is None:
        return ""
    if up_axis not in ("+X", "+Y", "+Z", "-X", "-Y", "-Z"):
        raise ValueError(f"up_axis must be one of +X +Y +Z -X -Y -Z, got {up_axis!r}")
    return f"\nup_axis {up_axis}"


def write(path, cloud: SplatCloud, *, overwrite: bool = False, binary: bool = True,
          axes: bool = True, progress=None, up_axis: str | None = None) -> Path:
    """Save ``cloud`` atomically (:func:`splatedit.atomic.atomic_open`).

    Args:
        path: target ``.ply`` (lossless), ``.xyz``, ``.off``, ``.las``,
            ``.laz``, ``.e57``, ``.pcd`` or ``.pts`` (world coordinates:
            the cloud's ``origin`` is added back).
        overwrite: replace an existing file (by default that is refused).
        binary: PLY only: binary little endian (default) or ascii.
        axes: PLY only: store normals and splat axes (default); False
            stores positions, colours and faces only.
        up_axis: PLY only: the model's up axis ("+Z", "-Y", ...) as a header
            comment (``comment up_axis +Z``), which the editor and ``render``
            read back (:func:`splatedit.model.orientation.header_up_hint`);
            other formats have no place for it (LAS/LAZ/E57 are Z-up anyway).
    Returns:
        the path written.
    Raises:
        InputError: the file exists and ``overwrite`` is False, unsupported
            extension, missing directory, write failure, or ``cloud`` fails
            :meth:`SplatCloud.validate` (NaN, values beyond
            ``MAX_COORDINATE_ABS``, degenerate axes).
    """
    path = Path(path)
    ext = _ext(path, WRITE_EXTENSIONS, "writing")
    check_writable_target(path, overwrite=overwrite)
    # every file we write must pass our own reader's checks: a cloud whose
    # arrays were changed in place since construction is checked again
    cloud.validate()
    report(progress, "writing", 0.0)
    try:
        with atomic_open(path, "wb") as fh:
            comment = f"written by splatedit from {cloud.name or 'a splat cloud'}" + _up_comment(up_axis)
            by_extension(ext).writer(fh, cloud, path, binary=binary, axes=axes, comment=comment)
    except OSError as exc:
        raise InputError(f"cannot write: {exc.strerror or exc}", path=str(path)) from None
    report(progress, "writing", 1.0)
    return path


def convert(in_path, out_path, *, overwrite: bool = False, binary: bool = True,
            progress=None) -> SplatCloud:
    """Read ``in_path`` and write it to ``out_path`` (format from the
    extension).  The output is checked before the (possibly long) read, so an
    existing output without ``overwrite=True`` fails at once.

    Returns:
        the cloud that was written.
    """
    out = Path(out_path)
    _ext(out, WRITE_EXTENSIONS, "writing")
    check_writable_target(out, overwrite=overwrite, protect=in_path)
    cloud = read(in_path, progress=progress)
    write(out, cloud, overwrite=overwrite, binary=binary, progress=progress)
    return cloud
