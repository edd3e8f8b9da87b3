"""The README's images of the three deformation modes: a bumpy open bar
(radius 1, length 8, round bumps 0.2 high and ~0.3 wide) fixed below z = 1,
its top end (the handle, z > 7) bent 120 degrees about the handle's centroid
(exact LU fits, the selection used as is).

    PYTHONPATH=$PWD python docs/images/bumpy_bar.py docs/images

writes bar_before.png, bar_linear.png, bar_rotation.png, bar_detail.png
(240 x 320) and prints per mode the largest splat axis and the top's height.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from splatedit.bench.bars import bar_transform, open_cylinder
from splatedit.deform.basis import DeformationBasis
from splatedit.deform.detail import DetailBasis
from splatedit.deform.modes import DeformationMode
from splatedit.model.cloud import SplatCloud
from splatedit.model.estimate import estimate_splats
from splatedit.render.camera import Camera
from splatedit.render.splat.headless import render_to_png

HEIGHT, WIDTH = 0.2, 0.12          # bump height and Gaussian width (model units)
DEGREES = 120.0                    # the bend
AROUND, ALONG = 10, np.arange(1.6, 6.6, 0.7)   # bumps per ring, ring heights


def bumpy_bar(spacing: float = 0.07):
    """(cloud, support, handle) of the bar."""
    p = open_cylinder(spacing=spacing).positions
    ang = np.arctan2(p[:, 1], p[:, 0])
    z = p[:, 2]
    h = np.zeros(len(p))
    centres = [(2 * np.pi * (k + 0.5 * (j % 2)) / AROUND, zc)
               for j, zc in enumerate(ALONG) for k in range(AROUND)]
    for a, zc in centres:
        da = (ang - a + np.pi) % (2 * np.pi) - np.pi
        d2 = da ** 2 + (z - zc) ** 2
        h += HEIGHT * np.exp(-d2 / (2 * WIDTH ** 2))
    pts = p.copy()
    pts[:, :2] *= (1.0 + h)[:, None]
    est = estimate_splats(pts)            # normals and splat sizes of the bumpy surface
    cloud = SplatCloud(pts, est.u, est.v, name="bumpy bar")
    assert np.array_equal(est.positions, pts)
    return cloud, z > 1.0, z > 7.0


def main(out_dir: str) -> int:
    out = Path(out_dir)
    cloud, sup, hnd = bumpy_bar()
    m = bar_transform(cloud, "bend", DEGREES)
    plain = DeformationBasis.fit(cloud, sup, [hnd], fill_holes=False, method="lu")
    detail = DetailBasis.fit(cloud, sup, [hnd], fill_holes=False, method="lu")
    results = {"before": cloud}
    for mode, b in ((DeformationMode.LINEAR, plain), (DeformationMode.ROTATION, plain),
                    (DeformationMode.DETAIL, detail)):
        results[mode.value] = b.apply(cloud, b.displacement([m], mode=mode))
    lo = np.min([c.positions.min(0) for c in results.values()], axis=0)
    hi = np.max([c.positions.max(0) for c in results.values()], axis=0)
    cam = Camera.frame(lo, hi, 240 / 320, direction=(1.0, 0.35, 0.25), up=(0.0, 0.0, 1.0))
    for name, c in results.items():
        render_to_png(c, out / f"bar_{name}.png", size=(240, 320), camera=cam)
        axis = max(np.linalg.norm(c.u, axis=1).max(), np.linalg.norm(c.v, axis=1).max())
        print(f"{name}: largest splat axis {axis:.2f}, top at z = {c.positions[:, 2].max():.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "."))
