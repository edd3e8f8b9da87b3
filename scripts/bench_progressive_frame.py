"""Time to full quality: ProgressiveFrame (pre-pass or vertex path) vs one Renderer.render.

    PYTHONPATH=$PWD python scripts/bench_progressive_frame.py 1000000 [--size 1280x720] [--chunks 20000,100000]

In one process, alternating, on the bunny-surface cloud of ``bench_editor``:
the one-submit pre-pass frame (what the former background refiner drew), and a
progressive frame per chunk size stepped to the end (sum of the step wall
times = its time to full quality).  One JSON line per count.
"""

from __future__ import annotations

import argparse
import json
import time


def measure(n: int, size: tuple[int, int], chunks: list[int], repeats: int, vertex: bool) -> dict:
    from splatedit.bench.editor import bunny_surface_cloud
    from splatedit.render.camera import Camera
    from splatedit.render.splat.progressive import ProgressiveFrame
    from splatedit.render.splat.renderer import Renderer
    cloud = bunny_surface_cloud(n)
    w, h = size
    cam = Camera.frame(*cloud.bounds(), aspect=w / h, direction=(0.3, 0.4, 1.0))
    out = {"case": "progressive_frame", "splats": n, "size": list(size), "render_s": []}
    with Renderer(validation=False) as r:
        r.set_cloud(cloud)
        r.render(cam, w, h)                     # pipelines, targets
        for _ in range(repeats):
            t = time.perf_counter()
            r.render(cam, w, h)
            out["render_s"].append(round(time.perf_counter() - t, 3))
            for c in chunks:
                for path in ((True, False) if vertex else (True,)):
                    r.prepass = path
                    with ProgressiveFrame(r, cam, w, h, c) as pf:
                        steps = []
                        while not pf.done:
                            t = time.perf_counter()
                            pf.step()
                            steps.append(time.perf_counter() - t)
                    r.prepass = True
                    key = f"progressive_{'prepass' if path else 'vertex'}_{c}"
                    out.setdefault(key + "_s", []).append(round(sum(steps), 3))
                    out[key + "_steps"] = len(steps)
                    out[key + "_step_max_ms"] = round(max(steps) * 1e3)
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("counts", type=int, nargs="+")
    ap.add_argument("--size", default="1280x720")
    ap.add_argument("--chunks", default="20000,100000,250000")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--vertex", action="store_true", help="also the vertex path")
    a = ap.parse_args()
    size = tuple(int(x) for x in a.size.split("x"))
    chunks = [int(c) for c in a.chunks.split(",")]
    for n in a.counts:
        print(json.dumps(measure(n, size, chunks, a.repeats, a.vertex)), flush=True)


if __name__ == "__main__":
    main()
