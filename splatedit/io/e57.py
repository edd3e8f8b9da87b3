"""E57 scanner files (pye57).

Read: every scan, each moved by its pose (rotation + translation) into the
file's frame and merged; or one scan picked by index with ``file.e57#2``
(0-based).  Colours (``colorRed..Blue``, 0..255) and intensity (scaled to
0..65535 from the scan's intensity limits, or from its values when the file
gives none) are kept; without colours, grey from the intensity.  Points of
invalid cartesian coordinates (``cartesianInvalidState`` != 0) are dropped.
The first scan's pose translation is the local origin when the points lie
within ``REBASE_MIN_ABS`` of it (as in the files written here), so a scan
read, edited and written keeps its origin.

Write: one scan whose pose is a pure translation by the cloud's origin, with
the local coordinates as its points (pye57 writes the points in single
precision: world coordinates of a georeferenced scan would be rounded to
0.5 m at y = 5,000,000; local ones keep float32 steps of about a micrometre
at 10 m from the origin); colours and intensity (0..65535) when the cloud
has them.
"""

from __future__ import annotations

import numpy as np

from splatedit.errors import InputError
from splatedit.io._build import build_cloud, check_finite
from splatedit.io._guard import library_call
from splatedit.io.las import grey_from_intensity
from splatedit.model.cloud import SplatCloud
from splatedit.tolerances import E57_MAX_POINTS_PER_BYTE


def split_scan_index(path: str):
    """``("file.e57", 2)`` for ``"file.e57#2"``; ``(path, None)`` otherwise."""
    text = str(path)
    head, sep, tail = text.rpartition("#")
    if sep and head.lower().endswith(".e57") and tail.isdigit():
        return head, int(tail)
    return text, None


def read_e57(path, *, scan: int | None = None, progress=None) -> SplatCloud:
    """Read an E57 file, all scans merged or the scan of index ``scan``."""
    src = str(path)
    with library_call(src, "not a readable E57 file"):
        import pye57
        e57 = pye57.E57(src)
        count = e57.scan_count
    with library_call(src, "not a readable E57 file"):
        xyz, colors, intensity, stored = _read_scans(e57, src, count, scan)
    return build_cloud(src if scan is None else f"{src}#{scan}", xyz, colors=colors,
                       progress=progress, intensity=intensity, stored_origin=stored)


def _read_scans(e57, src: str, count: int, scan):
    """The scans of the open ``e57`` (all ``count`` merged, or ``scan``);
    each scan's point count is checked against the file size first.

    Returns:
        (xyz (n, 3) float64, colours (n, 4) uint8 or None, intensity (n,)
        uint16 or None, the first scan's pose translation (3,))."""
    import os
    size = os.stat(src).st_size
    if count == 0:
        raise InputError("the file holds no scans", path=src)
    if scan is not None and not 0 <= scan < count:
        raise InputError(f"scan index {scan} out of range 0..{count - 1}", path=src)
    parts = []
    stored = None           # the first scan's pose translation: the origin we wrote there
    for i in ([scan] if scan is not None else range(count)):
        header = e57.get_header(i)
        names = set(header.point_fields)
        declared = int(header.point_count)
        if not 0 <= declared <= size * E57_MAX_POINTS_PER_BYTE:
            raise InputError(f"scan {i}: {declared} points cannot be stored in a file of {size} bytes "
                             f"(the count is wrong)", path=src)
        if stored is None:
            try:
                stored = np.asarray(header.translation, dtype=np.float64).reshape(3)
            except Exception:       # a pose node of another shape: no stored origin
                stored = np.zeros(3)
        with library_call(src, f"scan {i}: cannot read"):
            d = e57.read_scan(i, colors="colorRed" in names, intensity="intensity" in names,
                              transform=True, ignore_missing_fields=True)
        if "cartesianX" not in d:
            raise InputError(f"scan {i}: no cartesian coordinates (spherical-only scans are "
                             f"not supported)", path=src)
        keep = (np.asarray(d["cartesianInvalidState"]) == 0 if "cartesianInvalidState" in d
                else slice(None))
        xyz = np.column_stack([np.asarray(d[c], dtype=np.float64)[keep]
                               for c in ("cartesianX", "cartesianY", "cartesianZ")])
        rgb = (np.column_stack([np.asarray(d[c])[keep] for c in ("colorRed", "colorGreen", "colorBlue")])
               if "colorRed" in d else None)
        inten = None
        if "intensity" in d:
            raw = np.asarray(d["intensity"], dtype=np.float64)[keep]
            try:
                lo, hi = float(header.intensityMinimum), float(header.intensityMaximum)
            except Exception:          # no intensityLimits node
                lo, hi = (float(raw.min()), float(raw.max())) if raw.size else (0.0, 1.0)
            inten = np.clip(np.rint((raw - lo) / max(hi - lo, 1e-300) * 65535), 0, 65535)
        parts.append((xyz, rgb, inten))
    xyz = np.concatenate([p[0] for p in parts])
    check_finite({"x": xyz[:, 0], "y": xyz[:, 1], "z": xyz[:, 2]}, src, element=None)
    intensity = (np.concatenate([p[2] for p in parts]).astype(np.uint16)
                 if all(p[2] is not None for p in parts) else None)
    colors = None
    if all(p[1] is not None for p in parts):
        rgb = np.concatenate([p[1] for p in parts]).astype(np.float64)
        if rgb.size and (rgb.min() < 0 or rgb.max() > 255):
            raise InputError("colours outside 0..255", path=src)
        colors = np.full((len(rgb), 4), 255, dtype=np.uint8)
        colors[:, :3] = np.rint(rgb)
    elif intensity is not None:
        colors = grey_from_intensity(intensity)
    return xyz, colors, intensity, stored


