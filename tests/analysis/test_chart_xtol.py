"""``impact-harness chart --xtol``: the scans' edges bisected to an absolute tolerance, against
Newton on the exact flow (:func:`harness.reproduce.fig9_maps.ode_windows` on mapcheck.exact).
Apart from tests/analysis/test_chart.py (Figure 9's chart in a module fixture) so that two workers
can share the two charts.
"""
from __future__ import annotations

import json

import pytest

from harness.cli.main import main

pytestmark = pytest.mark.slow  # a chart and the exact flow's windows bisected to 1e-8


def test_xtol_is_an_absolute_tolerance_that_meets_the_exact_flows_edges(tmp_path) -> None:
    """``--xtol`` replaces the relative tolerance (1e-3 x sigma with --quick, ~3e-4 at the
    period-2 flip): the period-2 window's edges at Gamma = 10 then agree with Newton on the exact
    flow (fig9_maps.ode_windows, Newton on mapcheck.exact) to the tolerance asked for, and the
    Run line carries the option."""
    import re
    import shlex

    from harness.cli.main import build_parser
    from harness.reproduce.fig9_maps import ode_windows

    xtol = 1e-7
    argv = ["chart", "--config", "harness/experiments/fig9.toml", "--param2", "Gamma", "--range", "10:20", "--num", "2",
            "--M-max", "2", "--quick", "--sigma-range", "0.2:1.2", "--per-decade", "24", "--workers", "1",
            "--solver", "closed-form", "--xtol", repr(xtol), "--out", str(tmp_path)]
    assert main(argv) == 0
    res = json.loads((tmp_path / "chart.json").read_text())
    lo, hi = ode_windows(Gamma=10.0, M_max=2, xtol=1e-8)[2]  # the reference to 1e-8, 20 x inside the tolerance asked
    cv = res["scans"]["2"]
    assert cv["value"][0] == pytest.approx(10.0)
    # the bisection's bracket is xtol wide; Newton's residual adds far less
    assert abs(cv["lower"][0] - lo) < 2 * xtol and abs(cv["upper"][0] - hi) < 2 * xtol
    assert res["parameters"]["xtol"] == xtol
    report = (tmp_path / "report.md").read_text()
    assert f"bisected to {xtol:g} in sigma" in report
    line = re.search(r"Run: `impact-harness (.+?)`", report).group(1)
    assert build_parser().parse_args(shlex.split(line)).xtol == xtol
    with pytest.raises(SystemExit) as exc:  # argparse: a one-line error, exit status 2
        main([*argv[:-4], "--xtol", "0", "--out", str(tmp_path)])
    assert exc.value.code == 2
