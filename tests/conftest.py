"""Shared pytest fixtures.

``shared_data`` gives the path of ../shared/data (the team's sample scans) and
skips the test when it is absent, as it is in a user's clone.
"""

from __future__ import annotations

import os
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
