"""Constraints of the modeling metaphor: bands, control frames, affine
coordinates, and the error of every bad selection."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from splatedit.bench.solve import sphere_cloud, wavy_plane_cloud
from splatedit.deform.constraints import build_constraints
from splatedit.deform.frames import affine_coordinate_gradients, affine_coordinates, handle_frame
from splatedit.errors import ParameterError, SolverError
from splatedit.tolerances import BAND_RINGS


@pytest.fixture(scope="module")
def plane():
    return wavy_plane_cloud(60)


def disc(cloud, r, c=(0.0, 0.0)):
    return np.linalg.norm(cloud.positions[:, :2] - np.asarray(c), axis=1) <= r


# ------------------------------------------------------------- affine coords
@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10_000))
def test_affine_coordinates_reconstruct_and_sum_to_one(seed):
    rng = np.random.default_rng(seed)
    frame = rng.normal(size=(4, 3))
    if abs(np.linalg.det(frame[1:] - frame[0])) < 1e-3:
        frame[1:] += np.eye(3)
    pts = rng.normal(size=(50, 3)) * 3
    m = affine_coordinates(pts, frame)
    assert m.shape == (50, 4)
    np.testing.assert_allclose(m.sum(axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(m @ frame, pts, atol=1e-9 * (1 + np.abs(pts).max()))
    # the gradients are those of the (affine) coordinate functions
    g = affine_coordinate_gradients(frame)
    np.testing.assert_allclose(g.sum(axis=0), 0.0, atol=1e-12)
    step = rng.normal(size=3)
    np.testing.assert_allclose(affine_coordinates(pts + step, frame) - m,
                               np.broadcast_to(g @ step, m.shape), atol=1e-9)


def test_affine_coordinates_reject_degenerate_frame():
    with pytest.raises(ParameterError, match="coplanar"):
        affine_coordinates(np.zeros((2, 3)), np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.0]]))


def test_handle_frame_is_centroid_plus_scaled_axes_and_well_conditioned():
    # a flat handle (all z = 0) still gets a regular frame
    rng = np.random.default_rng(1)
    pts = np.column_stack([rng.uniform(-2, 2, 200), rng.uniform(-1, 1, 200), np.zeros(200)])
    f = handle_frame(pts, spacing=0.01)
    np.testing.assert_allclose(f[0], pts.mean(0))
    r = np.sqrt(np.mean(np.sum((pts - pts.mean(0)) ** 2, axis=1)))
    np.testing.assert_allclose(f[1:] - f[0], r * np.eye(3))
    m = affine_coordinates(pts, f)
    assert np.abs(m).max() < 4.0  # O(1) coordinates on the handle
    # a single-splat handle: the frame edge is one spacing
    f1 = handle_frame(pts[:1], spacing=0.5)
    np.testing.assert_allclose(f1[1:] - f1[0], 0.5 * np.eye(3))


# ------------------------------------------------------------------- bands
def test_bands_are_three_spacings_thick_on_the_right_side(plane):
    sup, hnd = disc(plane, 0.7), disc(plane, 0.2)
    con = build_constraints(plane, sup, [hnd])
    pos = plane.positions
    h = con.spacing
    np.testing.assert_allclose(h, 2.0 / 59, rtol=0.05)  # grid spacing (in xy; z adds a bit)
    assert con.band_width == pytest.approx(BAND_RINGS * h)
    # fixed band: exactly the outside splats within the width of the support
    d_sup, _ = cKDTree(pos[sup]).query(pos)
    expect_fixed = np.flatnonzero(~sup & (d_sup <= con.band_width * (1 + 1e-9)))
    np.testing.assert_array_equal(con.fixed_index, expect_fixed)
    assert not sup[con.fixed_index].any()
    # it has about three rings: fixed band splats lie between 0 and 3 spacings away
    assert d_sup[con.fixed_index].max() <= con.band_width * (1 + 1e-9)
    assert d_sup[con.fixed_index].max() > 2 * h
    # handle band: the handle splats within the width of the free region
    free = sup & ~hnd
    d_free, _ = cKDTree(pos[free]).query(pos)
    expect_band = np.flatnonzero(hnd & (d_free <= con.band_width * (1 + 1e-9)))
    np.testing.assert_array_equal(con.handle_band_index[0], expect_band)
    assert len(expect_band) < hnd.sum()  # the handle's inside is not constrained
    np.testing.assert_array_equal(con.free_index, np.flatnonzero(free))
    np.testing.assert_array_equal(con.support_index, np.flatnonzero(sup))


def test_values_are_block_affine_coordinates(plane):
    sup = disc(plane, 0.8)
    h1, h2 = disc(plane, 0.15, (0.4, 0)), disc(plane, 0.15, (-0.4, 0))
    con = build_constraints(plane, sup, [h1, h2])
    assert con.values.shape == (con.n_constraints, 8)
    assert con.control_frames.shape == (2, 4, 3)
    f = len(con.fixed_index)
    np.testing.assert_array_equal(con.values[:f], 0.0)
    np.testing.assert_array_equal(con.points[:f], plane.positions[con.fixed_index])
    for i, band in enumerate(con.handle_band_index):
        rows, cols = con.rows(i), con.columns(i)
        assert cols == slice(4 * i, 4 * i + 4)
        np.testing.assert_array_equal(con.points[rows], plane.positions[band])
        block = con.values[rows]
        np.testing.assert_allclose(block[:, cols], affine_coordinates(con.points[rows],
                                                                       con.control_frames[i]))
        other = np.delete(np.arange(8), np.arange(4 * i, 4 * i + 4))
        np.testing.assert_array_equal(block[:, other], 0.0)
        np.testing.assert_allclose(block[:, cols] @ con.control_frames[i], con.points[rows],
                                   atol=1e-12)
    assert [g.kind for g in con.groups] == ["handle", "handle"]


def test_index_arrays_are_accepted(plane):
    sup, hnd = disc(plane, 0.7), disc(plane, 0.2)
    a = build_constraints(plane, sup, [hnd])
    b = build_constraints(plane, np.flatnonzero(sup), [np.flatnonzero(hnd)])
    np.testing.assert_array_equal(a.points, b.points)
    np.testing.assert_array_equal(a.values, b.values)


def test_whole_model_support_has_no_fixed_band_and_is_allowed(plane):
    con = build_constraints(plane, np.ones(len(plane), bool), [disc(plane, 0.2)])
    assert not con.has_fixed_band
    assert len(con.fixed_index) == 0
    assert con.n_constraints == len(con.handle_band_index[0])


def test_exact_duplicate_band_points_are_dropped():
    c = wavy_plane_cloud(40)
    # duplicate every splat: same positions twice
    from splatedit.model.cloud import SplatCloud
    d = SplatCloud(np.vstack([c.positions, c.positions]), np.vstack([c.u, c.u]),
                   np.vstack([c.v, c.v]))
    sup = np.tile(disc(c, 0.7), 2)
    hnd = np.tile(disc(c, 0.2), 2)
    con = build_constraints(d, sup, [hnd], spacing=2.0 / 39)
    one = build_constraints(c, disc(c, 0.7), [disc(c, 0.2)], spacing=2.0 / 39)
    assert con.n_constraints == one.n_constraints


# ------------------------------------------------------------------ errors
def test_error_empty_support(plane):
    with pytest.raises(ParameterError, match="support.*no splats"):
        build_constraints(plane, np.zeros(len(plane), bool), [disc(plane, 0.2)])


def test_error_no_handles(plane):
    with pytest.raises(ParameterError, match="at least one handle"):
        build_constraints(plane, disc(plane, 0.7), [])


def test_error_empty_handle(plane):
    with pytest.raises(ParameterError, match=r"handles\[0\].*empty handle"):
        build_constraints(plane, disc(plane, 0.7), [np.zeros(len(plane), bool)])


def test_error_handle_outside_support(plane):
    with pytest.raises(ParameterError, match=r"handles\[0\].*outside the support"):
        build_constraints(plane, disc(plane, 0.3), [disc(plane, 0.5)])


def test_error_overlapping_handles(plane):
    with pytest.raises(ParameterError, match=r"handles\[1\].*overlaps handles\[0\]"):
        build_constraints(plane, disc(plane, 0.8), [disc(plane, 0.2), disc(plane, 0.2, (0.1, 0))])


def test_error_no_free_points(plane):
    sup = disc(plane, 0.5)
    with pytest.raises(ParameterError, match="no free splats"):
        build_constraints(plane, sup, [sup])


def test_error_handle_not_next_to_free_region(plane):
    # the support is two far-apart discs; the handle is the whole second disc
    a, b = disc(plane, 0.2, (-0.6, 0)), disc(plane, 0.2, (0.6, 0))
    with pytest.raises(SolverError, match="handle 0 has no splat within"):
        build_constraints(plane, a | b, [b])


def test_error_bad_mask_shape_and_indices(plane):
    with pytest.raises(ParameterError, match="support.*shape"):
        build_constraints(plane, np.ones(3, bool), [disc(plane, 0.2)])
    with pytest.raises(ParameterError, match="out of range"):
        build_constraints(plane, disc(plane, 0.7), [np.array([len(plane) + 5])])
    with pytest.raises(ParameterError, match="rings"):
        build_constraints(plane, disc(plane, 0.7), [disc(plane, 0.2)], rings=0)


def test_fixed_duplicate_of_a_handle_splat_is_dropped_and_reported_as_a_conflict():
    c = sphere_cloud(2000)
    from splatedit.model.cloud import SplatCloud
    # splat 0 duplicated: one copy in the handle, the other outside the support
    d = SplatCloud(np.vstack([c.positions, c.positions[:1]]), np.vstack([c.u, c.u[:1]]),
                   np.vstack([c.v, c.v[:1]]))
    top = d.positions[0]
    dist = np.linalg.norm(d.positions - top, axis=1)
    sup = dist <= 0.9
    hnd = dist <= 0.3
    sup[-1] = hnd[-1] = False
    con = build_constraints(d, sup, [hnd], rings=40)
    assert len(con.conflicts) == 1 and con.conflicts[0].handle == 0
    dup = len(d.positions) - 1
    assert dup in con.conflicts[0].fixed_index and dup not in con.fixed_index
    assert con.conflicts[0].min_distance == 0.0
    assert "fixed splats lie within" in con.conflicts[0].describe(con.spacing)
    # the kept constraints have distinct positions, so the fit is well posed
    assert len(np.unique(con.points, axis=0)) == len(con.points)


def test_every_point_duplicated_edits_and_the_copies_move_together():
    """An unwelded triangle soup stores each vertex several times: the spacing
    is that of the distinct positions, bands and closure work, and the copies
    of a splat end up at the same place (issue 12, class 4)."""
    from splatedit.data import default_model_path
    from splatedit.deform import DeformationBasis, transform
    from splatedit.io import read
    from splatedit.model.cloud import SplatCloud
    from splatedit.model.spacing import point_spacing
    c = read(default_model_path())
    n = c.n
    d = SplatCloud(np.vstack([c.positions] * 2), np.vstack([c.u] * 2), np.vstack([c.v] * 2))
    assert point_spacing(d.positions) == point_spacing(c.positions) > 0
    tip = c.positions[np.argmax(c.positions[:, 1])]
    dist = np.linalg.norm(d.positions - tip, axis=1)
    basis = DeformationBasis.fit(d, dist < 0.2, [dist < 0.05])
    out = basis.apply(d, basis.displacement([transform.translate([0.05, 0.0, 0.0])]))
    moved = np.linalg.norm(out.positions[:n] - c.positions, axis=1) > 0
    assert moved.sum() > 1000
    np.testing.assert_allclose(out.positions[:n], out.positions[n:], rtol=0, atol=1e-12)
