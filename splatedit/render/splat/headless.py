"""One-shot offscreen rendering to a PNG (what the CLI calls)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from PIL import Image

from splatedit.errors import InputError, ParameterError
from splatedit.atomic import atomic_open, check_writable_target
from splatedit.model.cloud import SplatCloud
from splatedit.render.camera import Camera
from splatedit.render.splat.renderer import Renderer
from splatedit.tolerances import (RENDER_LOD_PATH, RENDER_BUFFERS_BYTES_PER_PIXEL, RENDER_BYTES_PER_PIXEL,
                                  RENDER_LOD_MARGIN, RENDER_LOD_MAX_KEPT_SHARE,
                                  RENDER_LOD_MIN_RADIUS_PX)


def available_memory() -> int | None:
    """Bytes of memory the system can give without swapping (Linux
    ``MemAvailable``), or None where that is unknown."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def check_render_memory(size, buffers: bool = False) -> None:
    """Refuse, before allocating anything, an image that would not fit in the
    available memory (RENDER_BYTES_PER_PIXEL, RENDER_BUFFERS_BYTES_PER_PIXEL).

    Raises:
        ParameterError: naming ``--size`` with the estimate and what is free.
    """
    w, h = (int(s) for s in size)
    need = w * h * (RENDER_BUFFERS_BYTES_PER_PIXEL if buffers else RENDER_BYTES_PER_PIXEL)
    free = available_memory()
    if free is not None and need > free:
        what = " with --buffers" if buffers else ""
        raise ParameterError("--size", f"{w}x{h}{what} needs about {need / 2**30:.1f} GiB of memory, "
                                       f"only {free / 2**30:.1f} GiB is available; render a smaller image")


def keep_for_pixels(cloud: SplatCloud, camera: Camera, height: int,
                    min_radius_px: float = RENDER_LOD_MIN_RADIUS_PX, chunk: int = 1 << 20) -> np.ndarray:
    """Keep probabilities of a single view's level of detail.

    A splat of radius ``r`` (the geometric mean of its axis lengths) at depth
    ``z`` along the view axis is ``r * f / z`` pixels wide (``f = height /
    (2 tan(fov / 2))``); one below ``min_radius_px`` is kept with probability
    ``(r_px / min_radius_px)^2`` and enlarged to that radius by
    :func:`splatedit.model.lod.thinned_level`, so many splats in one pixel
    become about one that covers it, as point-cloud viewers draw a level
    chosen per output size.  Splats at or behind the eye keep 1.

    Args:
        cloud: n splats; camera: the view; height: image height in pixels.
    Returns:
        (n,) float64 probabilities in (0, 1].
    """
    eye = np.asarray(camera.eye, dtype=np.float64)
    fwd = -camera.view_matrix()[2, :3]
    f = height / (2.0 * np.tan(np.radians(camera.fov_deg) / 2.0))
    out = np.empty(cloud.n)
    scale = (f / min_radius_px) ** 2
    z0 = float(eye @ fwd)
    for lo in range(0, cloud.n, chunk):
        u, v = cloud.u[lo:lo + chunk], cloud.v[lo:lo + chunk]
        k = np.einsum("ij,ij->i", u, u)
        k *= np.einsum("ij,ij->i", v, v)
        np.sqrt(k, out=k)                                    # r^2 = |u| |v|
        z = cloud.positions[lo:lo + chunk] @ fwd
        z -= z0                                              # depth along the view axis
        ahead = z > 0
        z *= z
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            k *= scale
            k /= z                                           # (r f / (z m))^2
        k[~ahead | ~(k < 1.0)] = 1.0                         # behind the eye, NaN, or wide enough
        out[lo:lo + chunk] = k
    return out


def pixel_level(cloud: SplatCloud, camera: Camera, height: int, *,
                min_radius_px: float = RENDER_LOD_MIN_RADIUS_PX,
                max_kept_share: float = RENDER_LOD_MAX_KEPT_SHARE):
    """The level of detail ``splatedit render`` draws for this view: splats
    thinned and enlarged to about ``min_radius_px`` (:func:`keep_for_pixels`,
    :func:`splatedit.model.lod.thinned_level` with ``RENDER_LOD_MARGIN``), or None when it would keep
    more than ``max_kept_share`` of them (the full cloud is drawn then).

    Returns:
        :class:`splatedit.model.lod.LodLevel` or None.
    """
    from splatedit.model.lod import thinned_level
    keep = keep_for_pixels(cloud, camera, height, min_radius_px)
    if keep.sum() > max_kept_share * cloud.n:
        return None
    return thinned_level(cloud, keep, margin=RENDER_LOD_MARGIN)


