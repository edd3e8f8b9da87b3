"""``splatedit bench outofcore [--file F.copc.laz]``: a COPC scan used out of
core, each step beside laspy doing the same reading in the same run.

Cases (one dict each; every step runs in a fresh Python process, so that
``peak_rss_mb`` is its own):

* ``open``: :meth:`CopcFile.open` (header, VLRs, every hierarchy page) beside
  ``laspy.CopcReader.open`` (header and root hierarchy page).
* ``levels``: the points of the top levels (those ``render`` draws at most
  from the default view, by default levels 0..3): :meth:`CopcFile.read` of
  those nodes beside ``CopcReader.query(level=range(0, L + 1))`` (the same
  nodes).
* ``region``: the nodes of the sphere edit's region (below): ours beside
  ``CopcReader.query(bounds=...)`` (same nodes, laspy then filters).
* ``first_image``: ``splatedit render FILE -o x.png`` at 1280x720 from the
  default view, the whole process (imports, open, node choice, read, splat
  estimation, lavapipe frame); its points and nodes.
* ``edit_to_saved``: ``splatedit deform FILE --edit sphere.json -o out.copc.laz``,
  the whole process, beside a plain copy of the file (``shutil.copyfile``:
  the floor of writing it all).
* ``full_read``: every point, ours streamed (:meth:`CopcFile.read` of
  about 2M points of nodes at a time, nothing kept: bounded memory) beside
  ``laspy.read`` (all in memory) of the same file and of a plain LAZ of the
  same points when one is given (``--file`` ``X.copc.laz`` looks for
  ``X.laz``); laspy's reads are skipped when the records (with laspy's
  copies: 50 bytes a point measured, 5.05 GB at 100M) would not fit in a third of the free
  memory.

The sphere edit: a ground point near the file's centre (class 2 when the
file has classes), support radius 1 % of the horizontal extent (at least 8
units), a handle of a quarter of that raised by a fifth of it.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Iterator

import numpy as np

_CHILD = r"""
import json, sys, time
def rss_mb(key="VmRSS:"):
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith(key):
                return int(line.split()[1]) / 1024
kind = sys.argv[1]
args = json.loads(sys.argv[2])
import numpy as np
out = {}
if kind.startswith("laspy"):
    import laspy
else:
    from splatedit.io.copc import CopcFile, NodeKey
base = rss_mb()
t0 = time.perf_counter()
if kind == "open":
    f = CopcFile.open(args["path"]); out["nodes"] = len(f.nodes)
elif kind == "laspy_open":
    r = laspy.CopcReader.open(args["path"]); out["root_page_entries"] = len(r.root_page.entries)
elif kind == "read":
    f = CopcFile.open(args["path"])
    keys = [n.key for n in f.select(bounds=args.get("bounds"), max_depth=args.get("max_depth"))]
    b = f.read(keys); out["points"] = len(b); out["nodes"] = len(keys)
elif kind == "stream":
    f = CopcFile.open(args["path"])
    keys = [n.key for n in f.select()]
    total, i = 0, 0
    while i < len(keys):       # about 2M points at a time, nothing kept
        j, pts = i, 0
        while j < len(keys) and (j == i or pts + f.nodes[keys[j]].point_count <= 2_000_000):
            pts += f.nodes[keys[j]].point_count
            j += 1
        total += len(f.read(keys[i:j]))
        i = j
    out["points"] = total; out["nodes"] = len(keys)
elif kind == "laspy_query":
    r = laspy.CopcReader.open(args["path"])
    kw = {}
    if args.get("max_depth") is not None:
        kw["level"] = range(0, args["max_depth"] + 1)
    if args.get("bounds") is not None:
        b = np.array(args["bounds"])
        kw["bounds"] = laspy.copc.Bounds(mins=b[0], maxs=b[1])
    p = r.query(**kw); out["points"] = len(p)
elif kind == "laspy_read":
    las = laspy.read(args["path"]); out["points"] = len(las.points)
elif kind == "cli":
    from splatedit.cli import main
    import contextlib, io
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = main(args["argv"])
    out["rc"] = rc; out["stdout"] = buf.getvalue().strip().splitlines()[-1:]
