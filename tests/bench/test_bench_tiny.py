"""Every ``splatedit bench`` case runs, in its tiny form (issue 19 item 8:
``bench editor --quick`` died with ``TypeError: 'FrameInfo' object is not
subscriptable`` and no test had run it).  Each case goes through the same
code as ``splatedit bench NAME`` on the smallest inputs it takes
(:data:`splatedit.bench.runner.TINY`) and must give JSON lines."""

from __future__ import annotations

import json

import pytest

from splatedit.bench.runner import BENCHES, TINY, run_bench

#: the cases that draw with the Vulkan renderer
GPU = {"render", "editor", "detail", "gui", "gaussian-render", "gaussian-editor", "outofcore"}


def test_every_bench_case_has_a_tiny_form():
    assert set(TINY) == set(BENCHES)


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.gpu) if n in GPU else n for n in BENCHES])
def test_bench_case_runs_in_its_tiny_form_and_gives_json_lines(name):
    lines = list(run_bench(name, tiny=True))
    assert lines, f"bench {name} gave no line"
    for line in lines:
        assert isinstance(line, dict) and line
        json.dumps(line)            # what `splatedit bench` prints
