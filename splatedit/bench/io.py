"""``splatedit bench io``: reading and writing scan-sized files.

Cases (one dict each, printed as a JSON line by the CLI):

* ``ply_read``: a binary little-endian splat PLY as our writer lays it out
  (x y z double, nx ny nz float, ux..vz double: 84 bytes per splat, 840 MB at
  10M) on a Fibonacci sphere, generated once per size in a temporary folder
  (in chunks: the generator never holds the whole cloud).  Each reader runs
  in a fresh Python process so its peak memory is its own: ``splatedit``
  (:func:`splatedit.io.read`, the whole SplatCloud), ``plyfile`` (its plain
  ``PlyData.read``, the structured vertex array only) and ``open3d``
  (``read_point_cloud``, in ``SPLATEDIT_OPEN3D_PYTHON`` when set; skipped
  with a note when Open3D is not installed).
  Keys: ``seconds`` (the read alone), ``peak_rss_mb`` (the child's peak
  resident memory), ``base_rss_mb`` (the child's memory after its imports,
  before reading), ``kept_mb`` (bytes of the arrays the reader returns) and
  ``peak_over_kept`` = (peak - base) / kept.
* ``las_write`` / ``las_read`` / ``laz_write`` / ``laz_read``: a 1M-point
  georeferenced scan (UTM-like coordinates, scale 0.001, RGB, intensity,
  classification) through :func:`splatedit.io.write` and :func:`read`, with
  laspy's own read (``laspy.read``) in the same run.  LAS has no normals:
  our read includes normal estimation, orientation and sizing of the raw
  points (``splatedit.model.estimate``), which is most of its time.

* ``info_file`` / ``render_file`` (``--large`` only): issue 23's file, a
  binary PLY of float32 x y z nx ny nz radius (28 bytes a point, 280 MB at
  10M; a Fibonacci sphere), through the whole ``splatedit -q info`` and
  ``splatedit -q render`` processes (1280x720; the render draws its level
  of detail unless ``--full``), each beside Open3D's ``read_point_cloud`` of
  the same file in a fresh process of the same run: ``seconds`` and
  ``peak_rss_mb`` of each process (wall time, ``wait4``'s peak resident
  memory), ``open3d_s``, ``open3d_peak_rss_mb`` and ``ratio_to_open3d``.
  Open3D's interpreter: ``SPLATEDIT_OPEN3D_PYTHON`` if set (a separate
  environment), else this one; skipped with a note when it has no Open3D.

Sizes: 1M by default (``--quick``: 200k PLY, 20k LAS); 10M only with ``--large``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Iterator

import numpy as np

from splatedit.bench.render import fibonacci_sphere

_CHUNK = 1_000_000

_CHILD = r"""
import json, sys, time
kind, path = sys.argv[1], sys.argv[2]
import numpy as np
if kind == "splatedit":
    from splatedit.io import read
elif kind == "plyfile":
    import plyfile
else:
    import open3d as o3d
def rss_mb(key="VmRSS:"):
    # /proc, not getrusage: ru_maxrss survives exec and starts at the parent's size
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith(key):
                return int(line.split()[1]) / 1024
base = rss_mb()
t0 = time.perf_counter()
if kind == "splatedit":
    c = read(path)
    kept = sum(a.nbytes for a in (c.positions, c.u, c.v, c.colors) if a is not None)
    n = c.n
elif kind == "plyfile":
    d = np.array(plyfile.PlyData.read(path)["vertex"].data)   # mapped, then copied: the plain read
    kept, n = d.nbytes, len(d)
else:
    pc = o3d.io.read_point_cloud(path)
    n = len(pc.points)
    kept = n * 24 * (1 + pc.has_normals() + pc.has_colors())
dt = time.perf_counter() - t0
peak = rss_mb("VmHWM:")
print(json.dumps({"seconds": round(dt, 3), "n": n, "peak_rss_mb": round(peak), "base_rss_mb": round(base),
                  "kept_mb": round(kept / 2**20), "peak_over_kept": round((peak - base) / (kept / 2**20), 3)}))
