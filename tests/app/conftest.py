"""Fixtures of the editor tests: a private Xvfb server per test module."""

from __future__ import annotations

import shutil
import subprocess
import time
from pathlib import Path

import pytest


def _free_display() -> int:
    for n in range(91, 200):
        if not Path(f"/tmp/.X{n}-lock").exists() and not Path(f"/tmp/.X11-unix/X{n}").exists():
            return n
    raise RuntimeError("no free X display number")


@pytest.fixture(scope="module")
def xvfb(tmp_path_factory):
    if shutil.which("Xvfb") is None:
        pytest.skip("Xvfb is not installed (apt-get install xvfb)")
    if shutil.which("xdotool") is None:
        pytest.skip("xdotool is not installed (apt-get install xdotool)")
    fbdir = tmp_path_factory.mktemp("xvfb")
    n = _free_display()
    proc = subprocess.Popen(["Xvfb", f":{n}", "-screen", "0", "1280x800x24", "-fbdir", str(fbdir),
                             "-nolisten", "tcp", "-noreset"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    sock = Path(f"/tmp/.X11-unix/X{n}")
    t0 = time.time()
    while not sock.exists() and time.time() - t0 < 10:
        if proc.poll() is not None:
            pytest.fail(f"Xvfb :{n} exited with code {proc.returncode}")
        time.sleep(0.05)
    try:
        yield {"display": f":{n}", "screen": fbdir / "Xvfb_screen0"}
    finally:
        proc.terminate()
        try:
            proc.wait(5)
        except subprocess.TimeoutExpired:
            proc.kill()




@pytest.fixture(autouse=True)
def private_config(tmp_path, monkeypatch):
    """Every editor test (and the editor processes it starts) keeps its
    recent files in its own config folder, never the user's."""
    cfg = tmp_path / "config"
    monkeypatch.setenv("XDG_CONFIG_HOME", str(cfg))
    return cfg
