"""Retake the README's editor screenshot (docs/images/editor_gui.png).

    PYTHONPATH=$PWD python scripts/shoot_editor_gui.py [-o docs/images/editor_gui.png]

Opens the bundled bunny in the editor (1280x720, Dear ImGui panels) under a
private Xvfb, paints a support on the back (3D brush, three sizes larger),
a handle in it (the palette's Handle button's key, 2, five sizes smaller),
waits for the fit, starts a grab (G) and moves the mouse up and to the right
so the live deformation and the distance readout show, then grabs the
window.  Needs Xvfb and xdotool (the same harness as the window tests).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("-o", "--out", default=str(ROOT / "docs" / "images" / "editor_gui.png"))
    a = p.parse_args(argv)
    from PIL import Image

    import tests.app.window_harness as wh
    from tests.app.conftest import _start_xvfb
    wh.WINDOW = (1280, 720)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        (tmp / "fb").mkdir()
        xproc, n = _start_xvfb(tmp / "fb")
        os.environ["XDG_CONFIG_HOME"] = str(tmp / "config")    # no recent files offered
        from splatedit.data import default_model_path
        ed = wh.EditorProcess({"display": f":{n}", "screen": tmp / "fb" / "Xvfb_screen0"}, tmp,
                              str(default_model_path()), "--size", "1280x720")
        try:
            s = ed.idle(lambda s: s["loaded"] and s["frames_presented"] > 0, "model loaded", 120)
            cx, cy = wh._foreground_centre(ed.screenshot(), s["panel_box"])
            ed.xdo("mousemove", cx, cy, "key", "bracketright", "bracketright", "bracketright")
            ed.xdo("mousemove", cx - 40, cy - 10, "mousedown", "1", "mousemove", cx, cy - 10,
                   "mousemove", cx + 40, cy - 10, "mousemove", cx + 40, cy + 15, "mousemove", cx - 40,
                   cy + 15, "sleep", "0.1", "mouseup", "1")
            ed.idle(lambda s: s["support"] > 200, "support painted")
            ed.xdo("key", "2", "bracketleft", "bracketleft", "bracketleft", "bracketleft", "bracketleft",
                   "mousemove", cx + 30, cy - 20, "click", "1")
            ed.idle(lambda s: s["handle"] > 0 and s["state"] == "ready", "handle painted and fitted", 120)
            ed.xdo("mousemove", cx + 30, cy - 20, "key", "g", "mousemove", cx + 50, cy - 50,
                   "mousemove", cx + 70, cy - 80)
            s = ed.wait(lambda s: s["manip"] == "grab", "grabbing")
            f = s["frames_presented"]
            ed.wait(lambda s: s["frames_presented"] >= f + 3 and s["full_quality"], "the moved frame", 60)
            time.sleep(0.5)
            img = ed.screenshot()[:720, :1280, :3]
            Image.fromarray(img).save(a.out)
            ed.xdo("key", "Escape")
        finally:
            ed.close()
            xproc.terminate()
            xproc.wait(10)
    print(f"wrote {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
