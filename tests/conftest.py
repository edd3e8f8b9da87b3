"""Shared pytest fixtures.

``shared_data`` gives the path of ../shared/data (the team's sample scans) and
skips the test when it is absent, as it is in a user's clone.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parent.parent
SHARED_DATA = REPO_ROOT.parent / "shared" / "data"

# The whole suite runs with the Vulkan validation layer on (see splatedit/render/vk).
os.environ.setdefault("SPLATEDIT_VALIDATION", "1")


@pytest.fixture
def shared_data() -> Path:
    """Path of ../shared/data; skips the test when the folder is absent."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"sample data folder {SHARED_DATA} is absent (it is not part of a user's clone)")
    return SHARED_DATA


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    """Fail the test (setup, call or teardown phase) during which the Vulkan
    validation layer reported any warning or error (see splatedit.render.vk)."""
    outcome = yield
    core = sys.modules.get("splatedit.render.vk.core")
    if core is None:          # Vulkan never imported: nothing to check
        return
    msgs = core.drain_validation_messages()
    if not msgs:
        return
    rep = outcome.get_result()
    text = (f"{len(msgs)} Vulkan validation message(s) during {call.when}:\n  "
            + "\n  ".join(m[:2000] for m in msgs))
    if rep.passed or rep.skipped:
        rep.outcome = "failed"
        rep.longrepr = text
    else:
        rep.sections.append(("Vulkan validation", text))


# ------------------------------------------------------------ a private X server
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
