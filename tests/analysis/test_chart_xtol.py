"""``impact-harness chart --xtol``: the scans' edges bisected to an absolute tolerance, against
the exact flow (mapcheck.exact) on both sides of each edge.
Apart from tests/analysis/test_chart.py (Figure 9's chart in a module fixture) so that two workers
can share the two charts.
"""
from __future__ import annotations

import json

import pytest

from harness.cli.main import main
from harness.reproduce.fig9_maps import ALPHA, GAMMA, R
from mapcheck.linear import invert_alpha_gamma
from tests.support.edges import ExactFlow, dominant, edge_sides, good

pytestmark = pytest.mark.slow  # a chart and the exact flow's windows bisected to 1e-8


def test_xtol_is_an_absolute_tolerance_that_meets_the_exact_flows_edges(tmp_path) -> None:
    """``--xtol`` replaces the relative tolerance (1e-3 x sigma with --quick, ~3e-4 at the
    period-2 flip): the period-2 window's edges at Gamma = 10 then hold on the exact flow to the
    tolerance asked for (2 xtol inside each edge the exact flow's orbit, continued from one settled
    mid-window, is stable with one impact; 2 xtol beyond it is gone the way the edge's kind says),
    and the Run line carries the option."""
    import re
    import shlex

    from harness.cli.main import build_parser

    xtol = 1e-7
    argv = ["chart", "--config", "harness/experiments/fig9.toml", "--param2", "Gamma", "--range", "10:20", "--num", "2",
            "--M-max", "2", "--quick", "--sigma-range", "0.2:1.2", "--per-decade", "24", "--workers", "1",
            "--solver", "closed-form", "--xtol", repr(xtol), "--out", str(tmp_path)]
    assert main(argv) == 0
    res = json.loads((tmp_path / "chart.json").read_text())
    cv = res["scans"]["2"]
    assert cv["value"][0] == pytest.approx(10.0)
    # the bisection's bracket is xtol wide; Newton's residual adds far less
    for side, inward in (("lower", 1.0), ("upper", -1.0)):
        why = _exact_flow_disagrees(cv[side][0], cv[f"kind_{side}"][0], inward, cv["lower"][0], cv["upper"][0], xtol)
        assert not why, why
    assert res["parameters"]["xtol"] == xtol
    report = (tmp_path / "report.md").read_text()
    assert f"bisected to {xtol:g} in sigma" in report
    line = re.search(r"Run: `impact-harness (.+?)`", report).group(1)
    assert build_parser().parse_args(shlex.split(line)).xtol == xtol
    with pytest.raises(SystemExit) as exc:  # argparse: a one-line error, exit status 2
        main([*argv[:-4], "--xtol", "0", "--out", str(tmp_path)])
    assert exc.value.code == 2


def _exact_flow_disagrees(edge: float, kind: str, inward: float, lo: float, hi: float, xtol: float) -> str:
    """'' when the exact flow of Figure 9 at Gamma = 10 has its period-2 window edge of ``kind``
    within 2 ``xtol`` of ``edge`` (``inward``: the window's side), else what it found."""
    inv = invert_alpha_gamma(ALPHA, GAMMA)
    flow, s_mid = ExactFlow(inv.nu, inv.Omega, R, 10.0, "compliant"), 0.5 * (lo + hi)
    seed = flow.settle(s_mid, 2, 150)
    if not (good(seed) and seed.contacts.sum() == 1):
        return f"no stable period-2 orbit with one impact settles at sigma = {s_mid}"
    es = edge_sides(flow, 2, seed, s_mid, kind, edge + inward * xtol, edge - inward * xtol, xtol)
    if not (good(es.inside) and es.inside.contacts.sum() == 1):
        return f"{kind} at {edge}: no stable period-2 orbit at {es.s_in}"
    if kind == "flip":
        mu = dominant(flow.multipliers(es.s_out, es.outside.z[0], 2))
        return "" if es.outside.converged and mu.real < -1.0 else f"flip at {edge}: multiplier {mu} at {es.s_out}"
    if kind in ("graze", "fold"):
        return "" if not good(es.outside) else f"{kind} at {edge}: still stable at {es.s_out}"
    return f"edge kind {kind} not checked"
