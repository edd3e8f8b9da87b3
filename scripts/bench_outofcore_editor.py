"""Out of core, the editor side (issue 23 item 3): ``splatedit edit`` on a large
COPC scan driven under Xvfb with xdotool, beside laspy reading the same nodes
in the same run.

Measured (wall clock, the status file polled every 50 ms):

* open to first frame: process start -> the first presented frame of the scan;
* top view refined: numpad 7 -> the view's nodes shown (background job);
* stroke to preview: the support stroke's mouse-up -> its region shown at full
  resolution with the support spread to it; then the handle's fit;
* commit of G Z 2 and edit to saved: Ctrl+S -> the COPC written (streamed
  through ``rewrite_copc``);
* peak resident memory of the editor process (VmHWM);
* laspy (``CopcReader``, lazrs) reading the first view's levels and the region's
  box, the same nodes, in the same run.

Usage: ``python scripts/bench_outofcore_editor.py SCAN.copc.laz [--size 1280x720] [--budget FIRST,BUDGET]``
(needs Xvfb, xdotool, lavapipe or a GPU).  Prints one table.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))     # also when loaded by path (the tests)
from xvfb_display import start_xvfb  # noqa: E402

import numpy as np

ROOT = Path(__file__).resolve().parents[1]




class Editor:
    def __init__(self, scan: Path, tmp: Path, display: str, size: str, budget: str | None):
        self.status_path = tmp / "status.json"
        self.log = open(tmp / "editor.log", "w")
        env = dict(os.environ, DISPLAY=display, PYTHONPATH=str(ROOT), XDG_CONFIG_HOME=str(tmp / "config"),
                   XDG_STATE_HOME=str(tmp / "state"), SPLATEDIT_RECOVERY_DIR=str(tmp / "recovery"))
        env.pop("SPLATEDIT_VALIDATION", None)
        if budget:
            env["SPLATEDIT_OOC_BUDGET"] = budget
        self.env = env
        self.t0 = time.perf_counter()
        self.proc = subprocess.Popen([sys.executable, "-m", "splatedit.app.editor", str(scan), "--size", size,
                                      "--status-file", str(self.status_path), "--save-as", str(tmp / "edited.copc.laz"),
                                      "--out-of-core", "on"],
                                     env=env, stdout=self.log, stderr=subprocess.STDOUT, cwd=tmp)

    def status(self) -> dict:
        try:
            return json.loads(self.status_path.read_text())
        except (FileNotFoundError, json.JSONDecodeError):
            return {}

    def wait(self, cond, what: str, timeout: float = 600.0) -> tuple[dict, float]:
        t = time.perf_counter()
        while time.perf_counter() - t < timeout:
            s = self.status()
            try:
                if s and cond(s):
                    return s, time.perf_counter()
            except (KeyError, TypeError):
                pass
            if self.proc.poll() is not None:
                raise SystemExit(f"the editor ended while waiting for {what}: see {self.log.name}")
            time.sleep(0.05)
        raise SystemExit(f"timed out waiting for {what}; last status {self.status()}")

    def say(self, *a):
        print(*a, flush=True)

    def xdo(self, *args) -> float:
        subprocess.run(["xdotool", *map(str, args)], env=self.env, check=True, timeout=60)
        return time.perf_counter()

    def peak_rss_mb(self) -> float:
        for line in Path(f"/proc/{self.proc.pid}/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024.0
        return float("nan")

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(10)
        self.log.close()


def laspy_read(scan: Path, *, levels: int | None = None, box=None) -> tuple[float, int]:
    """Seconds and points of laspy's CopcReader reading levels 0..levels-1, or every level in ``box``."""
    import laspy
    t = time.perf_counter()
    with laspy.CopcReader.open(str(scan)) as r:
        if box is not None:
            pts = r.query(bounds=laspy.copc.Bounds(mins=np.asarray(box[0]), maxs=np.asarray(box[1])))
        else:
            pts = r.query(level=range(0, levels))
        n = len(pts)
        _ = np.asarray(pts.x), np.asarray(pts.y), np.asarray(pts.z)
    return time.perf_counter() - t, n


