"""Where an editor frame goes: moving and still frames in the real window (issue 19 item 9).

    PYTHONPATH=$PWD python scripts/bench_editor_window_frames.py [bunny] [100000] [1000000]
        [--size 1280x720] [--frames 30] [--profile] [--no-panel] [--dir /tmp]

For each model (``bunny``: the bundled model; a number: ``bench editor``'s
bunny-surface cloud of that many splats, written as binary PLY) the editor is
opened in-process under a private Xvfb (GUI on, lavapipe, vsync off) and its
event loop runs as usual; the window's ``poll`` is wrapped so that, once the
model and its level-of-detail pyramid are loaded, every loop iteration orbits
the camera a little (a moving frame, as a drag of the middle button does),
then stops and lets the still view refine.  Timers wrap the loop's stages:
``events`` (window poll + event handling), ``jobs`` (finished jobs, session
poll), ``sync`` (document -> viewport), ``render`` (the scene renderer's frame:
``Viewport.render``), ``refine`` (progressive steps of the still view),
``gui`` (Dear ImGui layout: ``EditorGui.build``), ``present`` (GUI pass +
blit + submit + present: ``render_frame``), ``status`` (status file,
validation) and ``other`` (the rest of the iteration).

In the same run, after the window's frames, the render-only frame of the same
scene: ``Viewport.render`` of the same camera and configuration without GUI
or present (what ``splatedit bench editor`` measures), moving and still.
``--profile`` adds cProfile's top functions (cumulative) of the moving frames.
One JSON line per model; the load average is in each line.
"""

from __future__ import annotations

import argparse
import cProfile
import io
import json
import os
import pstats
import subprocess
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))     # also when loaded by path (the tests)
from xvfb_display import start_xvfb  # noqa: E402




def _model(spec: str, folder: Path) -> Path:
    if spec == "bunny":
        from splatedit.data import default_model_path
        return Path(default_model_path())
    n = int(float(spec))
    path = folder / f"bench_fps_bunny{n}.ply"
    if not path.exists():
        from splatedit.bench.editor import bunny_surface_cloud
        from splatedit.io import write
        write(path, bunny_surface_cloud(n))
    return path


class Stages:
    """Per-iteration stage timers (ms)."""

    def __init__(self):
        self.cur: dict[str, float] = {}

    def wrap(self, obj, name: str, stage: str):
        fn = getattr(obj, name)

        def timed(*a, **k):
            t0 = time.perf_counter()
            try:
                return fn(*a, **k)
            finally:
                self.cur[stage] = self.cur.get(stage, 0.0) + (time.perf_counter() - t0) * 1e3
        setattr(obj, name, timed)