def write_e57(fh, cloud: SplatCloud, path) -> None:
    """Write ``cloud`` as a one-scan E57 file to the open binary file ``fh``
    (pye57 writes only by path: a scratch file in the folder of ``path``,
    the target named in errors, copied)."""
    import shutil
    import tempfile
    from pathlib import Path
    directory = Path(path).parent
    with tempfile.TemporaryDirectory(dir=directory, prefix=".splatedit-e57-") as tmp:
        scratch = Path(tmp) / "scan.e57"
        with library_call(path, "cannot write E57"):
            _write_e57_path(str(scratch), cloud)
        with open(scratch, "rb") as src:
            shutil.copyfileobj(src, fh, 1 << 22)


#: libE57 image files of failed writes, cancelled and kept alive: freeing
#: one while its writer objects (held by the exception's traceback) still
#: refer to it crashed the process (SIGSEGV) after the error line
_FAILED_WRITES: list = []


def _write_e57_path(tmp_path: str, cloud: SplatCloud) -> None:
    import pye57
    local = cloud.positions             # the pose's translation adds the origin back
    data = {"cartesianX": local[:, 0], "cartesianY": local[:, 1], "cartesianZ": local[:, 2]}
    if cloud.colors is not None:
        for j, c in enumerate(("colorRed", "colorGreen", "colorBlue")):
            data[c] = cloud.colors[:, j].astype(np.uint8)
    if cloud.intensity is not None:
        data["intensity"] = cloud.intensity.astype(np.float64)
    # the limits 0..65535 make a reader map our intensities back unchanged
    # (pye57 would otherwise store the data's own min/max as the limits)
    from types import SimpleNamespace
    lo, hi = local.min(axis=0), local.max(axis=0)   # cartesianBounds: the scan's own frame
    header = SimpleNamespace(name=cloud.name or "splatedit", rotation=np.array([1.0, 0, 0, 0]),
                             translation=np.asarray(cloud.origin, dtype=np.float64),
                             intensityMinimum=0.0,
                             intensityMaximum=65535.0, xMinimum=lo[0], yMinimum=lo[1],
                             zMinimum=lo[2], xMaximum=hi[0], yMaximum=hi[1], zMaximum=hi[2])
    e57 = pye57.E57(tmp_path, mode="w")
    try:
        e57.write_scan_raw(data, scan_header=header)
        e57.close()
    except BaseException:
        # a failed write (disk full) leaves libE57's file open: cancel it here,
        # else pye57's __del__ closes it again at some later garbage
        # collection and prints a second exception and libE57's debug lines
        image_file = e57.__dict__.pop("image_file", None)
        if image_file is not None:
            _FAILED_WRITES.append(image_file)
        raise