"""


def write_sphere_ply(path: Path, n: int) -> int:
    """Write ``n`` splats of a unit Fibonacci sphere as our binary PLY layout,
    ``_CHUNK`` splats at a time.  Returns the file size in bytes."""
    fields = ([(p, "<f8") for p in "xyz"] + [(p, "<f4") for p in ("nx", "ny", "nz")]
              + [(p, "<f8") for p in ("ux", "uy", "uz", "vx", "vy", "vz")])
    names = {"<f8": "double", "<f4": "float"}
    head = ["ply", "format binary_little_endian 1.0", f"element vertex {n}"]
    head += [f"property {names[t]} {p}" for p, t in fields] + ["end_header", ""]
    s = np.sqrt(4 * np.pi / n)
    with open(path, "wb") as fh:
        fh.write("\n".join(head).encode("ascii"))
        for lo in range(0, n, _CHUNK):
            nrm, t1, t2 = fibonacci_sphere(n, lo, min(n, lo + _CHUNK))
            arr = np.empty(len(nrm), dtype=fields)
            for j, p in enumerate("xyz"):
                arr[p] = nrm[:, j]
                arr["n" + p] = nrm[:, j]
                arr["u" + p] = s * t1[:, j]
                arr["v" + p] = s * t2[:, j]
            fh.write(arr.tobytes())
    return path.stat().st_size


def _child(kind: str, path: Path) -> dict:
    env = dict(os.environ)
    env.setdefault("NUMPY_MADVISE_HUGEPAGE", "0")     # as the CLI runs (see splatedit.cli)
    exe = _open3d_python() if kind == "open3d" else sys.executable
    proc = subprocess.run([exe, "-c", _CHILD, kind, str(path)], capture_output=True,
                          text=True, env=env)
    if proc.returncode != 0:
        last = (proc.stderr.strip().splitlines() or ["failed"])[-1]
        return {"skipped": last[:200]}
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _open3d_python() -> str:
    """The interpreter of the Open3D reads: ``SPLATEDIT_OPEN3D_PYTHON`` (an
    environment of its own: Open3D pins its own numpy) or this one."""
    return os.environ.get("SPLATEDIT_OPEN3D_PYTHON") or sys.executable


def _has_open3d() -> bool:
    import importlib.util
    return bool(os.environ.get("SPLATEDIT_OPEN3D_PYTHON")) or importlib.util.find_spec("open3d") is not None


def bench_ply_read(counts, tmp: Path) -> Iterator[dict]:
    for n in counts:
        path = tmp / f"sphere{n}.ply"
        t0 = time.perf_counter()
        size = write_sphere_ply(path, n)
        gen = time.perf_counter() - t0
        for kind in ("splatedit", "plyfile", "open3d"):
            out = {"bench": "io", "case": "ply_read", "reader": kind, "splats": n,
                   "file_mb": round(size / 2**20)}
            if kind == "open3d" and not _has_open3d():
                out["skipped"] = "open3d not installed (pip install splatedit[bench])"
            else:
                out.update(_child(kind, path))
            if kind == "splatedit":
                out["generate_s"] = round(gen, 2)
            yield out
        path.unlink()


def write_normals_radius_ply(path: Path, n: int) -> int:
    """Write ``n`` points of a unit Fibonacci sphere as float32 x y z nx ny nz
    radius (the radius: 1.5x the spacing of a hexagonal sampling of the
    sphere), ``_CHUNK`` at a time.  Returns the file size in bytes."""
    names = ("x", "y", "z", "nx", "ny", "nz", "radius")
    head = ["ply", "format binary_little_endian 1.0", f"element vertex {n}"]
    head += [f"property float {p}" for p in names] + ["end_header", ""]
    radius = 1.5 * np.sqrt(2.0 * 4.0 * np.pi / (np.sqrt(3.0) * n))
    with open(path, "wb") as fh:
        fh.write("\n".join(head).encode("ascii"))
        for lo in range(0, n, _CHUNK):
            nrm, _, _ = fibonacci_sphere(n, lo, min(n, lo + _CHUNK))
            arr = np.empty((len(nrm), 7), dtype="<f4")
            arr[:, :3], arr[:, 3:6], arr[:, 6] = nrm, nrm, radius
            fh.write(arr.tobytes())
    return path.stat().st_size


def _process(cmd) -> dict:
    """Run ``cmd``; its wall seconds and peak resident memory (``wait4``), or
    ``skipped`` with its last stderr line when it fails."""
    env = dict(os.environ)
    env.setdefault("NUMPY_MADVISE_HUGEPAGE", "0")
    t0 = time.perf_counter()
    try:
        proc = subprocess.Popen([str(c) for c in cmd], stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE, env=env)
    except OSError as exc:                       # no such interpreter
        return {"skipped": str(exc)[:200]}
    _, status, usage = os.wait4(proc.pid, 0)
    dt = time.perf_counter() - t0
    err = proc.stderr.read().decode(errors="replace")
    proc.stderr.close()
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        return {"skipped": ((err.strip().splitlines() or ["failed"])[-1])[:200]}
    return {"seconds": round(dt, 2), "peak_rss_mb": round(usage.ru_maxrss / 1024)}


def bench_large_file(n: int, tmp: Path) -> Iterator[dict]:
    """``info`` and ``render`` of a normals + radius PLY as whole processes,
    each beside Open3D's read of the same file (module docstring)."""
    path = tmp / f"scan{n}.ply"
    size = write_normals_radius_ply(path, n)
    o3d_python = _open3d_python()
    o3d_code = "import sys, open3d as o3d; print(len(o3d.io.read_point_cloud(sys.argv[1]).points))"
    cli = [sys.executable, "-m", "splatedit.cli", "-q"]
    for case, cmd in (("info_file", cli + ["info", path]),
                      ("render_file", cli + ["render", path, "-o", tmp / "render.png", "-f"])):
        out = {"bench": "io", "case": case, "splats": n, "file_mb": round(size / 2**20)}
        out.update(_process(cmd))
        o3d = _process([o3d_python, "-c", o3d_code, path])
        if "skipped" in o3d:
            out["open3d"] = "not available: " + o3d["skipped"] + " (set SPLATEDIT_OPEN3D_PYTHON)"
        else:
            out["open3d_s"], out["open3d_peak_rss_mb"] = o3d["seconds"], o3d["peak_rss_mb"]
            if "seconds" in out:
                out["ratio_to_open3d"] = round(out["seconds"] / o3d["seconds"], 2)
        out["load"] = round(os.getloadavg()[0], 1)
        yield out
    path.unlink()


