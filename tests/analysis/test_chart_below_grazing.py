"""``impact-harness chart`` below grazing: the edges of orbits that coexist with the wall-free one
(sigma < 0), continued over a second parameter in sigma itself.

Independent truth: mapcheck's closed-form flow and its own Newton shooting
(:class:`tests.support.edges.ExactFlow`), sharing nothing with the FMU. Apart from
tests/analysis/test_chart.py (whose module fixture is one chart of Figure 9) so that two workers
can share the charts.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from harness.cli.main import main
from tests.support.edges import ExactFlow

pytestmark = pytest.mark.slow  # two charts, each with its continuations and checks on the exact flow


def test_a_chart_below_grazing_continues_the_flip_of_the_coexisting_orbit_on_the_exact_flow(tmp_path) -> None:
    """A rigid wall with r close to 1 (docs/examples/windows-rigid): below grazing a period-2 orbit
    with one impact coexists with the wall-free orbit up to its flip (sigma = -0.2211 at r = 0.95).
    With --sigma-range reaching below 0 the chart finds it at the start of the range, continues its
    flip over r in sigma itself, and every point of that curve is a flip of the exact flow
    (mapcheck's own Newton: a multiplier -1, one impact per period), across the range of r."""
    assert main(["chart", "--nu", "0.8", "--Omega", "2.5", "--r", "0.95", "--wall", "rigid", "--param2", "r",
                 "--range", "0.85:0.95", "--num", "2", "--M-max", "2", "--quick", "--sigma-range=-0.3:0.3",
                 "--workers", "2", "--solver", "closed-form", "--out", str(tmp_path)]) == 0
    res = json.loads((tmp_path / "chart.json").read_text())
    (w2,) = [w for w in res["windows"] if w["M"] == 2]
    flip = w2["curves"]["upper"]
    assert flip["kind"] == "flip" and max(flip["p2"]) >= 0.95 and min(flip["p2"]) == pytest.approx(0.85)
    assert max(flip["sigma"]) < -0.1 and np.ptp(flip["sigma"]) > 0.05  # below grazing, and it moves with r
    for s, r, z in zip(flip["sigma"], flip["p2"], flip["points"]):
        orb = ExactFlow(0.8, 2.5, r, 10.0, "rigid").orbit(s, 2, z)
        assert orb.converged and int(np.sum(orb.contacts)) == 1, (r, s)
        assert np.min(np.abs(orb.multipliers + 1.0)) < 1e-6, (r, s, orb.multipliers)
    # the checks across the curve (the FMU's own Newton on both sides) and the per-value scans agree
    assert res["edge_check"]["2"]["checked"] == len(flip["sigma"]) == res["edge_check"]["2"]["confirmed"]
    sc = res["scans"]["2"]
    assert sc["value"] == pytest.approx([0.85, 0.95]) and all(k == "flip" for k in sc["kind_upper"])
    assert sc["upper"][-1] == pytest.approx(-0.22108, abs=1e-3)  # the exact flow's flip (docs/examples)
    assert (tmp_path / "chart.png").stat().st_size > 0


def test_a_fold_below_grazing_continued_over_gamma_is_the_exact_flows_fold(tmp_path) -> None:
    """An underdamped oscillator on a compliant wall (docs/examples/windows-underdamped): its
    period-3 orbit with one impact is born in a fold at sigma = -0.00706, before the wall-free orbit
    grazes.  The chart continues that fold over Gamma in sigma itself, and at every point the exact
    flow (mapcheck's own Newton) has the stable orbit 1e-6 above it, with a multiplier near +1 (a
    fold: 1 - |z| ~ sqrt(distance)), and no such orbit 1e-6 below; the check across the curve
    confirms every point (a fold has no orbit beyond it, stable or not)."""
    assert main(["chart", "--nu", "0.3", "--Omega", "1.2", "--r", "0.8", "--wall", "compliant", "--Gamma", "10",
                 "--param2", "Gamma", "--range", "10:40", "--log", "--num", "3", "--M-max", "3", "--quick",
                 "--sigma-range=-0.05:0.3", "--workers", "2", "--solver", "closed-form", "--out", str(tmp_path)]) == 0
    res = json.loads((tmp_path / "chart.json").read_text())
    (w3,) = [w for w in res["windows"] if w["M"] == 3]
    fold = w3["curves"]["lower"]
    assert fold["kind"] == "fold" and fold["p2"][0] == pytest.approx(10.0) and max(fold["p2"]) >= 40.0
    assert max(fold["sigma"]) < 0 and fold["sigma"][0] == pytest.approx(-0.00706, abs=2e-5)
    for s, G, z in zip(fold["sigma"], fold["p2"], fold["points"]):
        flow = ExactFlow(0.3, 1.2, 0.8, G, "compliant")
        inside, outside = flow.orbit(s + 1e-6, 3, z), flow.orbit(s - 1e-6, 3, z)
        assert inside.converged and inside.stable and int(np.sum(inside.contacts)) == 1, (G, s)
        assert 0.9 < np.max(np.abs(inside.multipliers)) < 1.0, (G, s, inside.multipliers)
        assert not (outside.converged and int(np.sum(outside.contacts)) == 1), (G, s)
    assert res["edge_check"]["3"]["confirmed"] == res["edge_check"]["3"]["checked"] == len(fold["sigma"])
