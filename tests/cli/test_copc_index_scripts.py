"""``splatedit deform X.copc.laz`` of an edit script with index lists (the
editor's, for a scan opened out of core: indices of the whole file in the order
it is read): out of core it reads only the nodes around the indexed points and
writes what the in-memory replay writes; an index beyond the file is one error
line."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from tests.app.copc_scans import terrain_copc

pytest.importorskip("lazrs", reason="COPC point data is LAZ-compressed (lazrs)")


def run_cli(*args):
    return subprocess.run([sys.executable, "-m", "splatedit.cli", "-q", *map(str, args)],
                          capture_output=True, text=True, timeout=120)


@pytest.fixture(scope="module")
def scan(tmp_path_factory):
    d = tmp_path_factory.mktemp("copc-index")
    return terrain_copc(d / "terrain.copc.laz", 40_000), d


def _rows(xyz):
    q = np.round(xyz, 3)
    return q[np.lexsort(q.T[::-1])]


def test_an_index_script_replays_out_of_core_as_in_memory(scan, tmp_path):
    from splatedit.io import read
    from splatedit.io.copc import CopcFile
    path, _ = scan
    whole = read(str(path))
    p = whole.positions
    c = p[np.argmin(np.linalg.norm(p[:, :2] - np.median(p[:, :2], axis=0), axis=1))]
    d = np.linalg.norm(p - c, axis=1)
    script = {"version": 1, "edits": [{"support": {"indices": np.flatnonzero(d < 12).tolist()},
                                        "handle": {"indices": np.flatnonzero(d < 3).tolist()},
                                        "transform": {"translate": [0.0, 0.0, 1.5]}}]}
    sp = tmp_path / "lift.json"
    sp.write_text(json.dumps(script))
    r = run_cli("deform", path, "--edit", sp, "-o", tmp_path / "ooc.copc.laz")
    assert r.returncode == 0, r.stderr
    r = run_cli("deform", path, "--edit", sp, "-o", tmp_path / "mem.ply")
    assert r.returncode == 0, r.stderr
    with CopcFile.open(tmp_path / "ooc.copc.laz") as f:
        ooc = f.read(list(f.nodes)).xyz
    mem = read(str(tmp_path / "mem.ply")).world_positions()
    moved = (np.abs(_rows(ooc) - _rows(whole.world_positions())) > 1e-6).any(axis=1).sum()
    assert moved > 100
    np.testing.assert_allclose(_rows(ooc), _rows(mem), rtol=0, atol=1e-3 + 1e-9)   # one 0.001 grid step


def test_an_index_beyond_the_file_is_one_error_line(scan, tmp_path):
    path, _ = scan
    sp = tmp_path / "bad.json"
    sp.write_text(json.dumps({"version": 1, "edits": [{"support": {"indices": [0, 1, 40_000]},
                                                        "handle": {"indices": [0]},
                                                        "transform": {"translate": [0, 0, 1]}}]}))
    r = run_cli("deform", path, "--edit", sp, "-o", tmp_path / "out.copc.laz")
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("splatedit: error:") and "40000" in lines[0]