def _median(xs):
    xs = sorted(xs)
    return round(xs[len(xs) // 2], 1) if xs else None


def measure(spec: str, size, frames: int, folder: Path, profile: bool, panel: bool = True) -> dict:
    from splatedit.app.editor import Editor
    from splatedit.tolerances import EDITOR_LOD_MIN_SPLATS
    path = _model(spec, folder)
    w, h = size
    ed = Editor(path, size=size, vsync=False, max_seconds=600)
    st = Stages()
    fr = ed.frames
    st.wrap(ed.routing, "handle_events", "events")
    st.wrap(ed.file_actions, "poll_jobs", "jobs")
    st.wrap(fr, "sync_document", "sync")
    st.wrap(ed.viewport, "render", "render")
    st.wrap(fr, "_progressive_step", "refine")
    if ed.gui is not None:
        st.wrap(ed.gui, "build", "gui")
    st.wrap(ed.presenter, "render_frame", "present")
    st.wrap(ed, "write_status", "status")
    st.wrap(ed, "collect_validation", "status")
    rows = {"moving": [], "still": []}
    state = {"phase": "load", "t_iter": None, "n": 0, "refinements": None, "prof": None, "t_phase": 0.0}
    poll = ed.window.poll

    def loaded() -> bool:
        vp = ed.viewport
        return (ed.session is not None and not ed.jobs and vp.cloud is not None
                and (vp.pyramid is not None or not ed.use_lod or vp.cloud.n < EDITOR_LOD_MIN_SPLATS)
                and fr.scene_key is not None)

    def iteration_poll(timeout):
        now = time.perf_counter()
        # close the previous iteration's record
        if state["t_iter"] is not None and state["phase"] in rows and fr.frames > state["frames0"]:
            total = (now - state["t_iter"]) * 1e3
            rec = dict(st.cur)
            rec["total"] = total
            rec["other"] = total - sum(v for k, v in st.cur.items())
            info = ed.viewport.last_info
            rec["splats"] = info.splats if info else None
            rec["div"] = info.div if info else None
            sc = ed.viewport.splats
            slot = sc.lod_slot if (info is not None and info.lod and sc.lod_slot is not None) else sc.full
            for k, v in (getattr(slot.r, "last_timings_ms", None) or {}).items():
                rec["gpu_" + k] = v
            rows[state["phase"]].append(rec)
        st.cur = {}
        state["t_iter"] = time.perf_counter()
        state["frames0"] = fr.frames
        ph = state["phase"]
        if ph == "load" and now - t_start > 300:
            ed.running = False
            state["phase"] = "done"
        if ph == "load" and loaded():
            state["phase"], state["t_phase"] = "warm", now
            if not panel and ed.panel_visible:
                ed.toggle_panel()            # the side panel hidden (its share of the GUI pass)
            state["n"] = 0
        if state["phase"] == "warm":
            state["n"] += 1
            ed.cam.orbit(2.0, 0.0)
            ed.motion()
            if state["n"] > 8:
                state["phase"] = "moving"
                if profile:
                    state["prof"] = cProfile.Profile()
                    state["prof"].enable()
        elif state["phase"] == "moving":
            if len(rows["moving"]) >= frames:
                if state["prof"] is not None:
                    state["prof"].disable()
                state["phase"], state["t_phase"] = "still", now
                state["refinements"] = fr.refinements
            else:
                ed.cam.orbit(2.0, 0.0)
                ed.motion()
        elif state["phase"] == "still":
            refined = fr.refinements > state["refinements"]
            settled = not fr.pending() and not fr.busy() and now - state["t_phase"] > 1.0
            if refined or settled or now - state["t_phase"] > 120:
                state["phase"] = "done"
                state["still_s"] = now - state["t_phase"]
                ed.running = False
        return poll(0.0 if state["phase"] in ("warm", "moving") else timeout)

    ed.window.poll = iteration_poll
    t_start = time.perf_counter()
    try:
        ed.run()
        # render-only frames of the same scene, same run: no GUI, no present
        vp = ed.viewport
        cam = ed.cam
        mov, full = [], []
        for _ in range(max(5, frames // 3)):
            cam.orbit(2.0, 0.0)
            t0 = time.perf_counter()
            vp.render(cam, w, h, interactive=True, resident=True)
            vp.splats.full.r.dev.wait_idle() if hasattr(vp.splats.full.r.dev, "wait_idle") else None
            mov.append((time.perf_counter() - t0) * 1e3)
        lod_info = vp.last_info
        for _ in range(2):
            t0 = time.perf_counter()
            vp.render(cam, w, h, interactive=False, resident=True)
            full.append((time.perf_counter() - t0) * 1e3)
    finally:
        ed.close()
    out = {"case": "editor_window_frames", "model": spec, "splats": int(vp.cloud.n) if vp.cloud is not None else None,
           "width": w, "height": h, "load_avg": os.getloadavg()[0]}
    for ph in ("moving", "still"):
        rs = rows[ph]
        if not rs:
            continue
        keys = sorted({k for r in rs for k in r if k not in ("splats", "div") and not k.startswith("gpu_")})
        gkeys = sorted({k for r in rs for k in r if k.startswith("gpu_")})
        out[f"{ph}_gpu_ms"] = {k[4:]: _median([r.get(k, 0.0) for r in rs]) for k in gkeys}
        out[f"{ph}_frames"] = len(rs)
        out[f"{ph}_ms"] = {k: _median([r.get(k, 0.0) for r in rs]) for k in keys}
        slow = max(rs, key=lambda r: r["total"])
        out[f"{ph}_slowest_ms"] = {k: round(v, 1) for k, v in slow.items() if k not in ("splats", "div")}
        out[f"{ph}_splats"] = rs[-1]["splats"]
        out[f"{ph}_div"] = rs[-1]["div"]
    out["still_to_done_s"] = round(state.get("still_s", float("nan")), 2)
    out["render_only_moving_ms"] = _median(mov)
    out["render_only_moving_splats"] = lod_info.splats if lod_info else None
    out["render_only_moving_div"] = lod_info.div if lod_info else None
    out["render_only_still_ms"] = _median(full)
    if "moving_ms" in out and out["render_only_moving_ms"]:
        out["moving_fps"] = round(1000.0 / out["moving_ms"]["total"], 1)
        out["moving_over_render_only"] = round(out["moving_ms"]["total"] / out["render_only_moving_ms"], 2)
    if state["prof"] is not None:
        s = io.StringIO()
        pstats.Stats(state["prof"], stream=s).sort_stats("cumulative").print_stats(35)
        out["profile"] = s.getvalue()
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("models", nargs="*", default=["bunny", "100000", "1000000"])
    ap.add_argument("--size", default="1280x720")
    ap.add_argument("--frames", type=int, default=30)
    ap.add_argument("--profile", action="store_true")
    ap.add_argument("--dir", default="/tmp")
    ap.add_argument("--no-panel", action="store_true", help="hide the side panel (Tab) while measuring")
    a = ap.parse_args()
    size = tuple(int(x) for x in a.size.split("x"))
    proc = None
    if not os.environ.get("SPLATEDIT_BENCH_KEEP_DISPLAY"):
        proc, disp = start_xvfb("1600x1000")
        os.environ["DISPLAY"] = disp
    try:
        for spec in a.models:
            out = measure(spec, size, a.frames, Path(a.dir), a.profile, panel=not a.no_panel)
            prof = out.pop("profile", None)
            print(json.dumps(out), flush=True)
            if prof:
                print(prof, file=sys.stderr, flush=True)
    finally:
        if proc is not None:
            proc.terminate()
            proc.wait()


if __name__ == "__main__":
    main()
