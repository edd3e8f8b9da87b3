"""PCA normals, MST orientation and hole-free splat sizing."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.model.estimate import (estimate_normals, estimate_splats, orient_normals,
                                      splat_axes, splat_radii, tangent_frame)


def sphere(n, seed=0, centre=(0.0, 0.0, 0.0), r=1.0):
    rng = np.random.default_rng(seed)
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    return p * r + np.asarray(centre)


def test_pca_normals_on_sphere_match_analytic_up_to_sign():
    p = sphere(3000)
    n = estimate_normals(p)
    cos = np.abs(np.einsum("ij,ij->i", n, p))
    assert np.degrees(np.arccos(cos.min())) < 5.0
    assert np.degrees(np.arccos(np.median(cos))) < 1.0


def test_orientation_on_sphere_is_outward_everywhere():
    p = sphere(3000)
    rng = np.random.default_rng(3)
    signs = rng.choice([-1.0, 1.0], size=(3000, 1))
    n = orient_normals(p, estimate_normals(p) * signs)
    assert np.all(np.einsum("ij,ij->i", n, p) > 0)


def test_orientation_is_outward_for_each_separate_component():
    a, b = sphere(1500, 1), sphere(1500, 2, centre=(10.0, 0, 0), r=2.0)
    p = np.vstack([a, b])
    n = orient_normals(p, estimate_normals(p))
    out = np.einsum("ij,ij->i", n, np.vstack([a, (b - [10.0, 0, 0])]))
    assert np.all(out > 0)


def test_plane_normals_are_plus_z():
    rng = np.random.default_rng(0)
    p = np.column_stack([rng.random((2000, 2)), np.zeros(2000)])
    n = orient_normals(p, estimate_normals(p))
    assert np.allclose(n, [0.0, 0.0, 1.0], atol=1e-9)


def test_vertical_plane_seed_points_away_from_centroid_side():
    rng = np.random.default_rng(0)
    p = np.column_stack([np.zeros(500), rng.random((500, 2))])
    n = orient_normals(p, estimate_normals(p))
    assert np.allclose(np.abs(n[:, 0]), 1.0)
    assert np.all(n[:, 0] == n[0, 0])      # consistent


def test_tangent_frame_is_right_handed_orthonormal():
    rng = np.random.default_rng(0)
    n = rng.normal(size=(1000, 3))
    n = np.vstack([n, [[0, 0, 1], [0, 0, -1], [1, 0, 0], [0, -1, 0]]])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    t1, t2 = tangent_frame(n)
    assert np.allclose(np.cross(t1, t2), n, atol=1e-12)
    assert np.allclose(np.einsum("ij,ij->i", t1, t2), 0, atol=1e-12)
    assert np.allclose(np.linalg.norm(t1, axis=1), 1) and np.allclose(np.linalg.norm(t2, axis=1), 1)


def test_splat_axes_have_requested_radius_and_normal():
    p = sphere(200)
    u, v = splat_axes(p, p * 3.0, radius=0.25)
    assert np.allclose(np.linalg.norm(u, axis=1), 0.25) and np.allclose(np.linalg.norm(v, axis=1), 0.25)
    nn = np.cross(u, v)
    assert np.allclose(nn / np.linalg.norm(nn, axis=1, keepdims=True), p, atol=1e-12)


@pytest.mark.parametrize("seed", [0, 1])
def test_estimated_splats_cover_sphere(seed):
    """Hole-free: every point of a dense random sample of the surface projects
    into at least one splat ellipse near it."""
    from scipy.spatial import cKDTree
    p = sphere(4000, seed)
    c = estimate_splats(p)
    q = sphere(200_000, seed + 100)
    k = 24
    _, idx = cKDTree(p).query(q, k=k)
    covered = np.zeros(len(q), dtype=bool)
    uu = np.einsum("ij,ij->i", c.u, c.u)
    vv = np.einsum("ij,ij->i", c.v, c.v)
    for j in range(k):
        i = idx[:, j]
        d = q - p[i]
        s = np.einsum("ij,ij->i", d, c.u[i]) / uu[i]
        t = np.einsum("ij,ij->i", d, c.v[i]) / vv[i]
        covered |= s * s + t * t <= 1.0
    assert covered.all(), f"{(~covered).sum()} uncovered surface points"


def test_duplicates_and_single_points_get_positive_radii():
    p = np.vstack([np.zeros((5, 3)), sphere(100)])
    r = splat_radii(p)
    assert np.all(r > 0)
    one = estimate_splats(np.array([[1.0, 2.0, 3.0]]))
    assert one.n == 1 and one.radii[0] > 0


def test_zero_normals_in_input_are_filled_consistently():
    p = sphere(1000)
    n = p.copy()
    n[::7] = 0.0
    c = estimate_splats(p, n)
    assert np.all(np.einsum("ij,ij->i", c.normals, p) > 0.99)


@pytest.mark.parametrize("name", ["kitten.xyz", "hippo1.ply"])
def test_estimated_orientation_agrees_with_the_scans_own_normals_everywhere(shared_data, name):
    from splatedit.io import read
    scan = read(shared_data / name)
    est = estimate_splats(scan.positions)
    agree = np.einsum("ij,ij->i", np.cross(est.u, est.v), np.cross(scan.u, scan.v)) > 0
    assert agree.all(), f"{(~agree).sum()} of {len(agree)} normals flipped"


def test_estimated_orientation_of_a_dense_bunny_sample_is_outward_everywhere(shared_data):
    """150k points sampled from the closed bunny mesh: every estimated normal
    agrees with the normal of the face it was sampled from (the two-level
    orientation: safe-edge forest + MST between its pieces)."""
    from splatedit.io import read
    mesh = read(shared_data / "bunny00.off")
    v, f = mesh.positions, mesh.faces
    rng = np.random.default_rng(7)
    per = 2
    r1, r2 = np.sqrt(rng.random((len(f), per))), rng.random((len(f), per))
    w = np.stack([1 - r1, r1 * (1 - r2), r1 * r2], -1)
    p = np.einsum("fsk,fkd->fsd", w, v[f]).reshape(-1, 3)
    face_n = np.repeat(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), per, axis=0)
    est = estimate_splats(p)
    agree = np.einsum("ij,ij->i", np.cross(est.u, est.v), face_n) > 0
    assert agree.all(), f"{(~agree).sum()} of {len(agree)} normals point inwards"
