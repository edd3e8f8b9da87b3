"""The live readout of a G/R/S move: the distance / angle / factor the
matrix applies, from the mouse or from typed keys."""

from __future__ import annotations

import math

import numpy as np

from splatedit.app.document.manipulation import GRAB, ROTATE, SCALE, Manipulation, ViewInfo


def _view(wpp=0.01):
    return ViewInfo(np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), np.array([0, 0, 1.0]), (100.0, 100.0), wpp)


def _number(text, word):
    return float(text.split(word)[1].split()[0].rstrip("x"))


def test_grab_readout_is_the_matrix_translation():
    m = Manipulation(GRAB, np.zeros(3), _view(), (100.0, 100.0))
    m.mouse = (130.0, 60.0)                       # 30 px right, 40 px up at 0.01 units / px
    t = m.matrix()[:3, 3]
    assert np.allclose(t, [0.3, 0.4, 0.0])
    assert math.isclose(_number(m.readout(), "distance"), 0.5, rel_tol=1e-3)
    m.set_axis(0)
    assert m.readout().startswith("distance X 0.3")
    for ch in "-2":
        m.type_char(ch)
    assert "(typed)" in m.readout() and _number(m.readout(), "distance X") == -2.0   # signed along the axis
    assert np.allclose(m.matrix()[:3, 3], [-2.0, 0, 0])


def test_rotate_readout_is_the_swept_angle():
    m = Manipulation(ROTATE, np.zeros(3), _view(), (150.0, 100.0))
    m.mouse = (100.0, 50.0)                       # a quarter turn counter-clockwise on screen
    ang = _number(m.readout(), "angle")
    assert math.isclose(abs(ang), 90.0, abs_tol=1e-6)
    r = m.matrix()[:3, :3]
    assert math.isclose(math.degrees(math.acos((np.trace(r) - 1) / 2)), 90.0, abs_tol=1e-6)
    m.mouse = (160.0, 101.0)                      # almost back: a small angle, not ~360
    assert abs(_number(m.readout(), "angle")) < 2.0


def test_scale_readout_is_the_factor():
    m = Manipulation(SCALE, np.zeros(3), _view(), (120.0, 100.0))
    m.mouse = (140.0, 100.0)                      # twice as far from the pivot's pixel
    assert math.isclose(_number(m.readout(), "factor"), 2.0)
    assert np.allclose(np.diag(m.matrix())[:3], 2.0)


def test_grab_readout_is_signed_along_the_axis_and_never_shows_minus_zero():
    """The tester's `distance X 0.1861 (-0.186, -0, -0)`: the main figure along
    an axis keeps the move's sign and a zero component reads 0."""
    m = Manipulation(GRAB, np.zeros(3), _view(), (100.0, 100.0))
    m.set_axis(0)
    m.mouse = (81.39, 100.0)                      # 18.61 px left: -0.1861 along X
    text = m.readout()
    assert text.startswith("distance X -0.1861 ") and "(-0.186, 0, 0)" in text and "-0," not in text
    assert m.label() == "Grab -0.186 along X"


def test_moves_name_their_history_entries():
    m = Manipulation(ROTATE, np.zeros(3), _view(), (120.0, 100.0))
    m.set_axis(2)
    for ch in "45":
        m.type_char(ch)
    assert m.label() == "Rotate 45 deg about Z"
    s = Manipulation(SCALE, np.zeros(3), _view(), (120.0, 100.0))
    for ch in "1.38":
        s.type_char(ch)
    assert s.label() == "Scale x1.38"
    g = Manipulation(GRAB, np.zeros(3), _view(), (100.0, 100.0))
    g.mouse = (112.0, 100.0)
    assert g.label() == "Grab 0.12"
