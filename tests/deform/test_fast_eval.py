"""Far-field basis evaluation (splatedit.deform.fast_eval, issue 20 part 2):
the basis of the default path stays within 0.5% of the handle's move of the
exact LU deformation evaluated directly, on a real scan's support and on a
sphere, while interpolating most free splats; the interpolant matches the
direct evaluation within its tolerance; scipy's RBFInterpolator agrees."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import RBFInterpolator

from splatedit.bench.solve import sample_transform, sphere_cloud
from splatedit.deform.basis import DeformationBasis
from splatedit.deform.fast_eval import RBFField, evaluate
from splatedit.deform.rbf import TriharmonicRBF
from splatedit.model.cloud import SplatCloud
from splatedit.tolerances import FAST_EVAL_TOL

#: the issue's accuracy budget: deviation from the exact LU deformation / handle move
BUDGET = 0.005


def _densified_scan(path, copies: int = 8, seed: int = 0) -> SplatCloud:
    """A real scan made denser: each point plus ``copies - 1`` jittered copies
    in its tangent plane (within a third of the point spacing), so that the
    support has enough splats for far-field boxes."""
    from splatedit.io import read
    from splatedit.model.spacing import point_spacing
    c = read(str(path))
    p, u, v = c.positions, c.u, c.v
    t1 = u / np.linalg.norm(u, axis=1, keepdims=True)
    t2 = v / np.linalg.norm(v, axis=1, keepdims=True)
    h = point_spacing(p)
    rng = np.random.default_rng(seed)
    a = rng.uniform(-h / 3, h / 3, (copies - 1, len(p), 2))
    extra = p[None] + a[..., :1] * t1[None] + a[..., 1:] * t2[None]
    pos = np.concatenate([p, extra.reshape(-1, 3)])
    s = 1.0 / np.sqrt(copies)
    return SplatCloud(pos, np.tile(u * s, (copies, 1)), np.tile(v * s, (copies, 1)), name="hippo-dense")


def _grab(cloud, support_frac: float, handle_frac: float):
    """Support: the ``support_frac`` of the splats nearest the highest splat;
    handle: the ``handle_frac`` nearest it."""
    p = cloud.positions
    tip = p[np.argmax(p[:, 1])]
    d = np.linalg.norm(p - tip, axis=1)
    order = np.argsort(d)
    sup = np.zeros(len(p), bool)
    sup[order[:int(support_frac * len(p))]] = True
    hnd = np.zeros(len(p), bool)
    hnd[order[:int(handle_frac * len(p))]] = True
    return sup, hnd


def _deviation(cloud, sup, hnd, scipy: bool = True):
    """(fast basis, largest displacement deviation / handle move, Jacobian
    deviation, scipy's deviation) for a lift-and-tilt of the handle."""
    fast = DeformationBasis.fit(cloud, sup, [hnd], method="lu", fill_holes=False)
    exact = DeformationBasis.fit(cloud, sup, [hnd], method="lu", fill_holes=False, eval_tol=0.0)
    dc = fast.displacement([sample_transform(cloud, hnd, sup)])
    free = np.searchsorted(fast.indices, fast.constraints.free_index)
    d_fast, d_exact = fast.displacements(dc), exact.displacements(dc)
    move = np.linalg.norm(d_exact, axis=1).max()
    dev = np.linalg.norm(d_fast[free] - d_exact[free], axis=1).max() / move
    jac = np.abs(fast.jacobians(dc)[free] - exact.jacobians(dc)[free]).max()
    if not scipy:
        return fast, dev, jac, None
    con = exact.constraints
    ref = RBFInterpolator(con.points, con.values, kernel="cubic", degree=2)(
        cloud.positions[con.free_index])
    dev_scipy = np.linalg.norm(ref @ dc - d_exact[free], axis=1).max() / move
    return fast, dev, jac, dev_scipy


@pytest.fixture
def dense_hippo(shared_data):
    return _densified_scan(shared_data / "hippo1.ply")


def test_far_field_basis_within_half_a_percent_of_exact_lu_on_a_scan(dense_hippo):
    """A 49k-splat densified hippo scan, the half nearest the top grabbed by
    its 4%: most free splats are interpolated and the deformation is within
    the 0.5% budget of the exact one (measured 2.6e-5 of the move, 0.0026%); scipy's cubic RBF
    agrees with the exact LU (the oracle)."""
    sup, hnd = _grab(dense_hippo, 0.5, 0.04)
    fast, dev, jac, dev_scipy = _deviation(dense_hippo, sup, hnd)
    st = fast.stats
    assert st["eval_interpolated"] > 0.5 * st["n_free"]
    assert dev <= BUDGET / 50
    assert jac < 1e-2
    assert dev_scipy < 1e-6


def test_far_field_basis_within_half_a_percent_of_exact_lu_on_a_sphere():
    """A 60k-splat sphere (all constraints near a quadric), the top cap
    grabbed: interpolated, and within the budget (measured 3.7e-5 of the move)."""
    cloud = sphere_cloud(60_000)
    sup, hnd = _grab(cloud, 0.4, 0.03)
    fast, dev, jac, _ = _deviation(cloud, sup, hnd, scipy=False)
    assert fast.stats["eval_interpolated"] > 0.5 * fast.stats["n_free"]
    assert dev <= BUDGET / 50
    assert jac < 1e-2
    # (scipy is no oracle here: it keeps the quadratic on constraints near a
    # quadric, the fit drops it; they differ by 0.7%, see issue 20 part 0)


def _field(seed=0, m=400):
    """A fitted field on a band-like constraint set: a ring of points (value
    0) and a small cap (affine values), plus its field object."""
    rng = np.random.default_rng(seed)
    t = rng.uniform(0, 2 * np.pi, m)
    ring = np.column_stack([np.cos(t), np.sin(t), 0.05 * rng.standard_normal(m)])
    cap = 0.1 * rng.standard_normal((m // 4, 3)) + [0, 0, 0.8]
    pts = np.concatenate([ring, cap])
    vals = np.zeros((len(pts), 2))
    vals[m:, 0] = 1.0
    vals[m:, 1] = cap[:, 0]
    f = TriharmonicRBF.fit(pts, vals, method="lu")
    return f, RBFField((f.centers - f.shift) / f.scale, f.weights, f.poly_coeffs), float(np.abs(vals).max())


def test_interpolated_values_and_gradients_match_direct_evaluation_within_tol():
    f, fld, vs = _field()
    rng = np.random.default_rng(1)
    x = rng.uniform(-0.8, 0.8, (40_000, 3)) * [1, 1, 0.5]
    xn = (x - f.shift) / f.scale
    ref, _ = evaluate(fld, xn, tol=0.0, value_scale=vs, far_field=False)
    out, st = evaluate(fld, xn, tol=FAST_EVAL_TOL, value_scale=vs)
    assert st.n_interpolated > 0.5 * len(x)
    assert st.max_check_error <= FAST_EVAL_TOL
    # the per-box check sees a few points; the rest stay within a small factor
    assert np.abs(out - ref).max() <= 20 * FAST_EVAL_TOL * vs
    # and the direct path is the RBF's own evaluation
    v, g = f.value_and_gradient(x)
    np.testing.assert_allclose(ref[:, :2], v, rtol=0, atol=1e-10)
    np.testing.assert_allclose(ref[:, 2:].reshape(-1, 3, 2).transpose(0, 2, 1) / f.scale, g,
                               rtol=0, atol=1e-9)


def test_a_box_failing_its_check_is_split_or_evaluated_directly():
    """An impossible tolerance rejects every interpolation: everything is
    evaluated directly, bit for bit the reference."""
    f, fld, vs = _field(2)
    x = np.random.default_rng(3).uniform(-0.5, 0.5, (20_000, 3)) * [1, 1, 0.4]
    xn = (x - f.shift) / f.scale
    ref, _ = evaluate(fld, xn, tol=0.0, value_scale=vs, far_field=False)
    out, st = evaluate(fld, xn, tol=1e-300, value_scale=vs)
    assert st.n_rejected > 0 and st.n_interpolated == 0 and st.n_direct == len(x)
    ok, _ = evaluate(fld, xn, tol=FAST_EVAL_TOL, value_scale=vs)[1], None
    assert ok.n_interpolated > 0     # the same points do interpolate at the default
    np.testing.assert_allclose(out, ref, rtol=0, atol=1e-12)


def test_precompute_bench_quick_case_reports_every_path():
    """The handle-to-first-frame bench at a tiny size: one dict with the
    default, exact, IQR and scipy paths and the GEMM yardstick."""
    import json

    from splatedit.bench.precompute import precompute_case
    out = precompute_case(20_000, 8_000, gemm_size=256)
    json.dumps(out)
    for key in ("total_s", "exact_total_s", "iqr_total_s", "scipy_s", "gemm_s", "closure_s",
                "over_gemm", "dev_rel", "iqr_dev_rel", "scipy_dev_rel", "m", "pairs_fraction"):
        assert key in out, key
    assert out["support"] == 8_000 and out["dev_rel"] <= BUDGET
    assert out["exact_pairs_fraction"] == 1.0


def test_basis_fit_and_far_field_hold_blas_to_one_thread_and_restore_it(monkeypatch):
    """The RBF solve (small LAPACK calls: OpenBLAS's threads made an IQR fit
    16x slower on the loaded 2-core machine) and the far-field box tasks run
    with BLAS on one thread; the library's own setting is back afterwards."""
    from splatedit import blas
    from splatedit.deform import fast_eval
    from splatedit.deform import rbf as rbf_module
    seen = {"fit": [], "rbf_at": []}
    fit = rbf_module.TriharmonicRBF.fit.__func__
    rbf_at = fast_eval.RBFField.rbf_at

    def spy_fit(cls, *a, **kw):
        seen["fit"].append(blas.blas_threads())
        return fit(cls, *a, **kw)

    def spy_at(self, *a, **kw):
        seen["rbf_at"].append(blas.blas_threads())
        return rbf_at(self, *a, **kw)

    monkeypatch.setattr(rbf_module.TriharmonicRBF, "fit", classmethod(spy_fit))
    monkeypatch.setattr(fast_eval.RBFField, "rbf_at", spy_at)
    cloud = sphere_cloud(8_000)
    sup, hnd = _grab(cloud, 0.4, 0.03)
    before = blas.blas_threads()
    DeformationBasis.fit(cloud, sup, [hnd], fill_holes=False)
    assert seen["fit"] == [1] and seen["rbf_at"] and set(seen["rbf_at"]) == {1}
    assert blas.blas_threads() == before


def test_a_rejected_box_of_coincident_points_is_evaluated_directly():
    """Thousands of copies of one point form a box that cannot be split; when
    its interpolant fails the check (an impossible tolerance here) it is
    evaluated directly instead of being split forever."""
    f, fld, vs = _field(4)
    x = np.concatenate([np.repeat(f.centers[:1] * 0.5, 12_000, axis=0),
                        np.random.default_rng(5).uniform(-0.5, 0.5, (12_000, 3)) * [1, 1, 0.4]])
    xn = (x - f.shift) / f.scale
    ref, _ = evaluate(fld, xn, tol=0.0, value_scale=vs, far_field=False)
    out, st = evaluate(fld, xn, tol=1e-300, value_scale=vs)
    assert st.n_rejected > 0 and st.n_direct == len(x)
    np.testing.assert_allclose(out, ref, rtol=0, atol=1e-12)


def test_basis_evaluated_in_spatial_chunks_matches_the_exact_basis(monkeypatch):
    """A support larger than one evaluation call is evaluated in chunks of
    compact slabs (coarse grid order, here of a shuffled cloud); every row
    lands in its place: within the tolerance of the exact basis."""
    import splatedit.deform.basis as basis_module
    cloud = sphere_cloud(60_000)
    perm = np.random.default_rng(6).permutation(cloud.n)
    cloud = SplatCloud(cloud.positions[perm], cloud.u[perm], cloud.v[perm])
    sup, hnd = _grab(cloud, 0.5, 0.03)
    exact = DeformationBasis.fit(cloud, sup, [hnd], method="lu", fill_holes=False, eval_tol=0.0)
    monkeypatch.setattr(basis_module, "_FAST_CHUNK", 10_000)
    fast = DeformationBasis.fit(cloud, sup, [hnd], method="lu", fill_holes=False)
    assert fast.stats["eval_interpolated"] > 0.1 * fast.stats["n_free"]
    vs = float(np.abs(exact.constraints.values).max())
    assert np.abs(fast.B - exact.B).max() <= 20 * FAST_EVAL_TOL * vs
    scale = fast.rbf.scale
    for a, b in ((fast.Bx, exact.Bx), (fast.By, exact.By), (fast.Bz, exact.Bz)):
        assert np.abs(a - b).max() * scale <= 20 * FAST_EVAL_TOL * vs
