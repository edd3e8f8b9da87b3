"""Brush logic on synthetic pick maps."""

import numpy as np

from splatedit.app.tools.pick_brush import BrushPicker, indices_in_circle, stroke_points


def grid_pick(h=40, w=60):
    # splat index = column block of 10 px x row block of 10 px; background on the last rows
    ys, xs = np.mgrid[0:h, 0:w]
    pick = (ys // 10) * 100 + xs // 10
    pick[h - 5:] = -1
    return pick


def test_indices_in_circle_exact_and_ignores_background():
    pick = grid_pick()
    got = indices_in_circle(pick, 15, 15, 3)
    assert got.tolist() == [101]
    got = indices_in_circle(pick, 20, 20, 2)
    assert sorted(got.tolist()) == [101, 102, 201, 202]
    assert indices_in_circle(pick, 30, 38, 2).tolist() == []
    assert indices_in_circle(pick, -100, -100, 5).size == 0


def test_circle_is_round_not_square():
    pick = np.arange(100 * 100).reshape(100, 100)
    got = indices_in_circle(pick, 50, 50, 10)
    assert 300 < len(got) < 330  # pi r^2 ~ 314, a square would be ~400
    ys, xs = np.divmod(got, 100)
    assert ((xs + 0.5 - 50) ** 2 + (ys + 0.5 - 50) ** 2 <= 100).all()


def test_stroke_points_cover_fast_drag():
    pts = stroke_points(0, 0, 100, 0, 10)
    assert pts[-1] == (100, 0)
    xs = [0] + [p[0] for p in pts]
    assert max(np.diff(xs)) <= 5.0 + 1e-9


def test_picker_adds_subpixel_visible_splats_only():
    pick = np.full((20, 20), -1)
    pick[:, :] = 0                      # splat 0 covers the screen at depth 1
    centers = np.array([[10, 10], [10.5, 10.5], [11, 11], [50, 50]], float)
    depths = np.array([1.0, 1.01, 5.0, 1.0])   # splat 2 is hidden behind splat 0
    tol = np.full(4, 0.02)
    bp = BrushPicker(pick, centers, depths, tol)
    got = bp.query(10, 10, 3).tolist()
    assert got == [0, 1]
    # with the renderer's front depth per pixel instead of the front splat's depth
    bp = BrushPicker(pick, centers, depths, tol, pick_depth=np.full((20, 20), 0.995))
    assert bp.query(10, 10, 3).tolist() == [0, 1]
    pd = np.full((20, 20), 0.9)
    bp = BrushPicker(pick, centers, depths, tol, pick_depth=pd)
    assert bp.query(10, 10, 3).tolist() == [0]     # both centres are behind the front surface