def drawn_for_view(cloud: SplatCloud, camera: Camera, height: int, raster_path: str | None = None):
    """What ``splatedit render`` draws of ``cloud`` for this view and on which
    path: the :func:`pixel_level` when splats crowd under a pixel, drawn on the
    compute path unless a path was asked for (``raster_path`` or
    ``SPLATEDIT_RASTER``): one frame, so no ``auto`` probe (two more full
    frames; ``RENDER_LOD_PATH``); else the cloud itself and the path asked for.

    Returns:
        (cloud to draw, raster path or None).
    """
    level = pixel_level(cloud, camera, height)
    if level is None:
        return cloud, raster_path
    if raster_path is None and not os.environ.get("SPLATEDIT_RASTER"):
        raster_path = RENDER_LOD_PATH
    return level.cloud, raster_path


def render_to_png(cloud: SplatCloud, out_png, *, size=(512, 512), camera: Camera | None = None,
                  basis=None, dC=None, selection=None, buffers_path=None,
                  device_name: str | None = None, raster_path: str | None = None, edl: bool = False) -> Path:
    """Render ``cloud`` offscreen and save an RGBA PNG (atomically: temp file + rename).

    Args:
        size: (width, height) in pixels.
        camera: default the editor's first view (:func:`splatedit.render.framing.default_view`:
            the main body from the front about the detected up axis).
        basis: optional ``(indices, B, Bx, By, Bz)`` deformation basis rows
            (see :meth:`Renderer.set_basis`), plus ``detail`` (N, 4) for the
            detail mode (:meth:`Renderer.set_detail`); applied on the GPU with ``dC``
            ((K, 3) control-frame displacement, default zeros).  Chained edits
            are committed on the CPU by the caller: pass the final cloud and
            the last edit's basis.
        selection: optional ``(support_mask, handle_mask)`` to tint.
        buffers_path: also save the float buffers (depth, normal, weight,
            colour; see :meth:`Renderer.render_buffers`) to this ``.npz``.
        raster_path: ``"auto"`` / ``"raster"`` / ``"compute"`` (the
            renderer's argument; default env var ``SPLATEDIT_RASTER`` or auto).
        edl: eye-dome lighting (:attr:`Renderer.edl`, default strength and radius).
    Returns the PNG path.

    Raises:
        InputError: naming the path, when an output cannot be written (its
            directory cannot be created or written, it is a directory, the
            disk is full, ...); the directories are checked (and created)
            before rendering.
    """
    w, h = size_and_basis(size, basis, dC)
    check_render_memory((w, h), buffers_path is not None)
    out_png = Path(out_png)
    outputs = [out_png] + ([Path(buffers_path)] if buffers_path is not None else [])
    for out in outputs:
        prepare_output(out)
    if camera is None:
        from splatedit.render.framing import default_view
        camera = default_view(cloud, (w, h), path=cloud.source).camera
    with Renderer(device_name=device_name, raster_path=raster_path) as r:
        r.set_cloud(cloud)
        r.edl = bool(edl)
        if selection is not None:
            r.set_selection(*selection)
        if basis is not None:
            idx, B, Bx, By, Bz = basis[:5]
            r.set_basis(idx, B, Bx, By, Bz)
            if len(basis) == 6:       # the detail mode's (n_b, lambda) rows
                r.set_detail(idx, basis[5])
            r.set_displacement(np.zeros((np.asarray(B).shape[1], 3)) if dC is None else dC)
        img = r.render(camera, w, h)
        bufs = r.render_buffers(camera, w, h) if buffers_path is not None else None
    write_image(out_png, lambda fh: Image.fromarray(img, "RGBA").save(fh, format="PNG"))
    if bufs is not None:
        write_image(Path(buffers_path), lambda fh: np.savez_compressed(fh, **bufs))
    return out_png


def size_and_basis(size, basis, dC) -> tuple[int, int]:
    """(width, height) of a headless render's ``size``; ParameterError for a
    bad size or a ``dC`` without a ``basis``."""
    try:
        w, h = (int(s) for s in size)
    except (TypeError, ValueError):
        raise ParameterError("size", f"must be (width, height), got {size!r}") from None
    if dC is not None and basis is None:
        raise ParameterError("dC", "given without a basis")
    return w, h


def prepare_output(path: Path) -> None:
    """Before rendering: create ``path``'s directory and check that a file can
    be written there (the CLI has already refused existing files unless
    --force, so an existing file is fine here)."""
    parent = path.parent if str(path.parent) else Path(".")
    try:
        parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise InputError(f"cannot create its directory {str(parent)!r}: {e.strerror or e}", path=str(path)) from None
    check_writable_target(path, overwrite=True)
    if not os.access(parent, os.W_OK | os.X_OK):
        raise InputError(f"directory {str(parent)!r} is not writable", path=str(path))


def write_image(path: Path, save) -> None:
    """Write a rendered image to ``path`` atomically: ``save(fh)`` writes the
    bytes to a temporary file that replaces ``path`` when done; an OS error
    is an :class:`~splatedit.errors.InputError` naming the path."""
    try:
        with atomic_open(path, "wb") as fh:
            save(fh)
    except OSError as e:
        raise InputError(f"cannot write: {e.strerror or e}", path=str(path)) from None
