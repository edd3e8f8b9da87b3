"""The selection-tools benchmark in a tiny form: it runs, and its figures
are consistent (the lasso takes about the share of the sphere it covers; the
mirror of half a sphere finds about the other half, at least the push's)."""

from splatedit.bench.selection_tools import main, run


def test_selection_tools_bench_runs_and_its_figures_agree(capsys):
    r = run(4000)
    assert 0.3 * r["n"] < r["lasso_inside"] < 0.8 * r["n"]
    assert r["push_found"] <= r["mirror_found"] <= r["n"] - r["selected"] + 50
    assert r["mirror_found"] > 0.7 * (r["n"] - r["selected"])
    assert main(["--n", "3000"]) == 0 and '"n": 3000' in capsys.readouterr().out
