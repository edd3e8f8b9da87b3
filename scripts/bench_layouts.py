"""CPU cost of packing GPU buffers through the declared dtypes
(splatedit/render/uniforms.py) against the hand-offset packing they replaced
(loaded from git revision REV, default 8ab4568).  Run from the repository root:
PYTHONPATH=$PWD python scripts/bench_layouts.py [REV]"""
import importlib.util
import os
import subprocess
import sys
import tempfile
import timeit

import numpy as np

sys.path.insert(0, ".")
from splatedit.bench.gs_scenes import gaussians_from_splats  # noqa: E402
from splatedit.data import default_model_path  # noqa: E402
from splatedit.deform.rotation import HandleRotation, RotationDisplacement  # noqa: E402
from splatedit.io import read  # noqa: E402
from splatedit.render.gpu_units import pack_deform_block  # noqa: E402
from splatedit.render.gaussian.resources import pack_geometry  # noqa: E402
from splatedit.render.uniforms import GS_FRAME_UBO, SPLAT_GEOM  # noqa: E402


def _load(name: str, path: str, rev: str):
    """Module ``path`` as it was at git revision ``rev``."""
    src = subprocess.run(["git", "show", f"{rev}:{path}"], check=True, capture_output=True, text=True).stdout
    with tempfile.NamedTemporaryFile("w", suffix=".py", delete=False) as f:
        f.write(src)
    try:
        spec = importlib.util.spec_from_file_location(name, f.name)
        m = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(m)
    finally:
        os.unlink(f.name)
    return m


def best_us(f, number: int) -> float:
    """Best of 7 repeats, microseconds per call."""
    return min(timeit.repeat(f, number=number, repeat=7)) / number * 1e6


def gs_frame_new():
    u = np.zeros((), GS_FRAME_UBO)
    u["view"] = np.eye(4)
    for name in GS_FRAME_UBO.names[1:]:
        u[name] = (1, 2, 3, 4)
    return u.reshape(1).view(np.float32)


def gs_frame_old():
    u = np.zeros(56, np.float32)
    u[0:16] = np.eye(4).reshape(-1)
    for a in range(16, 56, 4):
        if a == 40:
            u[40:44].view(np.uint32)[:] = (1, 2, 3, 4)
        else:
            u[a:a + 4] = (1, 2, 3, 4)
    return u


def main():
    rev = sys.argv[1] if len(sys.argv) > 1 else "8ab4568"
    _legacy_deform_block = _load("gpu_units_old", "splatedit/render/gpu_units.py", rev).pack_deform_block
    _legacy_geometry = _load("gs_resources_old", "splatedit/render/gs_resources.py", rev).pack_geometry
    rng = np.random.default_rng(0)
    dC = rng.normal(size=(16, 3))
    rot = RotationDisplacement(dC, tuple(HandleRotation(rng.normal(size=3), rng.normal(size=3),
                                                        rng.normal(size=(4, 3))) for _ in range(4)))
    print(f"deform block new: {best_us(lambda: pack_deform_block(dC, rot, 2.0), 2000):.1f} us, "
          f"old: {best_us(lambda: _legacy_deform_block(dC, rot, 2.0), 2000):.1f} us")
    print(f"GsFrame fill new: {best_us(gs_frame_new, 2000):.1f} us, old: {best_us(gs_frame_old, 2000):.1f} us")
    cloud = read(default_model_path())
    g = gaussians_from_splats(cloud, degree=3, seed=1)
    o = np.zeros(3)
    print(f"GS geometry n={len(g)} new: {best_us(lambda: pack_geometry(g, o, 0.5), 5) / 1e3:.1f} ms, "
          f"old: {best_us(lambda: _legacy_geometry(g, o, 0.5), 5) / 1e3:.1f} ms")
    m = cloud.n
    buf = np.zeros(m * SPLAT_GEOM.itemsize, np.uint8)

    def splat_new():
        geom = buf.view(SPLAT_GEOM)
        for name, a in (("center", cloud.positions - o), ("u", cloud.u), ("v", cloud.v)):
            np.multiply(a, 0.5, out=geom[name], casting="same_kind")

    def splat_old():
        geom = buf.view(np.float32).reshape(m, 9)
        for k, a in enumerate((cloud.positions - o, cloud.u, cloud.v)):
            np.multiply(a, 0.5, out=geom[:, 3 * k:3 * k + 3], casting="same_kind")

    print(f"splat geometry n={m} new: {best_us(splat_new, 10) / 1e3:.2f} ms, "
          f"old: {best_us(splat_old, 10) / 1e3:.2f} ms")


if __name__ == "__main__":
    main()
