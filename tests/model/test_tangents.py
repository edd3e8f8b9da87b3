"""Splats straight from a file's normals and radii (splatedit.model.tangents):
the same discs as the estimation path, without a neighbour search or scipy."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import plyfile

from splatedit.io import read
from splatedit.model.estimate import estimate_splats
from splatedit.model.tangents import splats_from_normals, usable_normals


def _scan(n=20000, seed=3):
    rng = np.random.default_rng(seed)
    nrm = rng.normal(size=(n, 3))
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    pts = 5.0 * nrm + rng.normal(scale=1e-3, size=(n, 3))
    radius = rng.uniform(0.01, 0.05, n)
    return pts, nrm * rng.uniform(0.5, 2.0, (n, 1)), radius     # normals not unit, as files have them


def test_given_normals_and_radii_give_the_estimation_paths_discs():
    pts, nrm, radius = _scan()
    fast = splats_from_normals(pts, nrm, radius)
    ref = estimate_splats(pts, nrm, radius=radius)
    np.testing.assert_allclose(fast.u, ref.u, rtol=0, atol=1e-15)
    np.testing.assert_allclose(fast.v, ref.v, rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(fast.u, axis=1), radius, rtol=1e-12)
    unit = nrm / np.linalg.norm(nrm, axis=1, keepdims=True)
    cross = np.cross(fast.u, fast.v)
    np.testing.assert_allclose(cross / np.linalg.norm(cross, axis=1, keepdims=True), unit, atol=1e-12)


def test_usable_normals_refuses_zero_and_non_finite_rows():
    pts, nrm, _ = _scan(1000)
    assert usable_normals(nrm)
    for bad in (np.zeros(3), np.array([np.nan, 0, 1]), np.array([np.inf, 0, 0])):
        m = nrm.copy()
        m[517] = bad
        assert not usable_normals(m)


def _write(path, pts, nrm, radius):
    a = np.empty(len(pts), dtype=[(c, "f4") for c in ("x", "y", "z", "nx", "ny", "nz", "radius")])
    for i, c in enumerate("xyz"):
        a[c] = pts[:, i]
        a["n" + c] = nrm[:, i]
    a["radius"] = radius
    plyfile.PlyData([plyfile.PlyElement.describe(a, "vertex")]).write(str(path))


def test_reading_a_normals_and_radius_ply_needs_no_neighbour_search(tmp_path):
    pts, nrm, radius = _scan(5000)
    _write(tmp_path / "scan.ply", pts, nrm, radius)
    code = ("import sys; from splatedit.io import read; c = read(sys.argv[1]); "
            "print(c.n, 'scipy.spatial' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code, str(tmp_path / "scan.ply")], capture_output=True,
                         text=True, check=True).stdout.split()
    assert out == ["5000", "False"]
    c = read(tmp_path / "scan.ply")
    np.testing.assert_allclose(np.linalg.norm(c.u, axis=1), radius.astype(np.float32), rtol=1e-6)


def test_a_file_with_some_zero_normals_still_gets_estimated_ones(tmp_path):
    pts, nrm, radius = _scan(5000)
    nrm[:10] = 0.0
    _write(tmp_path / "scan.ply", pts, nrm, radius)
    c = read(tmp_path / "scan.ply")
    cross = np.cross(c.u[:10], c.v[:10])
    assert np.all(np.linalg.norm(cross, axis=1) > 0)
    # the filled normals face outward like their neighbours' (the sphere's radial direction)
    assert np.all(np.einsum("ij,ij->i", cross, c.positions[:10]) > 0)
