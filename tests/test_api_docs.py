"""The API reference is generated from the docstrings (pdoc, scripts/build_api_docs.py)
and built on every test run: every module gets a page, nothing fails to document, and
public names carry docstrings (a ratchet that may only fall)."""

from __future__ import annotations

import importlib.util
import pkgutil

import pytest

import splatedit
from tests.conftest import REPO_ROOT

pdoc = pytest.importorskip("pdoc", reason="pdoc is the docs extra (scripts/install.sh installs it)")
import pdoc.doc  # noqa: E402

#: public classes and functions without a docstring (bench case drivers and
#: editor internals, counted when the reference was first built); may only fall
KNOWN_UNDOCUMENTED = 40


def _builder():
    spec = importlib.util.spec_from_file_location("build_api_docs", REPO_ROOT / "scripts" / "build_api_docs.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _module_names() -> list[str]:
    return ["splatedit"] + [m.name for m in pkgutil.walk_packages(splatedit.__path__, "splatedit.")]


@pytest.mark.slow
def test_api_reference_builds_a_page_for_every_module_without_warnings(tmp_path):
    problems = _builder().build(tmp_path)
    assert not problems, "pdoc could not document everything:\n" + "\n".join(problems)
    missing = [m for m in _module_names() if not (tmp_path / (m.replace(".", "/") + ".html")).is_file()]
    assert not missing, f"modules without a page in the API reference: {missing}"
    assert (tmp_path / "index.html").is_file() and (tmp_path / "search.js").is_file()


def _undocumented() -> list[str]:
    out = []
    for name in _module_names():
        module = pdoc.doc.Module.from_name(name)
        for member in module.flattened_own_members:
            if member.name.startswith("_") or member.modulename != name:
                continue        # private, or documented where it is defined
            if isinstance(member, (pdoc.doc.Class, pdoc.doc.Function)) and not member.docstring.strip():
                out.append(f"{name}.{member.qualname}")
    return out


def test_every_module_has_a_docstring():
    import importlib
    bare = [m for m in _module_names() if not (importlib.import_module(m).__doc__ or "").strip()]
    assert not bare, f"modules without a docstring: {bare}"


def test_public_classes_and_functions_are_documented_ratchet():
    undocumented = _undocumented()
    assert len(undocumented) <= KNOWN_UNDOCUMENTED, (
        f"{len(undocumented)} public classes/functions without a docstring (known: {KNOWN_UNDOCUMENTED}); "
        f"document the new ones: {undocumented}")
    if len(undocumented) < KNOWN_UNDOCUMENTED:
        pytest.fail(f"documented some: lower KNOWN_UNDOCUMENTED to {len(undocumented)}")
