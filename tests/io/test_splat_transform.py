"""Independent reader check: PlayCanvas's ``splat-transform`` (npm
``@playcanvas/splat-transform``, installed into ./.node by scripts/install.sh)
reads the Gaussian PLYs we write and converts them; its CSV and PLY outputs
hold our values exactly."""

from __future__ import annotations

import os
import shutil
import subprocess

import numpy as np
import plyfile
import pytest

from splatedit.data import gaussian_scene_path
from splatedit.deform.gaussians import transform_gaussians
from splatedit.io import read_gaussians, write_gaussians
from tests.conftest import REPO_ROOT

#: oldest Node.js the pinned splat-transform 2.7.1 supports (its "engines")
NODE_MIN_MAJOR = 18


def _splat_transform() -> str:
    """Path of the splat-transform CLI, or skip with the reason."""
    node = shutil.which("node")
    if node is None:
        pytest.skip("node is not installed (scripts/install.sh installs Debian's nodejs)")
    ver = subprocess.run([node, "--version"], capture_output=True, text=True).stdout.strip()
    try:
        major = int(ver.lstrip("v").split(".")[0])
    except ValueError:
        pytest.skip(f"cannot parse the node version {ver!r}")
    if major < NODE_MIN_MAJOR:
        pytest.skip(f"node {ver} is older than {NODE_MIN_MAJOR}, the oldest splat-transform 2.7.1 runs on")
    cli = os.environ.get("SPLATEDIT_SPLAT_TRANSFORM") or str(REPO_ROOT / ".node" / "node_modules" / ".bin"
                                                              / "splat-transform")
    if not os.path.exists(cli):
        pytest.skip(f"@playcanvas/splat-transform is not installed at {cli} (run scripts/install.sh, "
                    "or set SPLATEDIT_SPLAT_TRANSFORM)")
    return cli


def _run(cli, *args):
    r = subprocess.run([cli, *map(str, args)], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    return r


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    """A scene we wrote: the test scene turned 90 degrees (rotated SH, re-decomposed covariances)."""
    a = np.eye(4)
    a[:3, :3] = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    a[:3, 3] = [0.1, 0.2, -0.3]
    path = tmp_path_factory.mktemp("st") / "turned.ply"
    write_gaussians(path, transform_gaussians(read_gaussians(gaussian_scene_path()), a))
    return path


def test_splat_transform_reads_our_file_and_writes_our_values_as_csv(written, tmp_path):
    cli = _splat_transform()
    out = tmp_path / "turned.csv"
    _run(cli, written, out)
    ours = plyfile.PlyData.read(str(written))["vertex"].data
    with open(out) as fh:
        header = fh.readline().strip().split(",")
    table = np.loadtxt(out, delimiter=",", skiprows=1, ndmin=2)
    assert table.shape == (len(ours), len(ours.dtype.names))
    assert sorted(header) == sorted(ours.dtype.names)
    for j, nm in enumerate(header):
        # their float32 printed as a shortest round-trip decimal: exact after rounding to float32
        assert np.array_equal(table[:, j].astype(np.float32), ours[nm]), nm


def test_splat_transform_ply_output_reads_back_identically(written, tmp_path):
    cli = _splat_transform()
    out = tmp_path / "again.ply"
    _run(cli, written, out)
    a, b = read_gaussians(written), read_gaussians(out)
    for nm in ("positions", "log_scales", "rotations", "opacity_logits", "sh"):
        assert np.array_equal(getattr(a, nm), getattr(b, nm)), nm
