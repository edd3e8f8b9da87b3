"""The README is the user's manual: it must match what the program does."""

from __future__ import annotations

import re
from pathlib import Path

README = (Path(__file__).resolve().parent.parent / "README.md").read_text()
CI_RUN = (Path(__file__).resolve().parent.parent / ".ci" / "run").read_text()


def test_readme_lists_every_editor_control_shown_in_the_window():
    from splatedit.app.editor import CONTROLS
    missing = [line.strip() for line in CONTROLS.splitlines() if line.strip() and line.strip() not in README]
    assert not missing, f"README lacks these lines of the in-window help: {missing}"


def test_readme_has_exactly_two_setup_commands_and_ci_runs_the_test_one():
    blocks = re.findall(r"```sh\n(.*?)```", README.split("## Commands")[0], flags=re.S)
    commands = [b.strip() for b in blocks]
    assert len(commands) == 2, commands
    assert all(c.startswith("bash scripts/install.sh && ") for c in commands)
    assert commands[1] in CI_RUN


def test_readme_documents_every_cli_command():
    from splatedit.cli import build_parser
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    for name in sub.choices:
        assert f"splatedit {name}" in README, name


def test_readme_python_example_runs(tmp_path, monkeypatch):
    block = re.search(r"```python\n(.*?)```", README, flags=re.S).group(1)
    monkeypatch.chdir(tmp_path)
    exec(compile(block, "README.md", "exec"), {})
    assert (tmp_path / "bunny-ear.ply").is_file()
