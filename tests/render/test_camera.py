"""Camera tolerances come from splatedit.tolerances (no magic numbers in camera.py)."""

from __future__ import annotations

import ast
from pathlib import Path

import numpy as np
import pytest

import splatedit.render.camera as camera_mod
from splatedit.errors import ParameterError
from splatedit.render.camera import Camera
from splatedit.tolerances import RENDER_CLIP_MIN_RADIUS_REL, RENDER_FRAME_MIN_RADIUS_REL


def test_camera_has_no_tolerance_literals():
    """Only structural constants (0, 1, 2, 0.5, ...) appear as literals; tolerances are named."""
    tree = ast.parse(Path(camera_mod.__file__).read_text())
    nums = {n.value for n in ast.walk(tree) if isinstance(n, ast.Constant)
            and isinstance(n.value, (int, float)) and not isinstance(n.value, bool)}
    assert nums <= {0, 1, 2, 3, 4, 0.5, 179.0}, sorted(nums)


def test_up_parallel_threshold_is_the_named_constant(monkeypatch):
    with pytest.raises(ParameterError, match="parallel"):
        Camera((0, 0, 5), (0, 0, 0), up=(0, 0, 1))
    tilted = (0.0, 0.05, 1.0)              # sine of the angle to the view axis ~0.05
    Camera((0, 0, 5), (0, 0, 0), up=tilted)
    monkeypatch.setattr(camera_mod, "RENDER_CAMERA_MIN_UP_SINE", 0.1)
    with pytest.raises(ParameterError, match="parallel"):
        Camera((0, 0, 5), (0, 0, 0), up=tilted)


def test_degenerate_bounds_use_the_named_minimum_radii():
    p = np.array([1.0, 2.0, 3.0])
    cam = Camera.frame(p, p)                # a single point
    d = float(np.linalg.norm(cam.eye - p))
    assert d > 0 and np.isclose(d * np.sin(np.radians(cam.fov_deg / 2)),
                                RENDER_FRAME_MIN_RADIUS_REL * 3.0 * camera_mod.RENDER_FRAME_MARGIN)
    near, far = cam.clip_range(p, p)
    assert 0 < near < far
    # with the splat radius given, the point is framed by its splat
    cam = Camera.frame(p, p, min_radius=0.25)
    d = float(np.linalg.norm(cam.eye - p))
    assert np.isclose(d * np.sin(np.radians(cam.fov_deg / 2)), 0.25 * camera_mod.RENDER_FRAME_MARGIN)
    assert far - d <= 2 * RENDER_CLIP_MIN_RADIUS_REL * max(1.0, d)
