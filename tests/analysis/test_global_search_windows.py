"""``windows`` lists every attractor that random starts find, on lightly damped oscillators with
long-period attractors just below grazing that the scans alone do not reach; their edges hold on
the exact flow; a window inside two ranges is the same window in both.

The oscillators were found by brute force (random starts at sigma slightly below 0):

- ``period-10``: nu = 0.1, Omega = 2.25, r = 0.8, compliant wall Gamma = 100: a period-8 orbit
  with 4 impacts takes most starts; a period-10 orbit with 5 impacts, between a fold at -0.0017076
  and a flip at 0.0013758, a few per cent of them.  The scans see only the first.
- ``period-7``: nu = 0.3, Omega = 1.125, r = 0.8, Gamma = 100: a period-7 orbit with 3 impacts
  takes most starts just below grazing, beside a period-3 orbit with 1.

The runs use the library with an 11-point grid (the command line's --quick grid has 121) to keep
the tier's time; the census uses 10,000 starts per sigma on the batch kernel, other starts than
the windows' own (another seed, a wider region), each attractor confirmed on the exact flow.
"""
from __future__ import annotations

import numpy as np
import pytest

from harness.analysis.context import Context
from harness.analysis.windows.compare_windows import run_windows
from harness.analysis.windows.problem import WindowProblem, default_settings
from harness.config import SamplingSpec
from harness.runs.basins.global_search import Region, global_search
from harness.runs.experiment import Experiment
from tests.support.edges import ExactFlow
from tests.support.orbit_edges import confirm_edge

pytestmark = pytest.mark.slow

CASES = {
    "period-10": (dict(nu=0.1, Omega=2.25, r=0.8, Gamma=100.0), (-0.01, 0.004), [-0.008, -0.001]),
    "period-7": (dict(nu=0.3, Omega=1.125, r=0.8, Gamma=100.0), (-0.004, 0.001), [-0.0005]),
}
#: Edges are checked this far inside and beyond (relative to max(1, |sigma|)).
MARGIN = 1e-8


def _windows(tmp_path_factory, osc: dict, rng: tuple[float, float], n: int) -> tuple[dict, str]:
    prob = WindowProblem(osc["nu"], osc["Omega"], r=osc["r"], wall="compliant", Gamma=osc["Gamma"], M_max=None)
    st = default_settings(prob, True, rng)
    st.scan_grid = np.linspace(rng[0], rng[1], n)
    ctx = Context("windows", tmp_path_factory.mktemp("w"), True, Experiment.for_python(None, "closed-form", 1, False))
    return run_windows(ctx, prob, st)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    return {name: _windows(tmp_path_factory, osc, rng, 11) for name, (osc, rng, _) in CASES.items()}


def _flow(osc: dict) -> ExactFlow:
    return ExactFlow(osc["nu"], osc["Omega"], osc["r"], osc["Gamma"], "compliant")


@pytest.mark.parametrize("case", list(CASES))
def test_windows_lists_every_attractor_that_random_starts_find(runs, case) -> None:
    osc, _, census = CASES[case]
    res, report = runs[case]
    flow = _flow(osc)
    s = SamplingSpec(theta=0.5, n_transient=500, n_samples=40, tol=1e-7)
    for sigma in census:
        params = dict(osc, wall=1, sigma=sigma, solver=1)
        found = global_search(params, s, Region.around_orbits(sigma, 0.5, False, widen=2.0), 10000, seed=20261207)
        assert found.attractors
        for a in found.attractors:
            orb = flow.orbit(sigma, a.period, a.points[-1])  # the exact flow has it, stable
            assert orb.converged and int(np.sum(orb.contacts)) == a.impacts, (sigma, a.key)
            assert np.max(np.abs(flow.multipliers(sigma, orb.z[0], a.period))) < 1.0
            rows = [e for e in res["ode_windows_all"] if e["resolved"] and (e["M"], e["impacts"]) == (a.period, a.impacts)
                    and (e["lo"] is None or e["lo"] <= sigma) and (e["hi"] is None or sigma <= e["hi"])]
            assert rows, f"{case}: the attractor {a.key} ({a.share:.2%} of 10,000 starts at sigma = {sigma}) is not listed"
    if res["found_only_by_global_search"]:  # said at the top of the report, before how it was found
        assert report.index("**The global search found") < report.index("## How the ODE's windows were found")


@pytest.mark.parametrize("case", list(CASES))
def test_the_edges_of_every_window_hold_on_the_exact_flow(runs, case) -> None:
    """Every fold, flip and graze of a window (from its seed orbit) is confirmed on the exact flow
    MARGIN inside and beyond; every window has its basin share and routes."""
    osc = CASES[case][0]
    res, _ = runs[case]
    flow = _flow(osc)
    checked = 0
    for e in res["ode_windows_all"]:
        if not e["resolved"] or e["impacts"] == 0:
            continue
        searched_inside = any((e["lo"] is None or e["lo"] <= s) and (e["hi"] is None or s <= e["hi"])
                              for s in np.linspace(*CASES[case][1], 11))
        assert e["found_by"] and (e["basin_share"] is not None or not searched_inside), e  # measured where searched
        for edge, kind in zip((e["lo"], e["hi"]), e["kinds"]):
            if edge is None or kind not in ("fold", "flip", "graze"):
                continue
            why = confirm_edge(flow, e["M"], e["impacts"], e["seed_sigma"], e["seed_state"], edge, kind,
                               MARGIN * max(1.0, abs(edge)))
            assert not why, f"{case}: {kind} at {edge}: {why}"
            checked += 1
    assert checked >= 1


def test_a_window_inside_two_ranges_is_the_same_window_in_both(runs, tmp_path_factory) -> None:
    """The period-10 case over another range (shifted, another grid): every window fully inside
    both ranges has the same edges (1e-9) and kinds; the wall-free orbit is listed in both."""
    osc, rng, _ = CASES["period-10"]
    a, _ = runs["period-10"]
    other = (-0.004, 0.004)
    b, _ = _windows(tmp_path_factory, osc, other, 9)
    lo, hi = max(rng[0], other[0]), min(rng[1], other[1])

    def inside(res):
        return sorted(((e["M"], e["impacts"]), e["lo"], e["hi"], tuple(e["kinds"])) for e in res["ode_windows_all"]
                      if e["resolved"] and e["lo"] is not None and e["hi"] is not None and lo < e["lo"] and e["hi"] < hi)

    wa, wb = inside(a), inside(b)
    assert wa and [w[0] for w in wa] == [w[0] for w in wb]
    for x, y in zip(wa, wb):
        assert x[1] == pytest.approx(y[1], abs=1e-9) and x[2] == pytest.approx(y[2], abs=1e-9) and x[3] == y[3]
    for res in (a, b):
        assert any(e["M"] == 1 and e["impacts"] == 0 and e["resolved"] for e in res["ode_windows_all"])
