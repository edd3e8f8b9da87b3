"""CPU cost of packing GPU buffers through the declared dtypes
(splatedit/render/uniforms.py) against the hand-offset packing they replaced
(loaded from git revision REV, default 8ab4568).  Run from the repository root:
PYTHONPATH=$PWD python scripts/bench_layouts.py [REV]"""
import importlib.util
import subprocess
import sys
import tempfile
import timeit

import numpy as np

sys.path.insert(0, ".")
REV = sys.argv[1] if len(sys.argv) > 1 else "8ab4568"


def _load(name, path):
    """Module ``path`` as it was at REV."""
    with tempfile.NamedTemporaryFile("w", suffix=".py", delete=False) as f:
        f.write(subprocess.run(["git", "show", f"{REV}:{path}"], check=True, capture_output=True, text=True).stdout)
    spec = importlib.util.spec_from_file_location(name, f.name)
    m = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(m)
    return m


_legacy_deform_block = _load("gpu_units_old", "splatedit/render/gpu_units.py").pack_deform_block
_legacy_geometry = _load("gs_resources_old", "splatedit/render/gs_resources.py").pack_geometry
from splatedit.render.gpu_units import pack_deform_block
from splatedit.render.gs_resources import pack_geometry
from splatedit.render.uniforms import GS_FRAME_UBO, SPLAT_GEOM
from splatedit.deform.rotation import HandleRotation, RotationDisplacement
from splatedit.bench.gs_scenes import gaussians_from_splats
from splatedit.io import read
from splatedit.data import default_model_path
rng = np.random.default_rng(0)
dC = rng.normal(size=(16, 3))
rot = RotationDisplacement(dC, tuple(HandleRotation(rng.normal(size=3), rng.normal(size=3), rng.normal(size=(4, 3))) for _ in range(4)))
def best(f, n): return min(timeit.repeat(f, number=n, repeat=7)) / n * 1e6
for name, f in (("deform block new", lambda: pack_deform_block(dC, rot, 2.0)), ("deform block old", lambda: _legacy_deform_block(dC, rot, 2.0))):
    print(f"{name}: {best(f, 2000):.1f} us")
def gs_new():
    u = np.zeros((), GS_FRAME_UBO); u["view"] = np.eye(4); u["focal"] = (1, 2, 3, 4); u["viewport"] = (1, 2, 3, 4)
    u["eye"] = (1, 2, 3, 4); u["limits"] = (1, 2, 3, 4); u["params"] = (1, 2, 3, 4); u["background"] = (1, 2, 3, 4)
    u["counts"] = (1, 2, 3, 4); u["tint_support"] = (1, 2, 3, 4); u["tint_handle"] = (1, 2, 3, 4); u["display"] = (1, 2, 3, 4)
    return u.reshape(1).view(np.float32)
def gs_old():
    u = np.zeros(56, np.float32); u[0:16] = np.eye(4).reshape(-1)
    for a in range(16, 56, 4):
        if a == 40: u[40:44].view(np.uint32)[:] = (1, 2, 3, 4)
        else: u[a:a + 4] = (1, 2, 3, 4)
    return u
print(f"GsFrame fill new: {best(gs_new, 2000):.1f} us, old: {best(gs_old, 2000):.1f} us")
cloud = read(default_model_path())
g = gaussians_from_splats(cloud, degree=3, seed=1)
o = np.zeros(3)
print(f"GS geometry n={len(g)} new: {best(lambda: pack_geometry(g, o, 0.5), 5)/1e3:.1f} ms, old: {best(lambda: _legacy_geometry(g, o, 0.5), 5)/1e3:.1f} ms")
m = cloud.n
buf = np.zeros(m * 36, np.uint8)
def sg_new():
    geom = buf.view(SPLAT_GEOM)
    np.multiply(cloud.positions - o, 0.5, out=geom["center"], casting="same_kind")
    np.multiply(cloud.u, 0.5, out=geom["u"], casting="same_kind"); np.multiply(cloud.v, 0.5, out=geom["v"], casting="same_kind")
def sg_old():
    geom = buf.view(np.float32).reshape(m, 9)
    np.multiply(cloud.positions - o, 0.5, out=geom[:, 0:3], casting="same_kind")
    np.multiply(cloud.u, 0.5, out=geom[:, 3:6], casting="same_kind"); np.multiply(cloud.v, 0.5, out=geom[:, 6:9], casting="same_kind")
print(f"splat geometry n={m} new: {best(sg_new, 10)/1e3:.2f} ms, old: {best(sg_old, 10)/1e3:.2f} ms")
