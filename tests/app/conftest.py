"""Fixtures of the editor tests: private config, state and recovery folders
(the Xvfb fixture is in tests/conftest.py, shared with tests/render)."""

from __future__ import annotations

import pytest


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
