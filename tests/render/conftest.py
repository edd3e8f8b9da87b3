"""Fixtures of the render tests: one shared renderer (lavapipe, validation on
via tests/conftest.py) and reference-image comparison."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

REFERENCES = Path(__file__).resolve().parent / "references"
ARTIFACTS = Path(__file__).resolve().parents[1] / "_artifacts"

#: reference-image tolerance: mean |difference| over RGB (0..255 units) and the
#: share of pixels whose largest channel difference exceeds REF_PIXEL_TOL
REF_MEAN_TOL = 1.0
REF_PIXEL_TOL = 24
REF_BAD_SHARE = 0.005


@pytest.fixture(scope="session")
def renderer():
    from splatedit.render.splat.renderer import Renderer
    r = Renderer()
    yield r
    r.close()


@pytest.fixture
def compare_reference():
    """compare_reference(name, rgba) - compare with tests/render/references/NAME.png
    (regenerate with SPLATEDIT_UPDATE_REFERENCES=1; diffs go to tests/_artifacts/)."""

    def check(name: str, img: np.ndarray):
        ref_path = REFERENCES / f"{name}.png"
        if os.environ.get("SPLATEDIT_UPDATE_REFERENCES") == "1":
            REFERENCES.mkdir(exist_ok=True)
            Image.fromarray(img, "RGBA").save(ref_path)
            return
        if not ref_path.is_file():
            pytest.fail(f"missing reference {ref_path}; run with SPLATEDIT_UPDATE_REFERENCES=1")
        ref = np.asarray(Image.open(ref_path).convert("RGBA"))
        assert ref.shape == img.shape, f"size {img.shape} != reference {ref.shape}"
        diff = np.abs(img.astype(np.int16) - ref.astype(np.int16))[..., :3]
        mean = float(diff.mean())
        bad = float((diff.max(axis=2) > REF_PIXEL_TOL).mean())
        if mean > REF_MEAN_TOL or bad > REF_BAD_SHARE:
            ARTIFACTS.mkdir(parents=True, exist_ok=True)
            Image.fromarray(img, "RGBA").save(ARTIFACTS / f"{name}.actual.png")
            Image.fromarray(ref, "RGBA").save(ARTIFACTS / f"{name}.expected.png")
            Image.fromarray(np.clip(diff * 4, 0, 255).astype(np.uint8), "RGB").save(ARTIFACTS / f"{name}.diff.png")
            pytest.fail(f"{name}: mean diff {mean:.3f} (tol {REF_MEAN_TOL}), {bad:.4%} pixels off by "
                        f">{REF_PIXEL_TOL} (tol {REF_BAD_SHARE:.2%}); see {ARTIFACTS}")

    return check
