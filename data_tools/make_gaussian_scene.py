"""Make ``splatedit/data/bunny_gaussians.ply``: a 3D Gaussian Splatting test scene
fitted to the bundled bunny's splats (provenance: splatedit/data/PROVENANCE.md).

Usage: ``python data_tools/make_gaussian_scene.py [-o OUT]`` (deterministic:
the same bytes on every run; prints the size and sha256).

Construction (every choice is seeded; nothing is captured from images):

* centres: a random subset of ``N_GAUSSIANS`` of the 37,706 vertex splats of
  ``splatedit.data.default_model_path()`` (seed ``SEED``);
* covariance: the splat's ellipse (axes u, v; semi-axis lengths |u|, |v|)
  widened by sqrt(37706 / N) so the sparser Gaussians still cover the surface
  (2 sigma = the widened semi-axis), then made anisotropic by a log-uniform
  factor a in [1, 4] (sigma_u * a, sigma_v / a), plus a thin normal axis of
  3..15 % of the smaller tangent sigma; rotation = (u, n x u, n) with a random
  spin about the normal, stored as a quaternion of random sign and norm
  0.5..2 (files in the wild are not normalised);
* opacity: 70 % between 0.8 and 0.995, 30 % between 0.05 and 0.8 (logits stored);
* colour: DC from a warm albedo modulated smoothly by position; bands 1..3
  from an exact SH projection of a view-dependent term that is a cubic
  polynomial in the view direction d (so it lies in bands 0..3): a bluish
  sheen at grazing views, 1 - (d.n)^2, a warm highlight (-d.n)^3 when seen
  head on, and a position-dependent tint along a tangent, d.t;
* normals nx ny nz: zeros, as the reference implementation writes them.
"""

from __future__ import annotations

import argparse
import hashlib
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from splatedit.data import default_model_path  # noqa: E402
from splatedit.io import read, write_gaussians  # noqa: E402
from splatedit.model.gaussians import GaussianCloud, GaussianKind  # noqa: E402
from splatedit.model.spherical_harmonics import C0, sh_basis  # noqa: E402

N_GAUSSIANS = 5000
SEED = 20240613
OUT = ROOT / "splatedit" / "data" / "bunny_gaussians.ply"


def _quaternions(r: np.ndarray) -> np.ndarray:
    """(n, 4) unit quaternions (w, x, y, z) of rotation matrices (n, 3, 3)."""
    from scipy.spatial.transform import Rotation
    xyzw = Rotation.from_matrix(r).as_quat()
    return np.column_stack([xyzw[:, 3], xyzw[:, :3]])


def _fibonacci_directions(m: int) -> np.ndarray:
    """(m, 3) well-spread unit directions (a Fibonacci sphere)."""
    i = np.arange(m) + 0.5
    z = 1.0 - 2.0 * i / m
    r = np.sqrt(1.0 - z * z)
    phi = np.pi * (1.0 + 5 ** 0.5) * i
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def make_scene() -> GaussianCloud:
    rng = np.random.default_rng(SEED)
    bunny = read(default_model_path())
    pick = np.sort(rng.choice(bunny.n, N_GAUSSIANS, replace=False))
    p, u, v = bunny.positions[pick], bunny.u[pick], bunny.v[pick]
    n = np.cross(u, v)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    uh = u / np.linalg.norm(u, axis=1, keepdims=True)
    widen = np.sqrt(bunny.n / N_GAUSSIANS)
    su = np.linalg.norm(u, axis=1) * widen / 2.0
    sv = np.linalg.norm(v, axis=1) * widen / 2.0
    aniso = np.exp(rng.uniform(0.0, np.log(4.0), N_GAUSSIANS))
    su, sv = su * np.sqrt(aniso), sv / np.sqrt(aniso)
    sn = np.minimum(su, sv) * rng.uniform(0.03, 0.15, N_GAUSSIANS)
    spin = rng.uniform(0.0, 2 * np.pi, N_GAUSSIANS)
    t0 = uh
    t1 = np.cross(n, uh)
    a = np.cos(spin)[:, None] * t0 + np.sin(spin)[:, None] * t1
    b = np.cross(n, a)
    rot = np.stack([a, b, n], axis=2)                  # columns: axes of scale_0, scale_1, scale_2
    q = _quaternions(rot)
    q *= (rng.choice([-1.0, 1.0], N_GAUSSIANS) * rng.uniform(0.5, 2.0, N_GAUSSIANS))[:, None]

    high = rng.random(N_GAUSSIANS) < 0.7
    opac = np.where(high, rng.uniform(0.8, 0.995, N_GAUSSIANS), rng.uniform(0.05, 0.8, N_GAUSSIANS))
    logit = np.log(opac / (1.0 - opac))

    lo, hi = p.min(0), p.max(0)
    x = (p - lo) / (hi - lo)                           # position in the box, 0..1
    albedo = np.array([0.72, 0.58, 0.44]) + 0.12 * np.sin(2 * np.pi * np.column_stack(
        [x[:, 1] + 0.3 * x[:, 0], 1.3 * x[:, 2], x[:, 0] + x[:, 1]]))
    sh = np.zeros((N_GAUSSIANS, 16, 3))
    sh[:, 0, :] = (albedo - 0.5) / C0
    # view-dependent term: exact projection of a cubic in d onto bands 1..3
    dirs = _fibonacci_directions(64)
    pinv = np.linalg.pinv(sh_basis(dirs, 3))           # (16, m): exact for polynomials of degree <= 3
    dn = dirs @ n.T                                    # (m, N): d . n
    tang = np.column_stack([np.cos(6 * x[:, 1]), np.sin(6 * x[:, 1]), np.zeros(N_GAUSSIANS)])
    tang -= (tang * n).sum(1, keepdims=True) * n
    tang /= np.maximum(np.linalg.norm(tang, axis=1, keepdims=True), 1e-12)
    dt = dirs @ tang.T
    sheen = np.array([0.05, 0.12, 0.25])
    warm = np.array([0.3, 0.18, 0.05])
    tint = np.array([0.1, -0.05, -0.1])
    vals = ((1.0 - dn ** 2)[..., None] * sheen + (-dn)[..., None] ** 3 * warm
            + dt[..., None] * tint)                    # (m, N, 3)
    coef = np.einsum("km,mnc->nkc", pinv, vals)
    sh[:, 1:, :] = coef[:, 1:, :]
    return GaussianCloud(positions=p.astype(np.float32).astype(np.float64),
                         log_scales=np.log(np.column_stack([su, sv, sn])).astype(np.float32),
                         rotations=q.astype(np.float32), opacity_logits=logit.astype(np.float32),
                         sh=sh.astype(np.float32), normals=np.zeros((N_GAUSSIANS, 3), np.float32),
                         kind=GaussianKind.GS3D, name="bunny_gaussians.ply")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("-o", "--output", type=Path, default=OUT)
    args = ap.parse_args()
    write_gaussians(args.output, make_scene(), overwrite=True)
    data = args.output.read_bytes()
    print(f"wrote {args.output}: {len(data):,} bytes, sha256 {hashlib.sha256(data).hexdigest()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
