"""Fixtures of the editor tests: a private Xvfb server per test module."""

from __future__ import annotations

import os
import shutil
import subprocess
import time
from pathlib import Path

import pytest


def _start_xvfb(fbdir: Path) -> tuple[subprocess.Popen, int]:
    """Start a private Xvfb that picks a free display number itself
    (``-displayfd``: no race with other X servers started at the same time,
    e.g. by parallel test runs) and return it with its number once it accepts
    connections."""
    read_fd, write_fd = os.pipe()
    proc = subprocess.Popen(["Xvfb", "-displayfd", str(write_fd), "-screen", "0", "1280x800x24",
                             "-fbdir", str(fbdir), "-nolisten", "tcp", "-noreset"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, pass_fds=(write_fd,))
    os.close(write_fd)
    text = b""
    with os.fdopen(read_fd, "rb") as pipe:       # Xvfb writes "N\n" when it is ready
        while not text.endswith(b"\n"):
            chunk = pipe.read(1)
            if not chunk:
                break
            text += chunk
    if proc.poll() is not None or not text.strip().isdigit():
        proc.kill()
        pytest.fail(f"Xvfb did not start (exit code {proc.poll()}, said {text!r})")
    return proc, int(text)


@pytest.fixture(scope="module")
def xvfb(tmp_path_factory):
    if shutil.which("Xvfb") is None:
        pytest.skip("Xvfb is not installed (apt-get install xvfb)")
    if shutil.which("xdotool") is None:
        pytest.skip("xdotool is not installed (apt-get install xdotool)")
    fbdir = tmp_path_factory.mktemp("xvfb")
    proc, n = _start_xvfb(fbdir)
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
    recent files in its own config folder and its recovery copies in its own
    folder, never the user's (a recovery copy there would make the next
    editor start with the restore question)."""
    cfg = tmp_path / "config"
    monkeypatch.setenv("XDG_CONFIG_HOME", str(cfg))
    monkeypatch.setenv("XDG_STATE_HOME", str(tmp_path / "state"))
    monkeypatch.setenv("SPLATEDIT_RECOVERY_DIR", str(tmp_path / "recovery"))
    return cfg
