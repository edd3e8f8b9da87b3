"""A private X display for the window benchmarks in this folder.

    from xvfb_display import start_xvfb      # scripts/ is the script's own folder on sys.path
    proc, display = start_xvfb("1600x1000")  # ":N"; proc.terminate() when done

Xvfb picks a free display number itself and writes it to the pipe given by
``-displayfd`` (no race with other displays on the machine).
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path


def start_xvfb(size: str = "1600x1000", fbdir: Path | None = None) -> tuple[subprocess.Popen, str]:
    """Start Xvfb with one ``size`` screen (``"WxH"``, 24-bit; ``fbdir``: also
    keep the framebuffer there as an xwd file, for screenshots); returns the
    process and its display name ``":N"``."""
    r, w = os.pipe()
    cmd = ["Xvfb", "-displayfd", str(w), "-screen", "0", f"{size}x24", "-nolisten", "tcp"]
    if fbdir is not None:
        cmd += ["-fbdir", str(fbdir), "-noreset"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, pass_fds=(w,))
    os.close(w)
    text = b""
    with os.fdopen(r, "rb") as pipe:
        while not text.endswith(b"\n"):
            c = pipe.read(1)
            if not c:
                break
            text += c
    return proc, f":{int(text)}"
