"""Build the API reference from the package's docstrings with pdoc.

    .venv/bin/python scripts/build_api_docs.py [OUT]     (default build/api; open OUT/index.html)

pdoc walks a package's submodules but, where a package's ``__init__`` sets
``__all__``, only the ones it lists; every module of splatedit is public API
for a contributor, so the modules that walk misses are named as well (a
package only once: pdoc walks its children). tests/test_api_docs.py calls
:func:`build` on every test run, so the reference is built in CI and a module
that cannot be documented (an import that fails, an annotation pdoc cannot
resolve) fails the suite.
"""

from __future__ import annotations

import pkgutil
import sys
import warnings
from pathlib import Path

import pdoc
import pdoc.extract
import pdoc.render

REPO_ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO_ROOT))     # this checkout's package, also when run as a script

import splatedit  # noqa: E402

#: docstrings use Google sections (Args:, Returns:, Attributes:) and reST roles
DOCFORMAT = "google"


def module_specs() -> list[str]:
    """The module names to hand to pdoc: the package, then every module its
    walk would miss (a missed package stands for its children)."""
    everything = ["splatedit"] + [m.name for m in pkgutil.walk_packages(splatedit.__path__, "splatedit.")]
    walked = set(pdoc.extract.walk_specs(["splatedit"]))
    missed = [m for m in everything if m not in walked]
    return ["splatedit"] + [m for m in missed if m.rpartition(".")[0] not in missed]


def build(out: Path) -> list[str]:
    """Write the HTML reference into ``out``; returns pdoc's warnings (empty
    when every module, signature and annotation was documented)."""
    pdoc.render.configure(docformat=DOCFORMAT, show_source=False)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        pdoc.pdoc(*module_specs(), output_directory=Path(out))
    assert Path(splatedit.__file__).resolve().is_relative_to(REPO_ROOT), splatedit.__file__
    return [str(w.message) for w in caught]


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    out = Path(args[0] if args else "build/api")
    problems = build(out)
    for p in problems:
        print(f"build_api_docs: warning: {p}", file=sys.stderr)
    print(f"build_api_docs: wrote {out / 'index.html'}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
