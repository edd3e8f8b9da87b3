"""The README and the manual in docs/ must match what the program does."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text()
EDITOR_MANUAL = (ROOT / "docs" / "editor.md").read_text()
COMMANDS_MANUAL = (ROOT / "docs" / "commands.md").read_text()
#: the README is an entry point, the manual lives in docs/
README_MAX_LINES = 200
CI_RUN = (Path(__file__).resolve().parent.parent / ".ci" / "run").read_text()


def test_editor_manual_lists_every_editor_control_shown_in_the_window():
    from splatedit.app.editor import CONTROLS
    missing = [line.strip() for line in CONTROLS.splitlines()
               if line.strip() and line.strip() not in EDITOR_MANUAL]
    assert not missing, f"docs/editor.md lacks these lines of the in-window help: {missing}"


def test_readme_is_an_entry_point_that_links_every_manual_page():
    assert len(README.splitlines()) <= README_MAX_LINES
    for page in sorted((ROOT / "docs").glob("*.md")) + sorted((ROOT / "docs" / "dev").glob("*.md")):
        assert f"(docs/{page.relative_to(ROOT / 'docs')})" in README, page.name


def test_relative_links_in_readme_and_docs_point_at_files():
    for md in [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]:
        for target in re.findall(r"\]\(([^)#:\s]+)(?:#[^)]*)?\)", md.read_text()):
            assert (md.parent / target).exists(), f"{md.relative_to(ROOT)}: broken link {target}"


def test_readme_has_exactly_two_setup_commands_and_ci_runs_the_test_one():
    blocks = re.findall(r"```sh\n(.*?)```", README.split("## Commands")[0], flags=re.S)
    commands = [b.strip() for b in blocks]
    assert len(commands) == 2, commands
    assert all(c.startswith("bash scripts/install.sh && ") for c in commands)
    assert commands[1] in CI_RUN


def test_readme_and_the_commands_manual_document_every_cli_command():
    from splatedit.cli import build_parser
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    for name in sub.choices:
        assert f"splatedit {name}" in README, name
        assert f"splatedit {name}" in COMMANDS_MANUAL, name
