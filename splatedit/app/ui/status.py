"""The editor's status file (test hook, ``--status-file``): a JSON snapshot
of what the window shows, rewritten atomically whenever it changes."""

from __future__ import annotations

import dataclasses
import json
import os

import numpy as np

from splatedit.app.document.gaussian import gaussians_of
from splatedit.app.ui.transform_fields import field_target
from splatedit.render.vk import devices_created


def _r(v, nd=1):
    return round(float(v), nd)


def _browser(b) -> dict | None:
    """The file browser's state (None when closed): folder, entry names and kinds, selection."""
    if not b.shown:
        return None
    return {"folder": str(b.folder), "index": b.index, "top": b.top, "rows": b.rows, "typed": b.typed,
            "entries": [[e.kind.value, e.name] for e in b.entries],
            "box": list(b.box) if b.box else None, "row0": b.row0, "line_h": b.line_h}


def status_dict(ed) -> dict:
    """The editor's state as plain JSON types."""
    s = ed.session
    cam = ed.cam
    vp = ed.viewport
    help_ = ed.help
    guard = getattr(ed, "crash_guard", None)
    st = {"loaded": s is not None, "frames_presented": ed.presenter.frames_presented,
          "running": ed.running, "jobs": sorted(ed.jobs), "validation_messages": ed.validation_count,
          "confirm_quit": ed.confirm_quit, "prompt": ed.prompt, "help": help_.shown,
          "help_top": help_.top, "help_rows": help_.rows, "help_total": help_.total,
          "help_box": None if help_.box is None or not help_.shown else
          [help_.box.x, help_.box.y, help_.box.w, help_.box.h],
          "panel_visible": ed.panel_visible and ed.panel_box is not None,
          "window": list(ed.size), "panel_box": list(ed.panel_box) if ed.panel_box else [0, 0, 0, 0],
          "camera": {"distance": round(cam.distance, 6), "yaw": round(cam.yaw, 6), "pitch": round(cam.pitch, 6),
                     "target": [round(float(x), 6) for x in cam.target],
                     "up": [round(float(x), 6) for x in cam.up_axis],
                     "screen_offset": [round(float(x), 6) for x in cam.screen_offset],
                     "pivot": [round(float(x), 6) for x in cam.pivot()]},
          "frame_area": [round(float(x), 6) for x in ed.camera.view_area()],
          "up_axis": ed.camera.up.label, "up_source": ed.camera.up.source.value,
          "grey": bool(vp.grey), "edl": bool(getattr(vp, "edl", False)),
          "two_sided": bool(getattr(vp, "two_sided", False)), "splat_scale": round(float(vp.splat_scale), 4),
          "moving_frame_ms_median": (round(float(np.median(ed.moving_frame_ms)), 1)
                                     if ed.moving_frame_ms else None),
          "interactive_frames": len(vp.interactive_frames_ms),
          "interactive_ms_median": (round(float(np.median(vp.interactive_frames_ms[-30:])), 1)
                                    if vp.interactive_frames_ms else None),
          "last_render": {} if vp.last_info is None else
          {k: (round(v, 1) if isinstance(v, float) else v) for k, v in dataclasses.asdict(vp.last_info).items()},
          "gaussians": s is not None and gaussians_of(s.cloud) is not None,
          "saved": str(ed.saved_path) if ed.saved_path else None,
          "path": str(ed.path) if ed.path else None, "cloud_name": ed.cloud_name,
          "error_box": ed.error_box, "error_rect": list(ed.error_rect) if ed.error_rect else None, "confirm_open": str(ed.confirm_open) if ed.confirm_open else None,
          "browser": _browser(ed.browser), "message": ed.message,
          "script": str(ed.saved_script) if ed.saved_script else None,
          "confirm_restore": str(guard.confirm_restore.model) if guard and guard.confirm_restore else None,
          "restored": str(guard.restored.model) if guard and guard.restored else None,
          "internal_errors": guard.internal_errors if guard else 0}
    gui = getattr(ed, "gui", None)
    st["gui"] = gui is not None
    if gui is not None:
        st["gui_rects"] = {k: [b.x, b.y, b.w, b.h] for k, b in sorted(gui.rects.items())}
        st["gui_wants_mouse"] = bool(gui.wants_mouse)
        st["gui_wants_keyboard"] = bool(gui.wants_keyboard)
        st["gui_menu_open"] = bool(gui.menu_open)
        st["gui_panel_scrolls"] = bool(gui.panel_scrolls)
        st["help_visible_rows"] = int(gui.help_visible_rows)
        st["background"] = [round(float(x), 4) for x in vp.background[:3]]
        st["distortion_map"] = bool(vp.distortion_map)
    if s is None:
        return st
    ss = s.stats()
    tools = ed.selection_tools
    st.update(n=s.cloud.n, state=ss.state, support=ss.support, handle=ss.handle,
              edits=len(s.edits), dirty=s.dirty, undo_position=s.history.position,
              history=len(s.history), manip=None if s.manip is None else s.manip.mode,
              readout=ed.gizmo.readout_text(),
              brush=s.brush_target, fit_error=ss.error, handles=ss.handles,
              active_handle=ss.active_handle, handle_sizes=list(ss.handle_sizes),
              curve_points=ss.curve_points, curve_mode=s.curve_mode,
              pose_pending=ss.pose_pending, columns=ss.columns,
              basis_columns=None if s.basis is None else s.basis.n_columns,
              deformation=s.deformation.value,
              basis_kind=None if s.basis is None else type(s.basis).__name__,
              brush_mode=tools.mode, brush_note=ed.brush.mode_note(), closure_added=tools.last_added,
              closure_highlight=tools.highlighted(s.cloud) is not None,
              history_label=s.history.labels[s.history.position],
              region_armed=ed.region.armed, region_points=len(ed.region.points),
              mirror_painting=ed.mirror.painting, mirror_axis="XYZ"[ed.mirror.axis],
              view_hint_checked=ed.camera.hint_checked(),
              pivot=ed.pivot.mode, axes=ed.pivot.orientation,
              cursor=None if ed.pivot.cursor is None else [round(float(x), 9) for x in ed.pivot.cursor],
              manip_pivot=None if s.manip is None else [round(float(x), 9) for x in s.manip.pivot])
    ft = field_target(s)
    st["fields"] = {"kind": ft.kind.value, "index": ft.index, "problem": ft.problem,
                    "position": None if ft.position is None else [round(float(x), 9) for x in ft.position]}
    st["curve_positions"] = [[round(float(x), 9) for x in q] for q in s.curve_point_positions()]
    st["idle"] = bool(ed.idle())
    oc = getattr(ed, "ooc", None)
    #: an out-of-core scan: its points, the shown nodes and points, the camera state they were chosen for
    st["out_of_core"] = None if oc is None else {
        "points": int(oc.copc.point_count), "nodes_shown": len(oc.segments), "shown": oc.shown_points(),
        "max_depth_shown": max((t[0] for t in oc.shown), default=0), "view_chosen": oc.view_state is not None,
        "refined": oc.view_state == ed.cam.state() and "nodes" not in ed.jobs,
        "waiting": s.waiting, "loading_frames": oc.loading_frames,
        "loading_seconds": round(oc.loading_seconds, 3),
        "region": None if oc.region_world is None else oc.region_world.tolist()}
    cp = ss.commit
    #: a commit running in the background: its stage and fraction done
    st["commit"] = None if cp is None else {"stage": cp.stage, "fraction": round(cp.fraction, 3)}
    st["last_commit_ms"] = round(s.last_commit_seconds * 1e3, 1)
    fr = ed.frames
    pr = fr.progressive
    st["refining"] = None if pr is None else round(pr.frame.fraction, 3)
    #: the shown frame is the full-quality one (not a level of detail / reduced size)
    st["full_quality"] = not fr.scene_interactive
    last = fr.last_progressive
    st["last_refinement"] = None if last is None else last.timings()
    st["refinements"] = fr.refinements
    #: the brush's pick map of this view was drawn after its refinement (no pick on first use)
    st["pick_map_ready"] = fr.take_pick(ed.picking.key()) is not None
    st["vulkan_devices_created"] = devices_created()
    w, h = ed.size
    gz = ed.gizmo
    if not (w and h):
        st.update(gizmo=[], gizmo_rings=[], gizmo_scale=None, gizmo_box=None, curve_dots=[],
                  handle_px=[None] * len(s.selection.handles))
        return st
    st["gizmo"] = [[k, *(_r(v) for v in (*p0, *p1))] for k, p0, p1 in gz.axes(w, h)]
    back = cam.basis()[2]
    st["gizmo_rings"] = [[k, *(_r(v) for v in q), round(abs(float(back[k])), 3)]
                         for k, _ in gz.rings(w, h) for q in [gz.ring_grab_point(k, w, h)] if q is not None]
    grip = gz.scale_circle(w, h)
    st["gizmo_scale"] = None if grip is None else [_r(grip[0][0]), _r(grip[0][1]), grip[1]]
    box = gz.box(w, h)
    st["gizmo_box"] = None if box is None else [_r(v) for v in box]
    st["curve_dots"] = [[_r(v) for v in q] for q in ed.curve.dots(w, h)]
    hc = []
    for k, hm in enumerate(s.selection.handles):
        if hm.any():
            px, _ = cam.project(s.handle_centroid(k), w, h)
            hc.append([_r(px[0, 0]), _r(px[0, 1])])
        else:
            hc.append(None)
    st["handle_px"] = hc
    return st


class StatusWriter:
    """Writes :func:`status_dict` to ``path`` when it changed (atomically)."""

    def __init__(self, path):
        self.path = path
        self._last = None

    def write(self, ed) -> None:
        if self.path is None:
            return
        text = json.dumps(status_dict(ed), sort_keys=True)
        if text != self._last:
            # a temporary name of this process's own: two editors given the same
            # status file (a test restarting one while the other quits) must not
            # rename each other's temporary away
            tmp = self.path.with_name(f"{self.path.name}.{os.getpid()}.tmp")
            tmp.write_text(text)
            os.replace(tmp, self.path)
            self._last = text
