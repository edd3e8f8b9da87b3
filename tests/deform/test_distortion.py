"""Per-splat distortion (principal stretches, area change): known affine maps,
finite differences of a real deformation, the basis shortcuts, chunking."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.bench.solve import wavy_plane_cloud
from splatedit.deform.basis import DeformationBasis
from splatedit.deform.distortion import (DistortionProbe, basis_distortion, distortion_from_axes,
                                         principal_stretches)
from splatedit.deform.transform import compose, rotate, translate
from splatedit.errors import ParameterError
from splatedit.tolerances import DISTORTION_BROKEN_STRETCH, DISTORTION_WARN_STRETCH


def _axes(n, seed=0):
    """Random orthogonal tangent axes of different lengths, (n, 3) each."""
    rng = np.random.default_rng(seed)
    u = rng.normal(size=(n, 3)) * rng.uniform(0.01, 2.0, size=(n, 1))
    v = np.cross(u, rng.normal(size=(n, 3)))
    v *= rng.uniform(0.01, 2.0, size=(n, 1)) / np.linalg.norm(v, axis=1, keepdims=True)
    return u, v


def _map(J, *axes):
    return tuple(a @ np.asarray(J).T for a in axes)


def test_rotation_is_undistorted():
    u, v = _axes(1000)
    r = compose(rotate([0.3, -1.0, 0.5], 73.0))[:3, :3]
    s = distortion_from_axes(u, v, *_map(r, u, v))
    np.testing.assert_allclose(s.stretch, 1.0, atol=1e-12)
    np.testing.assert_allclose(s.area_change, 1.0, atol=1e-12)
    assert s.n_above_warn == 0 and s.max_stretch == pytest.approx(1.0, abs=1e-12)


def test_scale_by_two_along_one_tangent_axis_gives_two():
    u, v = _axes(500, seed=1)
    uh = u / np.linalg.norm(u, axis=1, keepdims=True)
    # J = I + uhat uhat^T per splat: doubles u, keeps v (v is orthogonal to u)
    u1 = 2.0 * u
    v1 = v + uh * np.einsum("ij,ij->i", uh, v)[:, None]
    s = distortion_from_axes(u, v, u1, v1)
    np.testing.assert_allclose(s.stretch, 2.0, rtol=1e-12)
    np.testing.assert_allclose(s.area_change, 2.0, rtol=1e-12)


def test_compression_counts_as_its_inverse_and_area_is_the_determinant():
    u = np.array([[1.0, 0.0, 0.0]] * 3)
    v = np.array([[0.0, 0.5, 0.0]] * 3)
    maps = [np.diag([1.0, 0.25, 1.0]), np.diag([3.5, 1.0, 7.0]), np.diag([2.0, 1.5, 1.0])]
    u1 = np.stack([m @ a for m, a in zip(maps, u)])
    v1 = np.stack([m @ a for m, a in zip(maps, v)])
    s = distortion_from_axes(u, v, u1, v1)
    np.testing.assert_allclose(s.stretch, [4.0, 3.5, 2.0])
    np.testing.assert_allclose(s.area_change, [0.25, 3.5, 3.0])
    assert (s.n_above_warn, s.n_above_broken) == (2, 0)       # 4.0 is not above 4x
    assert s.fraction_above_warn == pytest.approx(2 / 3)
    assert (s.min_area_change, s.max_area_change) == (0.25, 3.5)
    assert s.summary().startswith("stretch max 4.00x, 2 > 3x, 0 > 4x")
    assert DISTORTION_WARN_STRETCH == 3.0 and DISTORTION_BROKEN_STRETCH == 4.0


def test_singular_values_match_numpy_svd():
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=(2000, 3)), rng.normal(size=(2000, 3))
    b[:10] = 2.0 * a[:10] + 1e-9 * rng.normal(size=(10, 3))     # nearly flattened
    x, y = np.tile([1.0, 0.0, 0.0], (2000, 1)), np.tile([0.0, 1.0, 0.0], (2000, 1))
    s1, s2 = principal_stretches(x, y, a, b)
    ref = np.linalg.svd(np.stack([a, b], axis=2), compute_uv=False)
    np.testing.assert_allclose(s1, ref[:, 0], rtol=1e-12)
    np.testing.assert_allclose(s2, ref[:, 1], rtol=1e-6, atol=1e-12)


def test_non_orthogonal_axes_measure_the_map_not_the_axes():
    """Skewed axes (as some clouds have) of an undeformed splat give 1; a
    tangent-plane map diag(2, 1) gives 2 whichever axes span the plane."""
    u = np.array([[1.0, 0.0, 0.0], [0.3, 0.0, 0.0]])
    v = np.array([[0.6, 0.8, 0.0], [-2.0, 0.5, 0.0]])
    s = distortion_from_axes(u, v, u, v)
    np.testing.assert_allclose(s.stretch, 1.0, atol=1e-12)
    J = np.diag([2.0, 1.0, 5.0])
    s = distortion_from_axes(u, v, *_map(J, u, v))
    np.testing.assert_allclose(s.stretch, 2.0, rtol=1e-12)
    np.testing.assert_allclose(s.area_change, 2.0, rtol=1e-12)


def test_collapsed_splat_is_infinitely_stretched():
    u, v = _axes(4)
    s = distortion_from_axes(u, v, u, np.zeros_like(v))
    assert np.isinf(s.stretch).all() and s.n_above_broken == 4
    np.testing.assert_allclose(s.area_change, 0.0)


def test_chunking_does_not_change_the_result():
    u, v = _axes(1001, seed=4)
    J = np.random.default_rng(5).normal(size=(3, 3)) + 2 * np.eye(3)
    a = distortion_from_axes(u, v, *_map(J, u, v))
    b = distortion_from_axes(u, v, *_map(J, u, v), chunk=97)
    np.testing.assert_array_equal(a.stretch, b.stretch)
    np.testing.assert_array_equal(a.area_change, b.area_change)


def test_bad_shapes_are_parameter_errors():
    u, v = _axes(5)
    with pytest.raises(ParameterError, match="u1"):
        distortion_from_axes(u, v, u[:, :2], v)
    with pytest.raises(ParameterError, match="same number"):
        distortion_from_axes(u, v, u[:4], v)


def test_empty_input_is_undistorted():
    z = np.zeros((0, 3))
    s = distortion_from_axes(z, z, z, z)
    assert (s.n, s.max_stretch, s.n_above_warn, s.fraction_above_warn) == (0, 1.0, 0, 0.0)


# --------------------------------------------------- a real RBF deformation
@pytest.fixture(scope="module")
def edit():
    cloud = wavy_plane_cloud(60)
    xy = cloud.positions[:, :2]
    sup = np.linalg.norm(xy, axis=1) <= 0.7
    hnd = np.linalg.norm(xy, axis=1) <= 0.2
    basis = DeformationBasis.fit(cloud, sup, [hnd], method="lu")
    c = cloud.positions[hnd].mean(0)
    # lift, tilt and stretch the handle: free splats around it get stretched
    sx = translate(c) @ np.diag([2.2, 1.0, 1.0, 1.0]) @ translate(-c)       # 2.2x along x about c
    m = compose(translate([0.0, 0.0, 0.35]), rotate([1.0, 0.2, 0.0], 30.0, c), sx)
    return cloud, basis, basis.displacement([m])


def test_basis_distortion_matches_finite_differences_of_the_deformed_positions(edit):
    """Axes mapped by a central-difference Jacobian of p -> p + B(p) dC (the
    fitted RBF field itself) give the same stretch as basis_distortion."""
    cloud, basis, dc = edit
    s = basis_distortion(basis, cloud, dc)
    rng = np.random.default_rng(0)
    rows = rng.choice(np.searchsorted(basis.indices, basis.constraints.free_index), 60, replace=False)
    p = cloud.positions[basis.indices[rows]]
    h = 1e-5

    def field(x):
        return x + basis.rbf.value_and_gradient(x)[0] @ dc

    J = np.zeros((len(rows), 3, 3))
    for j in range(3):
        e = np.zeros(3)
        e[j] = h
        J[:, :, j] = (field(p + e) - field(p - e)) / (2 * h)
    u, v = cloud.u[basis.indices[rows]], cloud.v[basis.indices[rows]]
    ref = distortion_from_axes(u, v, np.einsum("nij,nj->ni", J, u), np.einsum("nij,nj->ni", J, v))
    np.testing.assert_allclose(s.stretch[rows], ref.stretch, rtol=1e-6)
    np.testing.assert_allclose(s.area_change[rows], ref.area_change, rtol=1e-6)
    assert s.max_stretch > 1.5                     # the edit really distorts


def test_basis_distortion_equals_the_committed_axes(edit):
    cloud, basis, dc = edit
    new = basis.commit(cloud, dc)
    i = basis.indices
    ref = distortion_from_axes(cloud.u[i], cloud.v[i], new.u[i], new.v[i])
    s = basis_distortion(basis, cloud, dc)
    np.testing.assert_allclose(s.stretch, ref.stretch, rtol=1e-10)
    # handle splats move rigidly and are scaled 2.2x along x only
    h = np.searchsorted(i, basis.constraints.groups[0].member_index)
    assert np.all(s.stretch[h] <= 2.2 + 1e-9) and s.stretch[h].max() > 2.0


def test_probe_matches_the_exact_figures_in_float32(edit):
    cloud, basis, dc = edit
    probe = DistortionProbe(basis, cloud)
    exact = basis_distortion(basis, cloud, dc)
    fast = probe.stats(dc)
    np.testing.assert_allclose(fast.stretch, exact.stretch, rtol=1e-5)
    assert fast.n_above_warn == exact.n_above_warn
    assert probe.stats(np.zeros_like(dc)).max_stretch == pytest.approx(1.0, abs=1e-5)
    with pytest.raises(ParameterError, match="dC"):
        probe.stats(dc[:2])
