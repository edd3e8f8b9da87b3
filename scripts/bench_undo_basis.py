"""Undo after a commit: the kept basis taken back vs a refit (the same session, same run).

Run from the repository root: `.venv/bin/python scripts/bench_undo_basis.py` (docs/PERFORMANCE.md)."""
import time, numpy as np
from splatedit.app.document.session import Session, GRAB, ViewInfo
from splatedit.bench.editor import bunny_surface_cloud
from splatedit.io import read
from splatedit.data import default_model_path
from splatedit.select.selection import SUPPORT, HANDLE
v = ViewInfo(right=np.array([1.0,0,0]), up=np.array([0,1.0,0]), back=np.array([0,0,1.0]), pivot_px=(100.,100.), world_per_px=0.01)
for name, c, frac in (("bunny", read(str(default_model_path())), 92), ("bunny300k", bunny_surface_cloud(300_000), 67)):
    p = c.positions
    s = Session(c, fit_sync=True)
    s.brush_target = SUPPORT; s.end_stroke(s.paint(np.flatnonzero(p[:,1] > np.percentile(p[:,1], frac))))
    s.brush_target = HANDLE; s.end_stroke(s.paint(np.flatnonzero(p[:,1] > np.percentile(p[:,1], 99))))
    s.wait_fit()
    row = {}
    for mode in ("kept", "refit"):
        s.begin(GRAB, v, (100,100)); s.manip.set_axis(0); [s.manip.type_char(ch) for ch in "0.01"]; s.finish()
        s.wait_fit()
        if mode == "refit":
            s.fit.drop_kept()
        t = time.perf_counter(); s.undo(); s.wait_fit(); row[mode] = time.perf_counter() - t
        assert s.basis is not None
    print(name, c.n, "support", int(s.selection.support.sum()), {k: round(v, 3) for k, v in row.items()},
          "ratio", round(row["refit"] / max(row["kept"], 1e-9)))
    s.close()
