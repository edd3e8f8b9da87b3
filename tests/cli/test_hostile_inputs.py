"""Issue 12, hostile inputs against the command line: every one ends in exit 0
with a readable result or exit 2 with exactly one ``splatedit: error:`` line
naming the file / flag and the place, never a traceback."""

from __future__ import annotations

import pytest

from splatedit.cli import main


def one_error_line(capsys) -> str:
    """The single stderr line of a failed in-process run (asserts there is one)."""
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith("splatedit: error: "), err
    assert "Traceback" not in err
    return lines[0]


# ---------------------------------------------------------- class 9: argparse
ARGUMENT_ERRORS = [
    # (id, argv, expected substrings of the one error line)
    ("missing -o", ["render", "x.ply"], ["render:", "-o/--output"]),
    ("bad size", ["render", "x.ply", "-o", "x.png", "--size", "0x1"], ["render:", "--size", "0x1"]),
    ("unknown command", ["nope"], ["invalid choice", "'nope'"]),
    ("missing info file", ["info"], ["info:", "file"]),
    ("unknown flag", ["info", "a.ply", "--bogus"], ["unrecognized arguments", "--bogus"]),
    ("negative tol", ["deform", "a.ply", "--edit", "e.json", "-o", "o.ply", "--tol", "-1"],
     ["deform:", "--tol", "'-1'"]),
    ("bad eye", ["render", "a.ply", "-o", "a.png", "--eye", "1,2"], ["render:", "--eye"]),
]


@pytest.mark.parametrize("argv,expected", [c[1:] for c in ARGUMENT_ERRORS],
                         ids=[c[0] for c in ARGUMENT_ERRORS])
def test_argument_errors_print_one_line_without_usage_block(capsys, argv, expected):
    with pytest.raises(SystemExit) as info:
        main(["-q", *argv])
    assert info.value.code == 2
    line = one_error_line(capsys)
    assert "usage:" not in line
    for sub in expected:
        assert sub in line, f"{sub!r} not in {line!r}"
