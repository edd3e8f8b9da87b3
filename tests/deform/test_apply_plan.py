"""The linear CPU apply's hot path (splatedit.deform.apply_plan): memory bounded by
what it keeps and returns, chunking invisible in the results, sub-chunks on one
BLAS thread; the chunked Jacobians."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

import splatedit.deform.apply_plan as apply_plan
import splatedit.deform.basis as basis_module
from splatedit.bench.solve import wavy_plane_cloud
from splatedit.deform.basis import DeformationBasis
from splatedit.deform.modes import DeformationMode
from splatedit.deform.transform import compose, rotate, translate
from splatedit.model.cloud import SplatCloud


def _peak_above(fn):
    """``(result, peak bytes)`` of numpy allocations during ``fn()`` above
    what was allocated before it (tracemalloc)."""
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        out = fn()
        return out, tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()


def test_hot_path_build_and_apply_on_1m_splats_stay_within_what_they_keep_and_return():
    """1M-splat wavy plane, a square support of 810k splats, K = 4 basis
    columns (one handle; the values do not matter for memory).  Building the
    hot path peaks at most 1.5x the arrays it keeps (the version that
    gathered all basis rows at once peaked at 2.35x, measured); one apply at
    most 1.1x the three (n, 3) outputs (measured 1.04x): no support-sized
    temporaries."""
    cloud = wavy_plane_cloud(1000)
    xy = cloud.positions[:, :2]
    idx = np.flatnonzero(np.max(np.abs(xy), axis=1) <= 0.9)
    rng = np.random.default_rng(0)
    pack = np.resize(0.1 * rng.standard_normal((4099, 4, 4)), (len(idx), 4, 4))   # cheap to make
    c, build_peak = _peak_above(lambda: apply_plan.build_hot_path(pack, idx, cloud))
    kept = sum(a.nbytes for a in c["arrays"])
    assert kept == 3 * (len(idx) + len(c["filler"])) * 7 * 8     # support + gaps computed through
    srcs = (cloud.positions, cloud.u, cloud.v)
    d = 0.01 * rng.standard_normal((4, 3))
    outs, apply_peak = _peak_above(lambda: apply_plan.apply_hot_path(c, srcs, d))
    returned = sum(o.nbytes for o in outs)
    print(f"build peak {build_peak / kept:.2f}x kept, apply peak {apply_peak / returned:.3f}x outputs")
    assert build_peak < 1.5 * kept
    assert apply_peak < 1.1 * returned
    # and it is the deformation: p' = p + B dC on the support, p elsewhere
    np.testing.assert_allclose(outs[0][idx], cloud.positions[idx] + pack[:, 0, :] @ d, rtol=0, atol=1e-15)
    rest = np.ones(len(cloud), bool)
    rest[idx] = False
    assert outs[0][rest].tobytes() == cloud.positions[rest].tobytes()


@pytest.fixture(scope="module")
def scattered():
    """A plane in shuffled file order (the run plan's index-array segments)
    and in grid order (its slices), each with a fitted one-handle basis."""
    grid = wavy_plane_cloud(70)
    perm = np.random.default_rng(5).permutation(len(grid))
    out = []
    for cloud in (grid, SplatCloud(grid.positions[perm], grid.u[perm], grid.v[perm])):
        r = np.linalg.norm(cloud.positions[:, :2], axis=1)
        basis = DeformationBasis.fit(cloud, r < 0.8, [r < 0.25], method="lu", fill_holes=False)
        out.append((cloud, basis))
    return out


@pytest.mark.parametrize("which", [0, 1], ids=["grid-order", "shuffled"])
def test_chunked_apply_equals_the_unchunked_one(scattered, which, monkeypatch):
    """Sub-chunks of 256 splats (the smallest) and build blocks of 100 plan rows against one
    GEMM per segment and one build block: the same deformed cloud (within
    1e-15 of the model size: only BLAS's blocking of the same sums differs)."""
    cloud, basis = scattered[which]
    d = basis.displacement([compose(rotate((0.2, 1.0, 0.1), 25.0, (0.1, 0.0, 0.2)),
                                    translate((0.0, 0.0, 0.2)))])
    monkeypatch.setattr(apply_plan, "LINEAR_APPLY_CHUNK", 1 << 30)
    monkeypatch.setattr(apply_plan, "BLAS_SINGLE_THREAD_MNK", 1 << 62)
    monkeypatch.setattr(apply_plan, "_BUILD_BLOCK", 1 << 30)
    whole = basis.apply_arrays(cloud, d)
    basis.release_cpu_cache()
    monkeypatch.setattr(apply_plan, "LINEAR_APPLY_CHUNK", 256)
    monkeypatch.setattr(apply_plan, "_BUILD_BLOCK", 100)
    chunked = basis.apply_arrays(cloud, d)
    assert max(hi - lo for lo, hi, _ in basis._cpu["segments"]) > 256     # really sub-chunked
    for a, b in zip(whole, chunked):
        assert np.abs(a - b).max() <= 1e-15 * cloud.diagonal
    moved = np.linalg.norm(whole[0] - cloud.positions, axis=1)
    assert moved.max() > 0.1 and (moved == 0).sum() > 0


def test_apply_sub_chunks_stay_on_one_blas_thread():
    """For 1-4 handles and curves' extra columns, every linear-apply product
    (c, K + 3) @ (K + 3, 3) is below the m n k where OpenBLAS starts a second
    thread, and c is at most LINEAR_APPLY_CHUNK."""
    from splatedit.tolerances import BLAS_SINGLE_THREAD_MNK, LINEAR_APPLY_CHUNK, ROTATION_APPLY_MIN_CHUNK
    for k in (4, 8, 12, 16, 22, 40):
        c = apply_plan.apply_chunk_rows(k)
        assert ROTATION_APPLY_MIN_CHUNK <= c <= LINEAR_APPLY_CHUNK
        assert c * (k + 3) * 3 < BLAS_SINGLE_THREAD_MNK, k


@pytest.mark.parametrize("mode", [DeformationMode.LINEAR, DeformationMode.ROTATION])
def test_chunked_jacobians_equal_the_whole_support_formula(scattered, mode, monkeypatch):
    """Jacobians computed in chunks of 300 splats equal I + (Bx, By, Bz) dC
    (plus the blended rotations) taken over the whole support at once."""
    from splatedit.deform.rotation import blend_jacobians, handle_blocks, split_displacement
    cloud, basis = scattered[1]
    d = basis.displacement([rotate((0.0, 1.0, 0.3), 60.0, (0.0, 0.0, 0.1))], mode=mode)
    monkeypatch.setattr(basis_module, "_BASIS_CHUNK", 300)
    jac = basis.jacobians(d)
    dc, rot = split_displacement(d)
    expect = np.einsum("njk,ki->nij", basis._pack[:, 1:, :], dc) + np.eye(3)
    if rot is not None:
        expect += blend_jacobians(rot, basis._pack, handle_blocks(basis))
    assert len(basis.indices) > 2 * 300
    np.testing.assert_allclose(jac, expect, rtol=0, atol=1e-13)
    assert (mode is DeformationMode.ROTATION) == (rot is not None)
