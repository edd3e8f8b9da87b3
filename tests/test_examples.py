"""Every script in examples/ runs as a user would run it (a fresh process in
an empty folder) and writes what its docstring promises."""

from __future__ import annotations

import subprocess
import sys

import pytest

from tests.conftest import REPO_ROOT

EXAMPLES = sorted((REPO_ROOT / "examples").glob("*.py"))
#: files each example promises to write into the current folder
WRITES = {"python_api.py": ["bunny-ear.ply", "bunny-ear-rotation.ply"],
          "render_gaussians.py": ["scene.png"]}


def test_every_example_is_listed():
    assert sorted(p.name for p in EXAMPLES) == sorted(WRITES)


@pytest.mark.parametrize("script", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_example_runs_and_writes_its_files(script, tmp_path):
    proc = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    for name in WRITES[script.name]:
        assert (tmp_path / name).stat().st_size > 0, name
