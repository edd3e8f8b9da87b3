"""Atomic writes keep permissions sane and never leave partial files."""

from __future__ import annotations

import os
import stat

import pytest

from splatedit.errors import InputError
from splatedit.atomic import atomic_open, atomic_write_text, check_writable_target


def test_new_file_gets_umask_permissions_not_mkstemp_0600(tmp_path):
    p = tmp_path / "a.txt"
    atomic_write_text(p, "x")
    umask = os.umask(0o022)
    os.umask(umask)
    assert stat.S_IMODE(p.stat().st_mode) == 0o666 & ~umask


def test_replacing_a_file_keeps_its_permissions(tmp_path):
    p = tmp_path / "a.txt"
    p.write_text("old")
    p.chmod(0o640)
    atomic_write_text(p, "new")
    assert p.read_text() == "new"
    assert stat.S_IMODE(p.stat().st_mode) == 0o640


def test_failure_midway_keeps_the_old_file_and_leaves_no_temp(tmp_path):
    p = tmp_path / "a.txt"
    p.write_text("old")
    with pytest.raises(RuntimeError):
        with atomic_open(p, "w") as fh:
            fh.write("partial")
            raise RuntimeError("disk full")
    assert p.read_text() == "old"
    assert sorted(x.name for x in tmp_path.iterdir()) == ["a.txt"]


def test_existing_target_is_refused_unless_overwrite(tmp_path):
    p = tmp_path / "a.txt"
    p.write_text("old")
    with pytest.raises(InputError, match="file exists"):
        check_writable_target(p, overwrite=False)
    assert check_writable_target(p, overwrite=True) == p


def test_input_file_is_protected(tmp_path):
    p = tmp_path / "in.ply"
    p.write_text("data")
    with pytest.raises(InputError, match="refusing to overwrite the input file"):
        check_writable_target(p, overwrite=False, protect=p)
