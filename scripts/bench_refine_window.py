"""Progressive refinement in the real editor window (Xvfb, lavapipe).

    PYTHONPATH=$PWD python scripts/bench_refine_window.py 1000000 4000000 [--size 1280x720] [--dir /tmp]
        [--modes progressive,background] [--repeats 2]

For each count: writes a bunny-surface model (``bench_editor``'s cloud) as
binary PLY, opens it in the editor under a private Xvfb with a status file,
and once it is idle: scrolls the wheel once (a camera change) and waits for
the refinement of the new view.  One JSON line per model: time to the first
refined chunk and to full quality after motion stopped, frame times while
refining (whole presented frames), the number of steps, and the input
latency (wheel event sent during refinement -> the new camera in the status
file), and the time from that event to the status showing the full-quality
frame of the new view (``wheel_to_full_quality_s``, for
the progressive refinement and the background refiner alike.  The
background refiner (a second Vulkan device) is gone since the progressive
refinement became the default; ``--modes background`` (it sets
``SPLATEDIT_REFINE=background`` for the editor) measures it on an older
revision (``PYTHONPATH`` of a checkout before branch progdefault).  With the
background refiner a status written before the level-of-detail frame can
still say full quality: a figure near 0.1 s is that race, not a frame).  Needs Xvfb and
xdotool.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))     # also when loaded by path (the tests)
from xvfb_display import start_xvfb  # noqa: E402




def _status(path: Path) -> dict:
    try:
        return json.loads(path.read_text())
    except (FileNotFoundError, json.JSONDecodeError):
        return {}


def _wait(path: Path, cond, timeout: float, proc=None) -> dict:
    t0 = time.time()
    while time.time() - t0 < timeout:
        if proc is not None and proc.poll() is not None:
            raise RuntimeError(f"the editor exited with code {proc.returncode}")
        s = _status(path)
        if s and cond(s):
            return s
        time.sleep(0.02)
    raise TimeoutError(f"last status: { {k: _status(path).get(k) for k in ('idle', 'refining', 'last_refinement')} }")


def measure(n: int, size: tuple[int, int], folder: Path, display: str, mode: str) -> dict:
    from splatedit.bench.editor import bunny_surface_cloud
    from splatedit.io import write
    model = folder / f"refine_bench_{n}.ply"
    if not model.exists():
        write(model, bunny_surface_cloud(n), overwrite=True)
    st = folder / f"refine_status_{n}.json"
    st.unlink(missing_ok=True)
    env = dict(os.environ, DISPLAY=display, SPLATEDIT_REFINE=mode)
    progressive = mode == "progressive"
    log = open(folder / f"refine_editor_{n}.log", "w")
    ed = subprocess.Popen([sys.executable, "-m", "splatedit.app.editor", str(model), "--status-file", str(st),
                           "--size", f"{size[0]}x{size[1]}"], env=env, stdout=log, stderr=subprocess.STDOUT)
    try:
        t_open = time.time()
        s = _wait(st, proc=ed, cond=lambda s: s.get("idle") and s.get("full_quality")
                  and (s.get("last_refinement") or not progressive), timeout=600)
        opened_s = time.time() - t_open
        # a camera change: one wheel step over the model, then the refinement of the new view
        def xdo(*a):
            subprocess.run(["xdotool", *map(str, a)], env=env, check=True)
        xdo("mousemove", size[0] // 2, size[1] // 2)
        d0 = s["camera"]["distance"]
        xdo("click", 5)
        _wait(st, proc=ed, cond=lambda s: s["camera"]["distance"] != d0, timeout=60)
        if progressive:
            _wait(st, proc=ed, cond=lambda s: s.get("refining") is not None and s["refining"] > 0.55, timeout=300)
        else:        # the background refiner: its frame is under way
            time.sleep(0.5)
        # input during refinement: a second wheel step, time until the status shows it
        d1 = _status(st)["camera"]["distance"]
        t_in = time.time()
        xdo("click", 4)
        _wait(st, proc=ed, cond=lambda s: s["camera"]["distance"] != d1, timeout=60)
        latency = time.time() - t_in
        # full quality of the last view (either refiner), from the wheel event
        s = _wait(st, proc=ed, cond=lambda s: s.get("idle") and s.get("full_quality") and s["camera"]["distance"] != d1
                  and (s.get("last_refinement") or not progressive), timeout=600)
        wheel_to_full = time.time() - t_in
        lr = s["last_refinement"] if progressive else {}
        return {"case": "editor_refine_window", "refine": "progressive" if progressive else "background",
                "splats": n, "size": list(size), "open_to_full_quality_s": round(opened_s, 2),
                "wheel_to_full_quality_s": round(wheel_to_full, 2),
                "input_latency_during_refine_ms": round(latency * 1e3),
                "moving_frame_ms_median": s.get("moving_frame_ms_median"), **lr}
    finally:
        ed.kill()
        ed.wait(10)
        log.close()


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("counts", type=int, nargs="+")
    ap.add_argument("--size", default="1280x720")
    ap.add_argument("--dir", default=tempfile.gettempdir())
    ap.add_argument("--modes", default=os.environ.get("SPLATEDIT_REFINE", "progressive"),
                    help="comma-separated refinement modes run in turn (progressive, background)")
    ap.add_argument("--repeats", type=int, default=1, help="rounds over the modes")
    a = ap.parse_args()
    size = tuple(int(x) for x in a.size.split("x"))
    proc, display = start_xvfb("1600x1000")
    try:
        for n in a.counts:
            for _ in range(a.repeats):
                for mode in a.modes.split(","):
                    out = measure(n, size, Path(a.dir), display, mode)
                    out["load_average"] = [round(x, 2) for x in os.getloadavg()]
                    print(json.dumps(out), flush=True)
    finally:
        proc.terminate()
        proc.wait(5)


if __name__ == "__main__":
    main()
