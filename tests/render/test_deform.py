"""GPU deformation (vertex shader, basis rows + dC) against the CPU-deformed cloud."""

from __future__ import annotations

import numpy as np
import pytest

from splatedit.errors import ParameterError
from splatedit.render.camera import Camera
from tests.render.deform_util import bump_basis, cpu_deform, gaussian_basis
from tests.render.scenes import sphere, torus

W = H = 192
#: GPU vs CPU deformed image: both paths use float32 on the GPU, differences are
#: rounding only; allow a few flipped edge pixels
MEAN_TOL = 0.25          # mean |diff| over RGB, 0..255 units
BAD_SHARE = 0.002        # share of pixels off by more than 16
DEPTH_TOL = 1e-3         # relative, median over pixels covered in both


def _compare(renderer, base, deformed, cam, setup):
    renderer.set_cloud(deformed)
    ref = renderer.render(cam, W, H)
    ref_buf = renderer.render_buffers(cam, W, H)
    renderer.set_cloud(base)
    setup()
    img = renderer.render(cam, W, H)
    buf = renderer.render_buffers(cam, W, H)
    diff = np.abs(img.astype(int) - ref.astype(int))[..., :3]
    assert diff.mean() < MEAN_TOL, diff.mean()
    assert (diff.max(axis=2) > 16).mean() < BAD_SHARE
    both = (ref_buf["weight"] > 0) & (buf["weight"] > 0)
    rel = np.abs(buf["depth"][both] - ref_buf["depth"][both]) / ref_buf["depth"][both]
    assert np.median(rel) < DEPTH_TOL
    return img


@pytest.mark.parametrize("k", [1, 4, 5, 8, 12, 16])
def test_gpu_deformation_matches_cpu(renderer, k):
    base = torus(100, 40)
    rng = np.random.default_rng(k)
    idx = np.flatnonzero(base.positions[:, 0] > -0.3)               # a support region
    B, Bx, By, Bz = gaussian_basis(base.positions[idx], k=k, seed=k)
    dC = rng.normal(scale=0.25, size=(k, 3))
    deformed = cpu_deform(base, idx, B, Bx, By, Bz, dC)
    cam = Camera.frame(*deformed.bounds(), 1.0, direction=(0.4, -0.8, 1.0))

    def setup():
        renderer.set_basis(idx, B, Bx, By, Bz)
        renderer.set_displacement(dC)
    img = _compare(renderer, base, deformed, cam, setup)
    assert (img[..., :3] < 250).any()


@pytest.mark.parametrize("k", [1, 5, 12, 16])
def test_vertex_path_deformation_matches_cpu(renderer, k):
    """The same with the all-in-vertex-shader path (basis rows as 4 * ceil(K/4) vertex attributes)."""
    saved = renderer.prepass
    renderer.prepass = False
    try:
        test_gpu_deformation_matches_cpu(renderer, k)
    finally:
        renderer.prepass = saved


