"""The install is reproducible: constraints.txt pins every package the
project and its tests need, and the venv that scripts/install.sh made holds
exactly those versions (what the suite was run with)."""

from __future__ import annotations

import re
import sys
import tomllib
from importlib import metadata
from pathlib import Path

import pytest

from tests.conftest import REPO_ROOT

PIN = re.compile(r"^([A-Za-z0-9_.\-]+)==([^\s;#]+)\s*$")


def _canonical(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _pins() -> dict[str, str]:
    pins = {}
    for line in (REPO_ROOT / "constraints.txt").read_text().splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        m = PIN.match(line)
        assert m, f"constraints.txt: not an exact pin: {line!r}"
        pins[_canonical(m.group(1))] = m.group(2)
    return pins


def _requirement_names(reqs: list[str]) -> set[str]:
    return {_canonical(re.split(r"[\s\[<>=!~;]", r, maxsplit=1)[0]) for r in reqs}


def test_constraints_pin_every_runtime_and_test_dependency():
    project = tomllib.loads((REPO_ROOT / "pyproject.toml").read_text())["project"]
    needed = _requirement_names(project["dependencies"] + project["optional-dependencies"]["test"]
                               + project["optional-dependencies"]["docs"])
    missing = needed - set(_pins())
    assert not missing, f"constraints.txt does not pin {sorted(missing)}"


def test_install_script_installs_through_the_constraints():
    script = (REPO_ROOT / "scripts" / "install.sh").read_text()
    assert 'PIP_CONSTRAINT="$PWD/constraints.txt"' in script


def test_installed_versions_equal_the_pins():
    if Path(sys.prefix).resolve() != (REPO_ROOT / ".venv").resolve():
        pytest.skip(f"not running in this checkout's install.sh venv ({sys.prefix})")
    wrong = {}
    for name, version in _pins().items():
        if name == "setuptools":    # the build backend's pin: used in pip's isolated build environment,
            continue                # whatever setuptools the venv module put into the venv itself
        try:
            have = metadata.version(name)
        except metadata.PackageNotFoundError:
            wrong[name] = (version, None)
            continue
        if have != version:
            wrong[name] = (version, have)
    assert not wrong, f"installed versions differ from constraints.txt (pinned, installed): {wrong}"
