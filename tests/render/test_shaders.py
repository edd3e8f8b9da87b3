"""The committed SPIR-V (spirv/ and the package copy splatedit/spirv/) is what
data_tools/compile_shaders.py produces from shaders_glsl/ right now."""

from __future__ import annotations

import importlib.util
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _compile_module():
    spec = importlib.util.spec_from_file_location("compile_shaders", ROOT / "data_tools" / "compile_shaders.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.skipif(shutil.which("glslangValidator") is None, reason="glslangValidator not installed")
def test_committed_spirv_is_fresh(tmp_path):
    mod = _compile_module()
    sources = mod.shader_sources()
    assert "shaders_glsl/splat.vert" in sources and len(sources) >= 6
    bad = mod.stale(tmp_path)
    assert not bad, "stale SPIR-V, run python data_tools/compile_shaders.py: " + ", ".join(bad)


def test_package_finds_spirv():
    from splatedit.render.vk import spirv_path
    p = spirv_path("splat.vert")
    assert p.parent == ROOT / "splatedit" / "spirv"
