"""Issue 12 class 7: SIGTERM during a write and temporaries left by SIGKILL."""

from __future__ import annotations

import os
import signal
import subprocess
import sys

import numpy as np

from splatedit.cli import main
from splatedit.data import default_model_path
from splatedit.io import read, write
from splatedit.atomic import remove_stale_temporaries


def test_sigterm_during_a_write_removes_the_temporary_and_keeps_the_target(tmp_path, monkeypatch, capsys):
    """Handled like Ctrl+C: exit 130, the old file untouched, no hidden file left."""
    import splatedit.io.formats as io_mod   # the registry calls write_ply
    out = tmp_path / "out.ply"
    out.write_bytes(b"old contents")
    real = io_mod.write_ply

    def write_then_terminate(fh, cloud, **kw):
        fh.write(b"ply\npartial")
        os.kill(os.getpid(), signal.SIGTERM)      # arrives in the middle of the write
        real(fh, cloud, **kw)

    monkeypatch.setattr(io_mod, "write_ply", write_then_terminate)
    previous = signal.getsignal(signal.SIGTERM)
    assert main(["-q", "convert", str(default_model_path()), str(out), "-f"]) == 130
    assert "interrupted" in capsys.readouterr().err
    assert out.read_bytes() == b"old contents"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.ply"]
    assert signal.getsignal(signal.SIGTERM) == previous      # handler put back


def test_temporary_left_by_sigkill_is_removed_by_the_next_write(tmp_path):
    out = tmp_path / "out.ply"
    code = ("import os, signal\nfrom splatedit.atomic import atomic_open\n"
            f"with atomic_open({str(out)!r}) as fh:\n"
            "    fh.write(b'half a file')\n    fh.flush()\n    os.kill(os.getpid(), signal.SIGKILL)\n")
    env = dict(os.environ, PYTHONPATH=os.getcwd())
    res = subprocess.run([sys.executable, "-c", code], env=env, timeout=60)
    assert res.returncode == -signal.SIGKILL
    stale = [p for p in tmp_path.iterdir()]
    assert len(stale) == 1 and stale[0].name.startswith(".out.ply.") and stale[0].name.endswith(".tmp")
    # files that are not ours, or whose writer is alive, stay
    foreign = tmp_path / ".out.ply.mine.tmp"
    foreign.write_text("a user's file")
    live = tmp_path / f".out.ply.{os.getpid()}.abcdefgh.tmp"
    live.write_text("being written")
    other = tmp_path / ".other.ply.999999999.abcdefgh.tmp"   # another target: not touched
    other.write_text("another target's")
    cloud = read(default_model_path())
    write(out, cloud)
    names = sorted(p.name for p in tmp_path.iterdir())
    assert stale[0].name not in names
    assert {foreign.name, live.name, other.name, "out.ply"} == set(names)
    assert np.array_equal(read(out).positions, cloud.positions)
    assert remove_stale_temporaries(out) == []
