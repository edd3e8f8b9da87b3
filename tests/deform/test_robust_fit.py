"""Numerically robust fits (issue 20, part 0): constraints a rounding away from
a quadric (spheres, cylinders, cones, planes stored with 3-12 decimals or in
float32) deform like their full-precision originals in every solver method;
the polynomial keeps its numerically independent part; a fit with weak
polynomial directions is checked against the fit without them."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from scipy.interpolate import RBFInterpolator

from splatedit.bench.quadric import PRECISIONS, SHAPES, lift, quadric_points, rounded
from splatedit.deform.basis import DeformationBasis
from splatedit.deform.gaussians import deform_with_evaluator, quaternions_from_matrices
from splatedit.deform.rbf import TriharmonicRBF, field_roughness
from splatedit.deform.rbf_fit import coordinate_precision, polynomial_basis
from splatedit.deform.transform import translate
from splatedit.model.estimate import estimate_splats, tangent_frame
from splatedit.model.gaussians import GaussianCloud
from splatedit.tolerances import COORD_FLOAT32_REL_PRECISION

#: the issue's bound: the stretch of a gentle lift within 10 % of full precision
STRETCH_REL = 0.10
ROUNDED = [p for p in PRECISIONS if p is not None]

_reference: dict = {}


def _full(shape: str, method: str, n: int):
    key = (shape, method, n)
    if key not in _reference:
        _reference[key] = lift(shape, None, method, n)
    return _reference[key]


def _assert_close_to_full(shape, precision, method, n=2000):
    ref = _full(shape, method, n)
    got = lift(shape, precision, method, n)
    assert got.n_broken == 0, (got, ref)
    assert abs(got.max_stretch / ref.max_stretch - 1.0) <= STRETCH_REL, (got, ref)
    # the 3x3 Jacobian (a thin Gaussian's normal axis) stays tame as well: the
    # full-precision fit's normal derivative is itself an extrapolation, so
    # the bound is the 10 % on top of 3-decimal rounding's own 8 %
    assert got.max_stretch_3d <= 1.2 * ref.max_stretch_3d, (got, ref)


@pytest.mark.parametrize("precision", ROUNDED, ids=str)
@pytest.mark.parametrize("shape", SHAPES)
def test_gentle_lift_of_a_rounded_quadric_stretches_like_full_precision_lu(shape, precision):
    _assert_close_to_full(shape, precision, "lu")


@pytest.mark.parametrize("precision", ROUNDED, ids=str)
@pytest.mark.parametrize("method", ["iqr", "auto"])
def test_gentle_lift_of_a_rounded_sphere_stretches_like_full_precision(method, precision):
    _assert_close_to_full("sphere", precision, method)


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(shape=st.sampled_from(SHAPES), precision=st.sampled_from(ROUNDED),
       method=st.sampled_from(["lu", "iqr", "auto"]))
def test_any_quadric_precision_and_method_stretches_like_full_precision(shape, precision, method):
    _assert_close_to_full(shape, precision, method)


# --------------------------------------------------------- the fit itself
@settings(max_examples=15, deadline=None)
@given(shape=st.sampled_from(SHAPES), cx=st.floats(-1e3, 1e3), radius=st.floats(1e-2, 1e2),
       seed=st.integers(0, 2**16),
       precision=st.sampled_from(["f32", 3, 4, 5, 6, 7, 8, 9, 10, 12]), method=st.sampled_from(["lu", "iqr"]))
def test_fitted_field_on_a_rounded_quadric_anywhere_is_as_steep_as_at_full_precision(
        shape, cx, radius, seed, precision, method):
    """A sphere, cylinder, cone or plane of any size anywhere, turned at
    random (float32 rounding far from the origin is coarse relative to the
    size), a smooth field on it: the fitted field's largest Jacobian at the
    points stays within 10 % of the full-precision fit's, and it still
    interpolates."""
    rng = np.random.default_rng(seed)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    centre = np.array([cx, -0.5 * cx, 0.25 * cx])
    p0 = centre + radius * quadric_points(shape, 300)[0] @ q.T
    p = rounded(p0, precision)
    # the range: up to 3 decimals on a unit object (rounding 5e-4 of
    # its radius); coarser rounding changes the shape itself
    assume(coordinate_precision(p) <= 5e-4 * radius)
    x = (p0 - centre) / radius
    vals = np.column_stack([np.sin(2 * x[:, 0]) + x[:, 1] * x[:, 2], np.cos(x[:, 2]) - x[:, 0]])
    ref = TriharmonicRBF.fit(p0, vals, method=method, tol=0.0)
    f = TriharmonicRBF.fit(p, vals, method=method, tol=0.0)
    assert f.residual < 1e-6
    r_ref, r = field_roughness(ref, p0), field_roughness(f, p)
    assert r <= (1 + STRETCH_REL) * r_ref, (r, r_ref, f.message)


def test_coordinate_precision_finds_decimal_grids_and_float32():
    p, _, _ = quadric_points("sphere", 500)
    assert coordinate_precision(np.round(p, 3)) == pytest.approx(5e-4)
    assert coordinate_precision(np.round(p, 6)) == pytest.approx(5e-7)
    assert coordinate_precision(np.round(p, 10)) == pytest.approx(5e-11)
    # float32 storage, or on no grid at all: the float32 bound
    f32 = COORD_FLOAT32_REL_PRECISION * np.abs(p).max()
    assert coordinate_precision(p.astype(np.float32).astype(np.float64)) == pytest.approx(f32, rel=1e-6)
    assert coordinate_precision(p) == pytest.approx(f32)
    # a decimal grid far from the origin: in float64 its own step (a scan in
    # georeferenced metres), in float32 at least the float32 rounding
    far = np.round(p * 10 + 5e5, 2)
    assert coordinate_precision(far) == pytest.approx(5e-3)
    far32 = np.round(p * 10 + 1000.0, 2).astype(np.float32).astype(np.float64)
    assert coordinate_precision(far32) == pytest.approx(5e-3)


@pytest.mark.parametrize("shape,rank", [("sphere", 9), ("cylinder", 9), ("cone", 9), ("plane", 6)])
@pytest.mark.parametrize("precision", [None, "f32", 7, 4])
def test_polynomial_keeps_exactly_the_part_the_quadric_leaves_independent(shape, rank, precision):
    p = rounded(quadric_points(shape, 1500)[0], precision)
    scale = 0.5 * np.ptp(p, axis=0).max()
    pn = (p - 0.5 * (p.min(0) + p.max(0))) / scale
    basis = polynomial_basis(pn, coordinate_precision(p) / scale)
    assert basis.rank == rank
    assert ("quadric" in basis.note) == (rank < 10)
    # orthogonal columns of norm sqrt(m), the values of the monomial combinations
    m = len(p)
    np.testing.assert_allclose(basis.matrix.T @ basis.matrix / m, np.eye(rank), atol=1e-8)


@pytest.mark.parametrize("shape", ["sphere", "cylinder", "cone"])
@pytest.mark.parametrize("method", ["lu", "iqr"])
def test_affine_fields_stay_exact_off_a_rounded_quadric(shape, method):
    """The affine terms are factored first, so an affine field on a rounded
    curved quadric (a rigid motion's displacement) is reproduced exactly
    everywhere, off the surface too (what a Gaussian's normal axis sees).
    (On a plane the normal coordinate is itself one of the dropped
    directions: nothing determines the field's normal derivative there.)"""
    p = rounded(quadric_points(shape, 600)[0], 7)
    a = np.array([[0.3, -1.2, 0.5], [2.0, 0.1, -0.7]])
    vals = p @ a.T + np.array([0.25, -3.0])
    f = TriharmonicRBF.fit(p, vals, method=method, tol=0.0)
    assert f.poly_rank < 10 and "affine" in f.message
    x = 0.8 * p[::7] + np.array([0.05, -0.1, 0.2])
    np.testing.assert_allclose(f(x), x @ a.T + np.array([0.25, -3.0]), atol=1e-8)
    np.testing.assert_allclose(f.gradient(x), np.broadcast_to(a, (len(x), 2, 3)), atol=1e-8)


def test_generic_points_keep_the_whole_polynomial_and_match_scipy():
    """Well-conditioned data: all 10 terms, no check, the scipy oracle."""
    rng = np.random.default_rng(3)
    p = rng.uniform(-1, 1, size=(150, 3))
    vals = np.column_stack([np.sin(p[:, 0]) * p[:, 1], p[:, 2] ** 2 - p[:, 0]])
    f = TriharmonicRBF.fit(p, vals, method="lu")
    assert f.poly_rank == 10 and "checked" not in f.message
    x = rng.uniform(-1, 1, size=(40, 3))
    ref = RBFInterpolator(p, vals, kernel="cubic", degree=2)(x)
    np.testing.assert_allclose(f(x), ref, rtol=0, atol=1e-8 * np.abs(ref).max())


@pytest.mark.parametrize("method", ["lu", "iqr"])
def test_jittered_float64_sphere_falls_back_to_the_fit_without_the_weak_direction(method):
    """Float64 points 1e-5 off a sphere (not a rounding grid: above the
    float32 bound, so the quadric direction is kept) make the full
    polynomial fit 15x steeper: the check drops the weak direction."""
    p, _, _ = quadric_points("sphere", 1200)
    p = p[p[:, 2] > 0.2]
    p = p + 1e-5 * np.random.default_rng(5).uniform(-1, 1, size=p.shape)
    vals = np.column_stack([(p[:, 2] > 0.85).astype(float), p[:, 0] * (p[:, 2] > 0.85)])
    f = TriharmonicRBF.fit(p, vals, method=method, tol=0.0)
    assert f.poly_rank == 9
    assert "weak directions make the field" in f.message and "dropped" in f.message
    assert f.residual < 1e-6


def test_jittered_sphere_lift_keeps_its_stretch():
    """The same, through the basis: a 2,000-point sphere, every point moved up
    to 1e-5 at random (float64), lifted: the 3x3 Jacobians stay as tame as
    on the exact sphere (before the check: 5.1x)."""
    p0, d, _ = quadric_points("sphere", 2000)
    p = p0 + 1e-5 * np.random.default_rng(1).uniform(-1, 1, size=p0.shape)
    res = []
    for pts in (p0, p):
        cloud = estimate_splats(pts)
        b = DeformationBasis.fit(cloud, pts[:, 2] > 0.2, [pts[:, 2] > 0.85], method="lu")
        sv = np.linalg.svd(b.jacobians(b.displacement([translate(0.2 * d)])), compute_uv=False)
        res.append(np.maximum(sv[:, 0], 1 / sv[:, 2]).max())
    assert res[1] <= (1 + STRETCH_REL) * res[0], res


# --------------------------------------------------------- Gaussians (3DGS)
def _sphere_gaussians(n=2000) -> GaussianCloud:
    p, _, _ = quadric_points("sphere", n)
    p = p.astype(np.float32).astype(np.float64)  # as every 3DGS file stores them
    nrm = p / np.linalg.norm(p, axis=1, keepdims=True)
    t1, t2 = tangent_frame(nrm)
    rot = np.stack([t1, t2, nrm], axis=2)  # columns: axes of the Gaussian
    rot[np.linalg.det(rot) < 0, :, 0] *= -1.0
    h = np.sqrt(4 * np.pi / n)
    log_s = np.log(np.array([0.5 * h, 0.5 * h, 0.02 * h], dtype=np.float32))
    return GaussianCloud(positions=p, log_scales=np.tile(log_s, (n, 1)),
                         rotations=quaternions_from_matrices(rot).astype(np.float32),
                         opacity_logits=np.zeros(n, np.float32), sh=np.zeros((n, 1, 3), np.float32),
                         name="sphere-gaussians")


def test_3dgs_sphere_lift_keeps_the_gaussians_shape():
    """The issue's 3DGS sphere (float32 centres, thin Gaussians along the
    normal): lifting the cap stretched a Gaussian 385x.  Now every Gaussian's
    axes change by at most the exact sphere's lift (1.3x-1.5x)."""
    scene = _sphere_gaussians()
    proxy = scene.proxy_splats()
    z = proxy.positions[:, 2]
    basis = DeformationBasis.fit(proxy, z > 0.2, [z > 0.85])
    out = deform_with_evaluator(scene, basis, basis.displacement([translate([0.0, 0.0, 0.2])]))
    idx = basis.indices
    a0 = scene.rotation_matrices()[idx] * np.exp(scene.log_scales[idx].astype(float))[:, None, :]
    a1 = out.rotation_matrices()[idx] * np.exp(out.log_scales[idx].astype(float))[:, None, :]
    # the covariance's principal axes: sqrt of the eigenvalues of A A^T
    s0 = np.sqrt(np.linalg.eigvalsh(a0 @ a0.transpose(0, 2, 1)))
    s1 = np.sqrt(np.linalg.eigvalsh(a1 @ a1.transpose(0, 2, 1)))
    ratio = s1 / s0
    stretch = np.maximum(ratio.max(axis=1), 1 / ratio.min(axis=1))
    assert stretch.max() < 1.6, stretch.max()
