"""Two rules of ``chart``'s second routes, each checked on its own against an independent truth.

* The wall-free window's graze (:func:`harness.analysis.chart.wall_free.wall_free_window`): below
  grazing the wall-free orbit (4) misses the wall by exactly -sigma (docs/theory.md section 10), so
  the error it reports with its graze -- how far the two orbits' gaps lie from that line -- must be
  of the size of Newton's residual, and the located graze within it of sigma = 0.
* An edge contradiction (:func:`harness.analysis.chart.contradictions._edges`): where the two routes
  put a window's lower edge apart, shooting at the midpoint decides; a stable orbit there says the
  route with the wider window (the lower edge further down) is right, none says the narrower one.
  The truth at the midpoint is the exact closed-form flow's (mapcheck, :class:`ExactFlow`), not the
  FMU's.

Figure 9's oscillator (nu = 4.605, Omega = 0.3059, r = 0.9, compliant wall, Gamma = 10): its
period-2 window is [0.28997, 0.81901] (flip to graze).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from harness import FmuSimulator
from harness.analysis.chart.contradictions import _edges
from harness.analysis.chart.run import ChartProblem
from harness.analysis.chart.wall_free import wall_free_window
from tests.support.edges import ExactFlow

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112, r=0.9)


def _params(gamma: float) -> dict:
    return {**FIG9, "wall": 1, "Gamma": gamma, "solver": 1}


def test_the_wall_free_graze_error_is_the_gaps_distance_from_minus_sigma(model) -> None:
    """Each value's reported error is the gaps' distance from gap = -sigma (Newton's 1e-11 residual, not
    the sum of |gap| and |sigma|), and the graze lies within it of sigma = 0."""
    grid = np.linspace(-0.2, 0.4, 13)
    wf = wall_free_window(model.source(), _params(10.0), "Gamma", [10.0, 100.0], grid)
    c = wf["curves"]["upper"]
    assert c["p2"] == pytest.approx([10.0, 100.0])
    for s, err in zip(c["sigma"], c["error"]):
        assert 0.0 <= err < 1e-9
        assert abs(s) <= 1e-9
    assert wf["upper"]["bracket"] == c["error"][0]


GAMMA, UPPER, FLIP = 10.0, 0.8190053, 0.2899707  # period 2 at Gamma = 10 (docs/theory.md section 11)


@pytest.fixture(scope="module")
def exact_period2() -> dict:
    """The exact flow's period-2 orbit settled at sigma = 0.5 (its point), and whether the flow settles
    on a stable period-2 orbit with one impact at 0.295 and 0.28 (either side of the flip)."""
    flow = ExactFlow(FIG9["nu"], FIG9["Omega"], FIG9["r"], GAMMA, "compliant")
    seed = flow.settle(0.5, 2, 200)
    assert seed.converged and int(np.sum(seed.contacts)) == 1
    out = {"seed": seed.z[0]}
    for s in (0.295, 0.28):
        o = flow.settle(s, 2, 400)
        out[s] = bool(o.converged and int(np.sum(o.contacts)) == 1 and np.max(np.abs(o.multipliers)) < 1.0)
    return out


@pytest.mark.slow
@pytest.mark.parametrize("continued_lo, scanned_lo", [(0.30, 0.29), (0.29, 0.27)])
def test_a_lower_edge_contradiction_is_settled_for_the_route_the_exact_flow_confirms(
        model, exact_period2: dict, continued_lo: float, scanned_lo: float) -> None:
    """The two routes' lower edges of period 2 put on either side of the exact flip (0.28997): the
    midpoint is inside the window (0.295: the scans' wider window right) or below it (0.28: the
    continuation's narrower one right); the route declared right is the wider one exactly where the
    exact flow has a stable period-2 orbit at the midpoint."""
    mid = 0.5 * (continued_lo + scanned_lo)
    exact_stable = exact_period2[mid]
    assert exact_stable == (mid > FLIP)
    problem = ChartProblem(_params(GAMMA), "Gamma", np.array([GAMMA]), True, 2, np.geomspace(0.05, 2.0, 20))
    sim = FmuSimulator(model.source(), instance_name="chart-rules")
    c = {"lo": continued_lo, "hi": UPPER, "window": {"curves": {}}}
    e = {"lo": scanned_lo, "hi": UPPER, "xtol": 1e-7, "kinds": ["flip", "graze"]}
    z = exact_period2["seed"]
    seeds = [{"M": 2, "impacts": 1, "track": [[0.5, float(z[0]), float(z[1])]]}]
    (found,) = _edges(sim, problem, GAMMA, "2", c, e, seeds)
    assert found["side"] == "lower" and found["evidence"]["found"] == exact_stable
    wider = "scans" if scanned_lo < continued_lo else "continuation"
    narrower = "continuation" if wider == "scans" else "scans"
    assert found["right"] == (wider if exact_stable else narrower)
    if exact_stable:
        assert math.isclose(found["evidence"]["sigma"], mid)