out["seconds"] = round(time.perf_counter() - t0, 3)
out["peak_rss_mb"] = round(rss_mb("VmHWM:")); out["base_rss_mb"] = round(base)
print(json.dumps(out))
"""


def _child(kind: str, **args) -> dict:
    env = dict(os.environ)
    root = str(Path(__file__).resolve().parent.parent.parent)
    env["PYTHONPATH"] = root + os.pathsep + env.get("PYTHONPATH", "")
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-c", _CHILD, kind, json.dumps(args)], capture_output=True,
                       text=True, env=env)
    if r.returncode != 0:
        return {"error": (r.stderr.strip().splitlines() or ["failed"])[-1]}
    out = json.loads(r.stdout.strip().splitlines()[-1])
    out["process_seconds"] = round(time.perf_counter() - t0, 3)
    return out


def sphere_edit(path) -> tuple[dict, np.ndarray]:
    """The benchmark's sphere edit of the COPC file ``path`` (local
    coordinates, see the module docstring) and its world box (2, 3)."""
    from splatedit.io.copc import CopcFile, file_origin
    with CopcFile.open(path) as f:
        origin = file_origin(f)
        lo, hi = f.point_bounds
        mid = (lo + hi) / 2
        r = max(8.0, 0.01 * float(np.max(hi[:2] - lo[:2])))
        box = np.array([[mid[0] - 2 * r, mid[1] - 2 * r, lo[2]], [mid[0] + 2 * r, mid[1] + 2 * r, hi[2]]])
        b = f.read(f.select(bounds=box))
        ground = b.records["classification"] == 2
        pick = ground if ground.sum() > 100 else np.ones(len(b), bool)
        d = np.linalg.norm(b.xyz[pick, :2] - mid[:2], axis=1)
        c = b.xyz[pick][np.argmin(d)] - origin
    script = {"version": 1, "edits": [{
        "support": {"sphere": {"center": c.tolist(), "radius": r}},
        "handle": {"sphere": {"center": c.tolist(), "radius": r / 4}},
        "transform": {"translate": [0.0, 0.0, r / 5]}}]}
    return script, np.stack([c + origin - r, c + origin + r])


def bench_outofcore(path=None, *, points: int = 1_000_000, levels: int = 3) -> Iterator[dict]:
    """The cases of the module docstring on ``path`` (default: a generated
    terrain of ``points`` points in a temporary folder)."""
    tmp = Path(tempfile.mkdtemp(prefix="splatedit-bench-ooc-"))
    try:
        laz = None
        if path is None:
            from splatedit.bench.terrain import write_terrain_copc
            path = tmp / "terrain.copc.laz"
            laz = tmp / "terrain.laz"
            write_terrain_copc(path, points, laz_path=laz)
        else:
            path = Path(path)
            name = path.name[:-len(".copc.laz")] if path.name.lower().endswith(".copc.laz") else None
            if name and (path.parent / f"{name}.laz").exists():
                laz = path.parent / f"{name}.laz"
        from splatedit.io.copc import CopcFile
        with CopcFile.open(path) as f:
            n, nodes = f.point_count, len(f.nodes)
        common = {"bench": "outofcore", "file": str(path), "points": n, "nodes": nodes,
                  "file_mb": round(os.path.getsize(path) / 1e6, 1), "load_avg": round(os.getloadavg()[0], 2)}
        yield {**common, "case": "open", "splatedit": _child("open", path=str(path)),
               "laspy": _child("laspy_open", path=str(path))}
        yield {**common, "case": "levels", "levels": f"0..{levels}",
               "splatedit": _child("read", path=str(path), max_depth=levels),
               "laspy": _child("laspy_query", path=str(path), max_depth=levels)}
        script, box = sphere_edit(path)
        yield {**common, "case": "region", "box": box.tolist(),
               "splatedit": _child("read", path=str(path), bounds=box.tolist()),
               "laspy": _child("laspy_query", path=str(path), bounds=box.tolist())}
        png = tmp / "first.png"
        yield {**common, "case": "first_image", "size": "1280x720",
               "splatedit": _child("cli", argv=["-q", "render", str(path), "-o", str(png), "--force"])}
        edit = tmp / "sphere.json"
        edit.write_text(json.dumps(script))
        out = tmp / "edited.copc.laz"
        t0 = time.perf_counter()
        shutil.copyfile(path, tmp / "copy.copc.laz")
        copy_s = time.perf_counter() - t0
        os.unlink(tmp / "copy.copc.laz")
        yield {**common, "case": "edit_to_saved", "edit": script["edits"][0],
               "splatedit": _child("cli", argv=["-q", "deform", str(path), "--edit", str(edit), "-o", str(out),
                                                "--force"]),
               "copy_seconds": round(copy_s, 3)}
        avail = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        line = {**common, "case": "full_read", "splatedit": _child("stream", path=str(path))}
        if n * 55 < avail / 3:
            line["laspy_copc"] = _child("laspy_read", path=str(path))
            if laz is not None:
                line["laspy_laz"] = _child("laspy_read", path=str(laz))
        else:
            line["laspy_skipped"] = f"{n} points need about {n * 55 / 1e9:.1f} GB"
        yield line
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
