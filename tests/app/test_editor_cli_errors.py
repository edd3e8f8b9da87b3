"""``splatedit edit`` failures before any window: one ``splatedit: error:``
line on stderr and exit code 2 (subprocesses, no display needed)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from splatedit.data import default_model_path

NO_DISPLAY = ("splatedit: error: cannot open a window: no display (set DISPLAY, or use the "
              "headless commands: splatedit demo/render/deform)")


def run_edit(*args, cwd=None):
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    return subprocess.run([sys.executable, "-m", "splatedit.cli", "edit", *map(str, args)],
                          env=env, cwd=cwd, capture_output=True, text=True, timeout=120)


def one_error(r) -> str:
    lines = r.stderr.splitlines()
    assert r.returncode == 2, r.stderr
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith("splatedit: error: ")
    assert r.stdout == ""
    return lines[0]


@pytest.fixture
def model(tmp_path) -> Path:
    p = tmp_path / "bunny.ply"
    shutil.copyfile(default_model_path(), p)
    return p


def test_no_display_is_one_error_line(model):
    assert one_error(run_edit(model)) == NO_DISPLAY
    assert one_error(run_edit()) == NO_DISPLAY            # the bundled model


def test_bad_model_files_are_refused_before_the_window(tmp_path):
    # without a display a window could not open: the file is checked first
    assert "missing.ply: no such file" in one_error(run_edit(tmp_path / "missing.ply"))
    (tmp_path / "m.obj").write_text("v 0 0 0\n")
    line = one_error(run_edit(tmp_path / "m.obj"))
    assert "m.obj" in line and "unsupported file extension '.obj'" in line and ".ply" in line
    assert "is a directory" in one_error(run_edit(tmp_path))


@pytest.mark.skipif(os.geteuid() == 0, reason="root reads files whatever their mode")
def test_unreadable_model_is_refused(model):
    model.chmod(0)
    try:
        assert "cannot read the file" in one_error(run_edit(model))
    finally:
        model.chmod(0o644)


def test_save_as_the_input_is_refused(model, tmp_path):
    before = model.read_bytes()
    line = one_error(run_edit(model, "--save-as", tmp_path / "." / "bunny.ply"))
    assert "--save-as" in line and "bunny.ply" in line
    line = one_error(run_edit(model, "--save-as", "bunny.ply", cwd=tmp_path))
    assert "--save-as" in line
    assert model.read_bytes() == before


@pytest.mark.parametrize("name, value", [("SPLATEDIT_REFINE_ABOVE_MS", "-5"), ("SPLATEDIT_REFINE_ABOVE_MS", "fast")])
def test_bad_refinement_settings_are_one_error_line(model, monkeypatch, name, value):
    monkeypatch.setenv(name, value)
    line = one_error(run_edit(model))
    assert name in line and repr(value) in line