def scan_cloud(n: int, seed: int = 0):
    """A synthetic georeferenced terrain tile: ``n`` points on a 1 km
    rolling surface at UTM-like coordinates (x ~ 500,000, y ~ 5,000,000 m)
    quantised to millimetres, with RGB, intensity and classification; splats
    sized from the grid spacing (no estimation)."""
    from splatedit.model.cloud import SplatCloud
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0, 1000, size=(n, 2))
    z = 200 + 5 * np.sin(xy[:, 0] / 50) * np.cos(xy[:, 1] / 70)
    world = np.round(np.column_stack([xy[:, 0] + 500_000, xy[:, 1] + 5_000_000, z]), 3)
    origin = np.array([500_500.0, 5_000_500.0, 200.0])
    h = 1000 / np.sqrt(n)
    u = np.zeros((n, 3))
    v = np.zeros((n, 3))
    u[:, 0] = h
    v[:, 1] = h
    colors = np.column_stack([rng.integers(0, 256, (n, 3)), np.full(n, 255)]).astype(np.uint8)
    return SplatCloud(world - origin, u, v, colors, name=f"tile{n}", origin=origin,
                      intensity=rng.integers(0, 65536, n), classification=rng.integers(1, 7, n))


def bench_las(n: int, tmp: Path) -> Iterator[dict]:
    import laspy
    from splatedit.io import read, write
    cloud = scan_cloud(n)
    for ext in (".las", ".laz"):
        path = tmp / f"tile{ext}"
        t0 = time.perf_counter()
        write(path, cloud, overwrite=True)
        tw = time.perf_counter() - t0
        t0 = time.perf_counter()
        back = read(path)
        tr = time.perf_counter() - t0
        t0 = time.perf_counter()
        laspy.read(path)
        tl = time.perf_counter() - t0
        same = bool(np.array_equal(np.round(back.world_positions() * 1000),
                                   np.round(cloud.world_positions() * 1000)))
        yield {"bench": "io", "case": ext[1:] + "_write", "points": n, "seconds": round(tw, 3),
               "file_mb": round(path.stat().st_size / 2**20, 1)}
        yield {"bench": "io", "case": ext[1:] + "_read", "points": n, "seconds": round(tr, 3),
               "laspy_read_s": round(tl, 3), "mm_exact": same}


def bench_io(*, quick: bool = False, large: bool = False, counts=None, las_points: int | None = None
             ) -> Iterator[dict]:
    """The PLY reads (``counts`` splats, default by ``quick`` / ``large``) and
    the LAS round trip (``las_points``)."""
    counts = counts or ((200_000,) if quick else ((1_000_000, 10_000_000) if large else (1_000_000,)))
    with tempfile.TemporaryDirectory(prefix="splatedit-bench-io-") as tmp:
        yield from bench_ply_read(counts, Path(tmp))
        if large:
            yield from bench_large_file(max(counts), Path(tmp))
        yield from bench_las(las_points or (20_000 if quick else 1_000_000), Path(tmp))