def note(rows: list, row: tuple) -> None:
    """Keep a result row and show it at once on stderr (a run cut short keeps its rows)."""
    rows.append(row)
    print(f"  {row[0]}: {row[1]:.2f} {row[2]}", file=sys.stderr, flush=True)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scan", type=Path)
    ap.add_argument("--size", default="1280x720")
    ap.add_argument("--zoom", type=int, default=14, help="wheel steps toward the centre before the edit")
    ap.add_argument("--budget", help="FIRST,BUDGET points (SPLATEDIT_OOC_BUDGET; default the editor's)")
    a = ap.parse_args(argv)
    for tool in ("Xvfb", "xdotool"):
        if shutil.which(tool) is None:
            raise SystemExit(f"{tool} is not installed")
    rows = []
    load0 = os.getloadavg()[0]
    with tempfile.TemporaryDirectory(prefix="bench-ooc-") as td:
        tmp = Path(td)
        xvfb, display = start_xvfb("1400x900", fbdir=tmp)
        ed = None
        try:
            ed = Editor(a.scan.resolve(), tmp, display, a.size, a.budget)
            s, t = ed.wait(lambda s: s["loaded"] and s["frames_presented"] > 0 and s["out_of_core"], "first frame")
            first = s["out_of_core"]
            note(rows, ("open to first frame", t - ed.t0, f"{first['shown']:,} of {first['points']:,} points "
                         f"(depth <= {first['max_depth_shown']})"))
            w, h = s["window"]
            cx, cy = (w + (s["panel_box"][0] + s["panel_box"][2])) // 2, h // 2
            t0 = ed.xdo("mousemove", cx, cy, "key", "KP_7")
            s, t = ed.wait(lambda s: s["out_of_core"]["refined"] and "nodes" not in s["jobs"]
                           and s["out_of_core"]["nodes_shown"] != first["nodes_shown"], "top view refined")
            oc = s["out_of_core"]
            note(rows, ("top view refined (numpad 7)", t - t0, f"{oc['shown']:,} points, {oc['nodes_shown']} nodes, "
                         f"depth <= {oc['max_depth_shown']}; {oc['loading_frames']} frames during "
                         f"{oc['loading_seconds']:.1f} s of loading"))
            d0 = s["camera"]["distance"]
            t0 = ed.xdo("mousemove", cx, cy, *(["click", "4"] * a.zoom))
            s, t = ed.wait(lambda s: s["out_of_core"]["refined"] and "nodes" not in s["jobs"]
                           and s["camera"]["distance"] < 0.99 * d0, "zoomed view refined")
            oc = s["out_of_core"]
            note(rows, (f"zoom in x{a.zoom} refined", t - t0, f"{oc['shown']:,} points, depth <= {oc['max_depth_shown']}; "
                         f"{oc['loading_frames']} frames during {oc['loading_seconds']:.1f} s of loading (total)"))
            ed.wait(lambda s: s["idle"], "idle")
            n0 = ed.status()["n"]
            ed.xdo("mousemove", cx - 40, cy - 10, "mousedown", "1", "mousemove", cx, cy - 10,
                   "mousemove", cx + 40, cy - 10, "mousemove", cx + 40, cy + 15, "mousemove", cx - 40, cy + 15,
                   "sleep", "0.1")
            t0 = ed.xdo("mouseup", "1")
            s, t = ed.wait(lambda s: s["support"] > 0 and s["n"] > n0 and s["out_of_core"]["waiting"] is None
                           and "region" not in s["jobs"], "region at full resolution")
            region = s["out_of_core"]["region"]
            note(rows, ("stroke to preview (region at full resolution)", t - t0,
                         f"support {s['support']:,}, {s['n'] - n0:,} points loaded"))
            t0 = ed.xdo("key", "2", "mousemove", cx, cy, "click", "1")
            s, t = ed.wait(lambda s: s["handle"] > 0 and s["state"] == "ready", "handle fitted")
            note(rows, ("handle to fitted", t - t0, f"handle {s['handle']:,}"))
            t0 = ed.xdo("mousemove", cx + 30, cy, "key", "g", "z", "2", "Return")
            s, t = ed.wait(lambda s: s["edits"] == 1 and s["state"] != "committing", "commit")
            note(rows, ("G Z 2 Enter to committed", t - t0, ""))
            t0 = ed.xdo("key", "ctrl+s")
            s, t = ed.wait(lambda s: s["saved"] and not s["dirty"], "saved")
            size = Path(s["saved"]).stat().st_size / 2**20
            note(rows, ("edit to saved (Ctrl+S, streamed)", t - t0, f"{size:,.0f} MiB written"))
            rss = ed.peak_rss_mb()
            note(rows, ("peak resident memory (VmHWM)", rss / 1024.0, "GiB"))
        finally:
            if ed is not None:
                ed.close()
            xvfb.kill()
            xvfb.wait(10)
    lt, ln = laspy_read(a.scan, levels=first["max_depth_shown"] + 1)
    note(rows, ("laspy CopcReader: the first view's levels", lt, f"{ln:,} points"))
    if region is not None:
        lt, ln = laspy_read(a.scan, box=region)
        note(rows, ("laspy CopcReader: the region's box, all levels", lt, f"{ln:,} points"))
    print("| step | seconds | notes |\n|---|---|---|")
    for name, sec, text in rows:
        print(f"| {name} | {sec:.2f} | {text} |")
    print(f"\nload average at start {load0:.2f}, at end {os.getloadavg()[0]:.2f}; {os.cpu_count()} cores")
    return 0


if __name__ == "__main__":
    sys.exit(main())
