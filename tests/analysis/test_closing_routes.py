"""A window's closing held against every route of the run (harness/analysis/chart/closing_routes.py).

The case: nu = 4, Omega = 0.5, r = 0.9, compliant wall (docs/examples/chart-compliant): over Gamma its
period-2 window, bounded by its flip curve alone past Gamma = 382.8, closes at the curve's tip near
Gamma = 490 (sigma = 0.376), where the smallest |multiplier| along sigma reaches 1.

Truth: the exact closed-form flow (mapcheck, :class:`ExactFlow`): the smallest spectral radius of its
period-2 orbit over sigma, below 1 just below the bisected closing and above 1 just above it.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from harness.analysis.chart.closing_evidence import boundary_features
from harness.analysis.chart.closing_routes import closing_route_lines, reconcile_closings
from harness.analysis.chart.run import ChartProblem
from harness.dynamics.attractors.scans import find_attractors
from tests.support.edges import ExactFlow

CASE = {"nu": 4.0, "Omega": 0.5, "r": 0.9, "wall": 1, "solver": 1}


def test_corners_and_turning_points_of_edge_curves_are_boundary_features() -> None:
    """Two straight edge curves in (ln p2, ln sigma) crossing at p2 = 100, sigma = 1, and a curve turning
    back at p2 = 200: both features found where they are, the curves' common start is no corner."""
    p = np.geomspace(50.0, 150.0, 11)
    a = {"kind": "flip", "p2": list(p), "sigma": list(p / 100.0), "turns": [], "end": {"reason": "range"}}
    b = {"kind": "graze", "p2": list(p), "sigma": list(100.0 / p), "turns": [], "end": {"reason": "range"}}
    c = {"kind": "flip", "p2": [150.0, 200.0, 150.0], "sigma": [3.0, 4.0, 5.0],
         "turns": [{"side": "max", "p2": 200.0, "sigma": 4.0}], "end": {"reason": "range"}}
    feats = boundary_features({"curves": {"lower": a, "upper": b}, "handovers": [{"curves": {"lower": c}}]})
    corner = [f for f in feats if f["kind"].startswith("corner")]
    assert len(corner) == 1 and corner[0]["p2"] == pytest.approx(100.0) and corner[0]["sigma"] == pytest.approx(1.0)
    assert any(f["kind"] == "turning point of the lower flip edge" and f["p2"] == 200.0 for f in feats)


@pytest.fixture(scope="module")
def held(model, sim) -> dict:
    """A closing reported at Gamma = 470, below a stable period-2 orbit that another route of the run
    (a contradiction settled by shooting) found at Gamma = 485: held against it."""
    p = {**model.defaults(), **CASE, "Gamma": 485.0}
    (a,) = [x for x in find_attractors(sim, p, [0.376], M_max=2, transient=600).attractors if x.period == 2][:1]
    problem = ChartProblem(dict(CASE, Gamma=5.0), "Gamma", np.geomspace(5.0, 1e4, 30), True, 2,
                           np.geomspace(0.05, 20.0, 40))
    out = {"closes": {"2": {"closes": 470.0, "sigma": 0.37, "how": "a candidate", "kind": "flip curve turns",
                            "confirmation": {"below": {}}, "tested": [], "codim2": []}},
           "windows": [{"M": 2, "impacts": 1, "curves": {}, "handovers": []}],
           "contradictions": {"found": [{"window": "2", "p2": 485.0, "type": "presence", "right": "scans",
                                         "evidence": {"found": True, "sigma": 0.376,
                                                      "point": [float(x) for x in a.points[0]]}}]}}
    changed = reconcile_closings(model.source(), problem, out, [])
    return {"changed": changed, "closes": out["closes"]}


def test_a_closing_never_stands_below_a_stable_orbit_of_the_run(held) -> None:
    cl = held["closes"]["2"]
    r = cl["routes"]
    assert held["changed"] and cl["superseded"]["closes"] == 470.0
    assert r["status"] == "unresolved" and r["feature"] is None  # no edge curve given: nothing to coincide with
    assert cl["closes"] == r["p2"] > 485.0 and r["bracket"][1] / r["bracket"][0] - 1.0 < 2e-6
    lines = "\n".join(closing_route_lines(held["closes"], "Gamma"))
    assert "**unresolved**" in lines and f"{r['p2']:.7g}" in lines and "470" in lines


def _exact_min_radius(G: float, sigma: float, z) -> float:
    """The smallest spectral radius of the exact flow's period-2 orbit over sigma within 0.3 % of ``sigma``."""
    flow = ExactFlow(CASE["nu"], CASE["Omega"], CASE["r"], G, "compliant")
    last = {"z": np.asarray(z, float)}

    def rho(s: float) -> float:
        o = flow.orbit(float(s), 2, last["z"])
        assert o.converged and int(np.sum(o.contacts)) == 1
        last["z"] = o.z[0]
        return float(np.max(np.abs(o.multipliers)))  # central differences: ~1e-8, the margin is 3e-6

    rho(sigma)
    # rho is a parabola in sigma near its minimum: sigma to 1e-5 gives rho to ~1e-10
    return float(minimize_scalar(rho, bounds=(0.997 * sigma, 1.003 * sigma), method="bounded",
                                 options={"xatol": 1e-5}).fun)


@pytest.mark.slow
def test_the_one_parameter_route_brackets_the_exact_flows_closing(held) -> None:
    """The exact flow's smallest radius is below 1 at 1e-4 below the bisected closing and above 1 at 1e-4
    above it (its slope: ~3e-6 per 1e-4 in Gamma)."""
    r = held["closes"]["2"]["routes"]
    pb, s, z = r["p2"], r["sigma"], r["point"]
    assert _exact_min_radius(pb * (1.0 - 1e-4), s, z) < 1.0 < _exact_min_radius(pb * (1.0 + 1e-4), s, z)


def test_confirmation_shots_keep_to_the_window_not_to_every_curves_crossing() -> None:
    """A window about 0.1 wide around sigma 0.22 and a graze curve crossing the same p2 at sigma 175 (run off):
    the shots are spread between the window's own edges, at the window's density."""
    from harness.analysis.chart.window_region import bracketing
    from harness.dynamics.maps.sigma_search import sigma_grid

    edges = bracketing([0.17, 0.27, 175.0], 0.22)
    assert edges == [0.17, 0.27]
    grid = sigma_grid(edges[0], edges[1], 0.25, 25)
    assert grid[0] > 0.14 and grid[-1] < 0.33 and np.sum((grid > 0.17) & (grid < 0.27)) >= 12
    assert bracketing([0.3, 0.4], 0.22) == [0.3, 0.4]  # beyond every crossing: the two nearest