def test_prepass_basis_windows(renderer, monkeypatch):
    """A basis larger than one storage binding is dispatched in windows (here
    forced small: 3 windows) with the same result."""
    base = torus(100, 40)
    k = 16
    idx = np.flatnonzero(base.positions[:, 1] > -0.5)
    B, Bx, By, Bz = gaussian_basis(base.positions[idx], k=k, seed=4)
    dC = np.random.default_rng(4).normal(scale=0.2, size=(k, 3))
    deformed = cpu_deform(base, idx, B, Bx, By, Bz, dC)
    cam = Camera.frame(*deformed.bounds(), 1.0, direction=(0.4, -0.8, 1.0))
    limits = renderer.dev.limits

    class Small:
        def __getattr__(self, name):
            return getattr(limits, name)
        maxStorageBufferRange = 256 * (base.n // 3 + 64)

    def setup():
        renderer.set_basis(idx, B, Bx, By, Bz)
        renderer.set_displacement(dC)
        monkeypatch.setattr(renderer.dev, "limits", Small())
    try:
        _compare(renderer, base, deformed, cam, setup)
        assert len(renderer.prepass_part.current.windows) == 1 and len(renderer.prepass_part.current.windows[0][2]) == 3
    finally:
        monkeypatch.undo()
        renderer.set_cloud(base)


@pytest.mark.parametrize("centre, dC, direction", [
    ((0.0, 0.0, 1.0), (0.0, 0.0, 1.6), (0.3, 0.2, 1.0)),      # pulled 1.6 units towards the eye
    ((0.7, 0.0, 0.7), (0.8, 0.0, -3.0), (0.0, 0.0, 1.0)),     # pushed 3 units away, beside the sphere
])
def test_deformation_beyond_the_undeformed_bounds_is_not_clipped(renderer, centre, dC, direction):
    """near/far come from the undeformed cloud; a displacement that leaves its
    bounding sphere must grow them (the editor: a handle dragged outside the
    model), so the GPU image equals the CPU-deformed cloud's with the same
    camera (framed on the undeformed cloud, as in the editor)."""
    base = sphere(5000)
    idx = np.arange(base.n)
    B = bump_basis(base.positions, centre, sigma=0.8)
    dC = np.array([dC])
    deformed = cpu_deform(base, idx, *B, dC)
    cam = Camera.frame(*base.bounds(), 1.0, direction=direction)
    near, far = cam.clip_range(*base.bounds())
    depth = (deformed.positions - cam.eye) @ ((cam.target - cam.eye) / np.linalg.norm(cam.target - cam.eye))
    assert depth.min() < near or depth.max() > far        # the undeformed clip range would cut it

    def setup():
        renderer.set_basis(idx, *B)
        renderer.set_displacement(dC)
    img = _compare(renderer, base, deformed, cam, setup)
    assert (img[..., :3] < 250).any()
    # and the plain vertex path
    saved = renderer.prepass
    renderer.prepass = False
    try:
        _compare(renderer, base, deformed, cam, setup)
    finally:
        renderer.prepass = saved


def test_basis_replacement_clears_old_rows(renderer):
    base = sphere(6000, overlap=1.2)
    rng = np.random.default_rng(3)
    first = np.arange(0, 3000)
    second = np.arange(2000, 6000)
    B1 = gaussian_basis(base.positions[first], seed=1)
    B2 = gaussian_basis(base.positions[second], seed=2)
    dC = rng.normal(scale=0.3, size=(4, 3))
    deformed = cpu_deform(base, second, *B2, dC)
    cam = Camera.frame(*base.bounds(), 1.0, direction=(1, 0.3, 0.2))

    def setup():
        renderer.set_basis(first, *B1)
        renderer.set_basis(second, *B2)    # rows 0..1999 must become undeformed again
        renderer.set_displacement(dC)
    _compare(renderer, base, deformed, cam, setup)


def test_zero_displacement_is_identity(renderer):
    base = sphere(3000)
    cam = Camera.frame(*base.bounds(), 1.0)
    renderer.set_cloud(base)
    plain = renderer.render(cam, 96, 96)
    idx = np.arange(base.n)
    renderer.set_basis(idx, *gaussian_basis(base.positions))
    renderer.set_displacement(np.zeros((4, 3)))
    # (the pre-pass fills records in a non-deterministic order: additive
    # blending may round differently by one unit)
    assert np.abs(renderer.render(cam, 96, 96).astype(int) - plain).max() <= 2
    renderer.clear_basis()
    assert np.abs(renderer.render(cam, 96, 96).astype(int) - plain).max() <= 2


def test_basis_errors(renderer):
    base = sphere(500)
    renderer.set_cloud(base)
    idx = np.arange(10)
    good = np.zeros((10, 4))
    with pytest.raises(ParameterError, match="1..16 columns .*RENDER_MAX_BASIS_COLUMNS.*got 17"):
        z = np.zeros((10, 17))
        renderer.set_basis(idx, z, z, z, z)
    with pytest.raises(ParameterError, match="got 0"):
        z = np.zeros((10, 0))
        renderer.set_basis(idx, z, z, z, z)
    with pytest.raises(ParameterError, match="same number of columns"):
        renderer.set_basis(idx, np.zeros((10, 5)), good, good, good)
    with pytest.raises(ParameterError, match="shape"):
        renderer.set_basis(idx, np.zeros((9, 4)), good, good, good)
    with pytest.raises(ParameterError, match="indices"):
        renderer.set_basis(idx + 495, good, good, good, good)
    with pytest.raises(ParameterError, match="dC"):
        renderer.set_displacement(np.zeros((3, 3)))
    z5 = np.zeros((10, 5))
    renderer.set_basis(idx, z5, z5, z5, z5)          # K = 5 (padded to 8 on the GPU)
    with pytest.raises(ParameterError, match=r"shape \(5, 3\)"):
        renderer.set_displacement(np.zeros((8, 3)))
    with pytest.raises(ParameterError, match="finite"):
        renderer.set_displacement(np.full((5, 3), np.nan))
    renderer.set_displacement(np.zeros((5, 3)))


@pytest.mark.parametrize("prepass", [True, False])
@pytest.mark.parametrize("kind, degrees", [("bend", 120.0), ("twist", 180.0)])
def test_rotation_mode_gpu_matches_cpu(renderer, prepass, kind, degrees):
    """Rotation-aware handles (rotation.glsl) on the GPU against
    DeformationBasis.apply, on the bench bar with a real fitted basis."""
    from splatedit.bench.bars import bar_basis, bar_transform, open_cylinder
    from splatedit.deform.modes import DeformationMode
    base = open_cylinder()
    basis = bar_basis(base)
    d = basis.displacement([bar_transform(base, kind, degrees)], mode=DeformationMode.ROTATION)
    assert d.rotating
    _compare_rotation(renderer, prepass, base, basis, d)


def _compare_rotation(renderer, prepass: bool, base, basis, d) -> None:
    """The GPU's rotation-aware deformation of ``base`` by ``d`` (with the
    pre-pass or the vertex path) against the CPU's DeformationBasis.apply."""
    deformed = basis.apply(base, d)
    cam = Camera.frame(*deformed.bounds(), 1.0, direction=(0.4, -0.8, 1.0))

    def setup():
        renderer.set_basis(*basis.rows_for_gpu())
        renderer.set_displacement(d)
    saved = renderer.prepass
    renderer.prepass = prepass
    try:
        img = _compare(renderer, base, deformed, cam, setup)
    finally:
        renderer.prepass = saved
    assert (img[..., :3] < 250).any()


@pytest.mark.parametrize("prepass", [True, False])
def test_rotation_mode_far_pivot_gpu_matches_cpu(renderer, prepass):
    """A handle turned about a far pivot takes its centroid as the arc centre
    (deform/rotation_centre.py); the GPU draws the same deformation (the
    centre only enters the per-frame uniforms)."""
    from splatedit.bench.bars import bar_basis, open_cylinder
    from splatedit.deform.modes import DeformationMode
    from splatedit.deform.transform import rotate
    base = open_cylinder()
    basis = bar_basis(base)
    d = basis.displacement([rotate((1.0, 0.0, 0.0), 150.0, (0.0, 8.0, 7.5))], mode=DeformationMode.ROTATION)
    assert np.array_equal(d.rotations[0].center, basis.constraints.groups[0].controls[0])
    _compare_rotation(renderer, prepass, base, basis, d)
