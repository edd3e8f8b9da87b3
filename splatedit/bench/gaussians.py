"""``splatedit bench gaussians``: the CPU cost of deforming and saving a Gaussian scene.

Scene: the shipped test scene (5,000 Gaussians, SH degree 3) repeated with
jitter (a fraction of the spacing) to ``n`` Gaussians on the bunny's surface.
Edit: the ears (top 20 % in y) turned 30 degrees inside a support of the
upper half.  Reported per case, in the same run: the fit, the Gaussian
transport split into its parts (centres + Jacobians from the basis, the
covariance re-decomposition, the SH rotation), the save, and as the floor
the plain-splat ``apply`` of the same basis on the proxy discs.
"""

from __future__ import annotations

import os
import tempfile
import time

import numpy as np


def bench_scene(n: int, seed: int = 0):
    """A GaussianCloud of ``n`` Gaussians (the test scene tiled with jitter)."""
    from splatedit.data import gaussian_scene_path
    from splatedit.io import read_gaussians
    base = read_gaussians(gaussian_scene_path())
    rng = np.random.default_rng(seed)
    rep = -(-n // len(base))
    idx = np.tile(np.arange(len(base)), rep)[:n]
    jitter = rng.normal(scale=0.3 * float(np.exp(base.log_scales).max(1).mean()), size=(n, 3))
    return base.replace(positions=base.positions[idx] + jitter * (np.arange(n) >= len(base))[:, None],
                        log_scales=base.log_scales[idx], rotations=base.rotations[idx],
                        opacity_logits=base.opacity_logits[idx], sh=base.sh[idx],
                        normals=None if base.normals is None else base.normals[idx],
                        extra={k: v[idx] for k, v in base.extra.items()}, layout=base.layout)


def _best(f, repeat):
    out, best = None, float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = f()
        best = min(best, time.perf_counter() - t0)
    return out, best


def bench_gaussian_deform(n: int, repeat: int = 3) -> dict:
    from splatedit.deform.basis import DeformationBasis
    from splatedit.deform.gaussians import decompose_factor, deform_gaussians, polar_rotation
    from splatedit.io import write_gaussians
    from splatedit.model.spherical_harmonics import rotate_sh
    from splatedit.script import TRS
    g = bench_scene(n)
    proxy = g.proxy_splats()
    y = proxy.positions[:, 1]
    support, handle = y > 0.0, y > np.percentile(y, 80)
    from splatedit.select.closure import closed_masks
    t0 = time.perf_counter()
    support, hs, _ = closed_masks(proxy, support, [handle])
    basis = DeformationBasis.fit(proxy, support, hs)
    fit = time.perf_counter() - t0
    m = TRS(rotate_axis=(1.0, 0.0, 0.0), rotate_degrees=30.0).matrix(proxy.positions[handle].mean(0))
    d_c = basis.displacement([m])
    idx = basis.indices
    (disp, jac), t_eval = _best(lambda: (basis.displacements(d_c), basis.jacobians(d_c)), repeat)
    k = g.log_scales.shape[1]
    r_old = g.rotation_matrices(idx)
    s_old = np.exp(g.log_scales[idx].astype(np.float64))
    _, t_dec = _best(lambda: decompose_factor((jac @ r_old[:, :, :k]) * s_old[:, None, :]), repeat)
    _, t_sh = _best(lambda: rotate_sh(g.sh[idx], polar_rotation(jac)), repeat)
    out, t_all = _best(lambda: deform_gaussians(g, idx, disp, jac), repeat)
    _, t_plain = _best(lambda: basis.apply(proxy, d_c), repeat)
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "bench.ply")
        _, t_save = _best(lambda: write_gaussians(path, out, overwrite=True), repeat)
        size = os.path.getsize(path)
    return {"bench": "gaussians", "gaussians": n, "support": int(len(idx)), "sh_degree": g.sh_degree,
            "fit_s": round(fit, 3), "basis_eval_s": round(t_eval, 4), "decompose_s": round(t_dec, 4),
            "sh_rotate_s": round(t_sh, 4), "deform_total_s": round(t_all, 4),
            "save_s": round(t_save, 4), "file_mb": round(size / 2**20, 1),
            "plain_splat_apply_s": round(t_plain, 4),
            "deform_vs_plain": round(t_all / max(t_plain, 1e-9), 1),
            "deform_save_s": round(t_eval + t_all + t_save, 4)}
