"""One-shot offscreen rendering of a GaussianCloud to a PNG (``splatedit render``
on a Gaussian Splatting scene), and the surface-splat proxy through which the
existing edit fitting (which works on a SplatCloud) deforms Gaussians."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from splatedit.errors import ParameterError
from splatedit.model.cloud import SplatCloud
from splatedit.model.gaussians import GaussianCloud
from splatedit.render.camera import Camera
from splatedit.render.gaussian.renderer import GaussianRenderer, gaussian_bounds
from splatedit.render.splat.headless import prepare_output, size_and_basis, write_image, check_render_memory


def splat_proxy(cloud: GaussianCloud) -> SplatCloud:
    """The Gaussians' splat proxy, :meth:`GaussianCloud.proxy_splats` (one
    disc per Gaussian, same indices, spanned by its two largest axes at
    ``GAUSSIAN_PROXY_SIGMAS`` standard deviations, DC colours): supports,
    handles and bases fitted on it apply to the Gaussians row for row.  The
    same proxy as the editor's and ``splatedit deform``'s."""
    return cloud.proxy_splats()


def default_camera(cloud: GaussianCloud, width: int, height: int) -> Camera:
    """Camera.frame of the Gaussians' 3-sigma box, looking from +z."""
    lo, hi = gaussian_bounds(cloud)
    return Camera.frame(lo, hi, aspect=width / height)


def render_gaussians_to_png(cloud: GaussianCloud, out_png, *, size=(512, 512), camera: Camera | None = None,
                            basis=None, dC=None, sort: str = "auto", path: str = "auto",
                            device_name: str | None = None) -> Path:
    """Render a GaussianCloud offscreen and save an RGBA PNG (atomically).

    Args:
        size: (width, height) pixels; camera: default :func:`default_camera`.
        basis: optional ``(indices, B, Bx, By, Bz)`` rows applied on the GPU
            with ``dC`` ((K, 3), default zeros), as :func:`render_to_png`.
        sort: depth sort, path: draw path (``"raster"``, ``"compute"`` or
            ``"auto"``), as for :class:`GaussianRenderer`.
    Returns the PNG path.
    """
    if not isinstance(cloud, GaussianCloud):
        raise ParameterError("cloud", f"must be a GaussianCloud, got {type(cloud).__name__}")
    w, h = size_and_basis(size, basis, dC)
    check_render_memory((w, h))
    out_png = Path(out_png)
    prepare_output(out_png)
    camera = default_camera(cloud, w, h) if camera is None else camera
    with GaussianRenderer(sort=sort, path=path, device_name=device_name) as r:
        r.set_gaussians(cloud)
        if basis is not None:
            idx, B, Bx, By, Bz = basis
            r.set_basis(idx, B, Bx, By, Bz)
            r.set_displacement(np.zeros((np.asarray(B).shape[1], 3)) if dC is None else dC)
        img = r.render(camera, w, h)
    write_image(out_png, lambda fh: Image.fromarray(img, "RGBA").save(fh, format="PNG"))
    return out_png
