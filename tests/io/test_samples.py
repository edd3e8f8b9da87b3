"""The team's sample files (../shared/data) read with the README's counts."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.io import read

SAMPLES = [("bunny00.off", 37706, 75408), ("kitten.xyz", 5210, None),
           ("hippo1.ply", 6104, None), ("poste_france.xyz", 9031, None)]


@pytest.mark.parametrize("name,n,faces", SAMPLES, ids=[s[0] for s in SAMPLES])
def test_sample_reads_with_readme_counts(shared_data, name, n, faces):
    c = read(shared_data / name)
    assert c.n == n
    assert (c.faces is None) if faces is None else (len(c.faces) == faces)
    assert np.all(np.isfinite(c.u)) and np.all(c.radii > 0)


def test_kitten_estimated_normals_agree_with_file_normals(shared_data):
    from splatedit.model.estimate import estimate_normals, orient_normals
    c = read(shared_data / "kitten.xyz")
    est = orient_normals(c.positions, estimate_normals(c.positions))
    agree = np.einsum("ij,ij->i", est, c.normals)
    assert np.mean(agree > 0) > 0.99
    assert np.median(agree) > 0.98


def test_hippo_normals_are_the_files(shared_data):
    import plyfile
    c = read(shared_data / "hippo1.ply")
    v = plyfile.PlyData.read(str(shared_data / "hippo1.ply"))["vertex"].data
    n = np.column_stack([v["nx"], v["ny"], v["nz"]])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    assert np.allclose(c.normals, n, atol=1e-12)
