"""Bar bend and twist tests (Botsch & Sorkine 2008) on a densely sampled open cylinder.

The cylinder (radius R, along +z from 0 to L) is fixed below ``z = FIXED``;
its top end ``z > L - HANDLE`` is the handle, rotated about the handle's
centroid: a *bend* about the x axis, a *twist* about the bar's axis.  The
figure of merit is the distance of the middle cross-section's splats (an
undeformed ring at ``z = L / 2``) from their deformed centroid, relative to R:
1 is a kept cross-section, the linear mode collapses it towards 0.

    python -m splatedit.bench.bars        # one JSON line per case and mode
"""

from __future__ import annotations

import json
import sys
import time
from dataclasses import asdict, dataclass

import numpy as np

from splatedit.deform.basis import DeformationBasis
from splatedit.deform.modes import DeformationMode
from splatedit.deform.transform import rotate
from splatedit.model.cloud import SplatCloud

#: cylinder radius, length, fixed and handle lengths (model units)
RADIUS = 1.0
LENGTH = 8.0
FIXED = 1.0
HANDLE = 1.0
#: the targets of issue 9: (kind, degrees)
CASES = (("bend", 90.0), ("bend", 120.0), ("bend", 150.0), ("twist", 135.0), ("twist", 180.0))


def open_cylinder(radius: float = RADIUS, length: float = LENGTH, spacing: float = 0.1) -> SplatCloud:
    """An open cylinder of splats on a staggered grid, about ``spacing`` apart.

    Returns a SplatCloud of about 2 pi R L / spacing^2 splats (5,000 at the
    defaults), axes tangent (u around, v along the axis), radius ~ spacing.
    """
    n_around = int(round(2.0 * np.pi * radius / spacing))
    n_along = int(round(length / spacing)) + 1
    z = np.linspace(0.0, length, n_along)
    k = np.arange(n_around)
    ang = 2.0 * np.pi * (k[None, :] + 0.5 * (np.arange(n_along)[:, None] % 2)) / n_around
    zz = np.broadcast_to(z[:, None], ang.shape)
    pos = np.stack([radius * np.cos(ang), radius * np.sin(ang), zz], axis=-1).reshape(-1, 3)
    a = ang.reshape(-1)
    r = 0.75 * spacing
    u = r * np.stack([-np.sin(a), np.cos(a), np.zeros_like(a)], axis=1)
    v = np.zeros_like(u)
    v[:, 2] = r
    return SplatCloud(pos, u, v, name="open cylinder")


def bar_basis(cloud: SplatCloud) -> DeformationBasis:
    """The bar's basis: support z > FIXED, handle z > L - HANDLE (exact LU)."""
    z = cloud.positions[:, 2]
    length = float(z.max())
    return DeformationBasis.fit(cloud, z > FIXED, [z > length - HANDLE], method="lu", fill_holes=False)


def bar_transform(cloud: SplatCloud, kind: str, degrees: float) -> np.ndarray:
    """(4, 4) map of the handle: rotation about its centroid (x axis: bend, z: twist)."""
    z = cloud.positions[:, 2]
    c = cloud.positions[z > float(z.max()) - HANDLE].mean(axis=0)
    return rotate((1.0, 0.0, 0.0) if kind == "bend" else (0.0, 0.0, 1.0), degrees, c)


def middle_ring(cloud: SplatCloud) -> np.ndarray:
    """Indices of the splats of the undeformed ring nearest ``z = L / 2``."""
    z = cloud.positions[:, 2]
    mid = 0.5 * float(z.max())
    zr = z[np.argmin(np.abs(z - mid))]
    return np.flatnonzero(z == zr)


@dataclass
class BarResult:
    kind: str
    degrees: float
    mode: str
    #: distances of the middle ring's splats from their centroid, over R
    min_radius: float
    max_radius: float
    apply_seconds: float


def bar_case(cloud, basis, kind: str, degrees: float, mode: DeformationMode,
             radius: float = RADIUS) -> tuple[BarResult, SplatCloud]:
    """Deform the bar and measure its middle cross-section."""
    d = basis.displacement([bar_transform(cloud, kind, degrees)], mode=mode)
    t0 = time.perf_counter()
    out = basis.apply(cloud, d)
    t = time.perf_counter() - t0
    ring = out.positions[middle_ring(cloud)]
    r = np.linalg.norm(ring - ring.mean(axis=0), axis=1) / radius
    return BarResult(kind, degrees, DeformationMode(mode).value, float(r.min()), float(r.max()), t), out


def run(cases=CASES, modes=(DeformationMode.LINEAR, DeformationMode.ROTATION)):
    """Yield one BarResult per case and mode (one shared basis)."""
    cloud = open_cylinder()
    basis = bar_basis(cloud)
    for kind, deg in cases:
        for mode in modes:
            yield bar_case(cloud, basis, kind, deg, mode)[0]


def main(argv=None) -> int:
    for res in run():
        print(json.dumps(asdict(res)))
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
