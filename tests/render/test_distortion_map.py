"""Distortion heat map (Renderer.distortion_map): the stretch computed in the
pre-pass / vertex shader from the Jacobian it applies, against the CPU
definition (splatedit.deform.distortion), and the colours of the ramp."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.deform.distortion import distortion_from_axes
from splatedit.render.camera import Camera
from splatedit.tolerances import DISTORTION_HEAT_MAX_STRETCH
from tests.render.deform_util import cpu_deform
from tests.render.scenes import plane

W = H = 160
#: seen 35 degrees off the plane's normal: no specular highlight (R.V = cos 70 deg)
VIEW = (0.0, -0.7, 1.0)


@pytest.fixture(params=[True, False], ids=["prepass", "vertex"])
def heat(renderer, request):
    saved = renderer.prepass, renderer.distortion_map
    renderer.prepass, renderer.distortion_map = request.param, True
    yield renderer
    renderer.prepass, renderer.distortion_map = saved


#: the support (x > 0) stays rigid up to x = CALM_BAND: a band of 1x stretch as
#: wide as 30% of the plane, whatever pixels a driver's blending gives the
#: support's border (an H200 left 5 and 49 calm pixels of a 1x band only a
#: few splats wide)
CALM_BAND = 0.3


def _quadratic_stretch(cloud, a=3.0 / (2.0 * (1.0 - CALM_BAND))):
    """Splats with x > 0 move by a max(x - CALM_BAND, 0)^2 along x:
    J = I + 2 a max(x - CALM_BAND, 0) e_x e_x^T, so a splat's stretch is 1x up
    to x = CALM_BAND, then 1 + 2 a (x - CALM_BAND), up to 4x at x = 1."""
    idx = np.flatnonzero(cloud.positions[:, 0] > 0.0)
    d = np.maximum(cloud.positions[idx, :1] - CALM_BAND, 0.0)
    B, Bx, zero = d * d, 2.0 * d, np.zeros_like(d)
    return idx, (B, Bx, zero, zero), np.array([[a, 0.0, 0.0]])


def test_translation_is_neutral(heat):
    base = plane(60)
    idx = np.flatnonzero(base.positions[:, 0] > -0.2)
    one, zero = np.ones((len(idx), 1)), np.zeros((len(idx), 1))
    heat.set_cloud(base)
    heat.set_basis(idx, one, zero, zero, zero)
    heat.set_displacement([[0.3, 0.1, 0.2]])
    lo, hi = base.bounds()
    cam = Camera.frame(lo, hi + [0.3, 0.1, 0.2], 1.0, direction=VIEW)
    buf = heat.render_buffers(cam, W, H)
    img = heat.render(cam, W, H)[..., :3].astype(int)
    fg = buf["weight"] > 0
    sup = fg & (buf["color"][..., 1] > 0.99)
    other = fg & (buf["color"][..., 1] < 0.01)
    assert sup.sum() > 3000 and other.sum() > 1000
    assert np.abs(buf["color"][..., 0][sup]).max() < 1e-3          # log(stretch) = 0
    chroma = img.max(axis=2) - img.min(axis=2)
    assert chroma[sup].max() <= 8                                    # neutral grey, no tint
    assert chroma[other].max() <= 2
    lum = img.mean(axis=2)
    assert lum[sup].mean() > lum[other].mean() + 30                  # support lighter than the rest


@pytest.mark.parametrize("a", [-0.6, 1.5, 2.5])
def test_uniform_stretch_is_encoded_exactly(heat, a):
    """B = x, Bx = 1: J = I + a e_x e_x^T on the support, stretch max(1 + a, 1 / (1 + a))."""
    base = plane(40)
    idx = np.flatnonzero(base.positions[:, 0] > -0.5)
    x = base.positions[idx, :1]
    zero = np.zeros_like(x)
    heat.set_cloud(base)
    heat.set_basis(idx, x, np.ones_like(x), zero, zero)
    heat.set_displacement([[a, 0.0, 0.0]])
    deformed = cpu_deform(base, idx, x, np.ones_like(x), zero, zero, np.array([[a, 0.0, 0.0]]))
    ref = distortion_from_axes(base.u[idx], base.v[idx], deformed.u[idx], deformed.v[idx])
    np.testing.assert_allclose(ref.stretch, max(1 + a, 1 / (1 + a)), rtol=1e-12)
    cam = Camera.frame(*deformed.bounds(), 1.0, direction=VIEW)
    col = heat.render_buffers(cam, W, H)["color"]
    sup = col[..., 1] > 0.99
    assert sup.sum() > 2000
    want = np.log(ref.max_stretch) / np.log(DISTORTION_HEAT_MAX_STRETCH)
    # 8-bit unorm record colour (pre-pass), then 16-bit float accumulation
    np.testing.assert_allclose(col[..., 0][sup] / col[..., 1][sup], min(want, 1.0), atol=1.5 / 255)


def test_stretch_matches_the_cpu_definition_and_turns_red_beyond_3x(heat):
    base = plane(60)
    idx, (B, Bx, By, Bz), dC = _quadratic_stretch(base)
    deformed = cpu_deform(base, idx, B, Bx, By, Bz, dC)
    ref = distortion_from_axes(base.u[idx], base.v[idx], deformed.u[idx], deformed.v[idx])
    stretch = np.ones(base.n)
    stretch[idx] = ref.stretch
    assert 3.9 < ref.max_stretch <= 4.0
    heat.set_cloud(base)
    heat.set_basis(idx, B, Bx, By, Bz)
    heat.set_displacement(dC)
    cam = Camera.frame(*deformed.bounds(), 1.0, direction=VIEW)
    buf = heat.render_buffers(cam, W, H)
    img = heat.render(cam, W, H)[..., :3].astype(int)
    pick, _ = heat.pick(cam, W, H)
    col = buf["color"]
    sup = (buf["weight"] > 0) & (col[..., 1] > 0.99) & (pick >= 0)
    assert sup.sum() > 3000
    s = stretch[pick[sup]]
    want = np.log(s) / np.log(DISTORTION_HEAT_MAX_STRETCH)
    got = col[..., 0][sup] / col[..., 1][sup]
    err = np.abs(got - want)
    # a pixel blends the picked splat with its neighbours, whose t differs by
    # ~0.07 / stretch per grid step (0.1 in stretch), plus the 8-bit encoding
    assert np.median(err) < 0.02 and np.quantile(err, 0.99) < 0.08, (np.median(err), err.max())
    r, g, b = (img[..., c][sup] for c in range(3))
    red = s > 3.1
    assert red.sum() > 200
    assert (r[red] > 90).all() and (r[red] > 3 * g[red]).all() and (r[red] > 2 * b[red]).all()
    calm = s < 1.1
    mid = (s > 1.8) & (s < 2.2)                                      # orange: red > green > blue
    # lavapipe: 922 calm, 438 mid, 2026 red pixels; the calm band is ~20 splats wide
    assert calm.sum() > 500 and mid.sum() > 200, (calm.sum(), mid.sum(), red.sum())
    assert ((r[mid] > g[mid]) & (g[mid] > b[mid])).mean() > 0.95
    assert np.mean(r[calm] - b[calm]) < 0.5 * np.mean(r[mid] - b[mid])   # ~1x: near neutral
    # the ramp darkens monotonically: luminance falls with the stretch
    assert np.corrcoef(s, (r + g + b) / 3.0)[0, 1] < -0.9


def test_glsl_heat_constant_mirrors_the_tolerance():
    import re
    from pathlib import Path
    src = (Path(__file__).resolve().parents[2] / "shaders_glsl" / "distortion.glsl").read_text()
    m = re.search(r"const float HEAT_MAX_STRETCH = ([0-9.]+);", src)
    assert m and float(m[1]) == DISTORTION_HEAT_MAX_STRETCH
    for t, stretch in re.findall(r"const float T\w+ = ([0-9.]+);\s*// log\(([0-9.]+)\) / log\(4\)", src):
        assert float(t) == pytest.approx(np.log(float(stretch)) / np.log(DISTORTION_HEAT_MAX_STRETCH), abs=1e-7)
