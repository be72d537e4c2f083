"""Grazes solved with their orbit by Newton on the extended system (orbit + gap of the free flight = 0),
against the exact closed-form flow (mapcheck, nothing of the harness).

* A compliant wall's impacting period-1 orbit continued down to its graze: the grazing orbit is the
  wall-free orbit (4) touching the wall, so the graze is at sigma = 0 exactly (docs/theory.md
  section 10) -- located from the impacting side, its entry velocity heading to 0.
* Figure 9's period-2 window at Gamma = 10 ends at its upper edge where the free passage of its
  orbit touches the wall: the exact flow's zero of that passage's highest point (mapcheck's orbit
  to 3e-15, the highest point by brentq on v = 0, a quadratic through three orbits 1e-5 to 3e-5
  below) is the truth.
"""
from __future__ import annotations

import numpy as np
import pytest

from harness.dynamics.attractors.scans import find_attractors
from harness.dynamics.continuation.continue_orbit import continue_orbit
from mapcheck.orbits import solve_periodic_orbit
from tests.mapcheck.test_impact_orbit import coco
from tests.support.edges import ExactFlow

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112, r=0.9)


def _graze(br):
    (g,) = [e for e in br.events if e.kind == "graze"]
    return g


def test_a_compliant_impacting_orbit_grazes_at_sigma_zero_to_rounding(sim, model) -> None:
    nu, Om = coco(0.8)
    p = {**model.defaults(), "nu": nu, "Omega": Om, "r": 0.8, "wall": 1, "Gamma": 100.0, "solver": 1}
    (a,) = [x for x in find_attractors(sim, p, [2.0], M_max=1, transient=300).attractors if x.period == 1]
    br = continue_orbit(sim, p, 1, 2.0, a.points[0], p_range=(-0.9, 10.0), direction=-1, max_points=400)
    g = _graze(br)
    lo, hi = g.interval
    assert g.quantity == "entry velocity" and "by Newton on the extended system" in g.note
    assert abs(g.value) < 1e-13 and lo <= 0.0 <= hi and hi - lo < 1e-13, (g.value, g.interval)
    assert abs(br.values[g.index]) > 100 * (hi - lo)  # not the last orbit that converged


def _exact_passage_top(flow: ExactFlow, sigma: float, z) -> tuple[float, np.ndarray]:
    """The highest u of the free period of the exact period-2 orbit at ``sigma`` (Newton from ``z``)."""
    o = solve_periodic_orbit(flow.step_of(sigma), np.asarray(z, float), 2, tol=3e-15, rel_h=1e-6,
                             scale=np.array([0.1, 0.6]), max_iter=40)
    assert o.converged and sorted(o.contacts.tolist()) == [0, 1]
    k = int(np.argmin(o.contacts))
    zk = o.z[k]
    return float(flow.max_u_per_step(sigma, zk, 1, 800)[0]), o.z[0]


@pytest.mark.slow
def test_figure9_period2_graze_is_the_exact_flows_to_1e11(sim, model) -> None:
    p = {**model.defaults(), **FIG9, "wall": 1, "Gamma": 10.0, "solver": 1}
    (a,) = [x for x in find_attractors(sim, p, [0.5], M_max=2, transient=300).attractors if x.period == 2]
    br = continue_orbit(sim, p, 2, 0.5, a.points[0], p_range=(0.05, 5.0), direction=1, max_points=400)
    g = _graze(br)
    assert g.quantity == "gap" and "by Newton on the extended system" in g.note
    flow = ExactFlow(FIG9["nu"], FIG9["Omega"], FIG9["r"], 10.0, "compliant")
    z, tops, ds = g.point, [], np.array([3e-5, 2e-5, 1e-5])
    for d in ds:
        top, z = _exact_passage_top(flow, g.value - d, z)
        tops.append(top)
    roots = np.roots(np.polyfit(-ds, tops, 2))
    exact = g.value + float(roots[np.argmin(np.abs(roots))].real)
    lo, hi = g.interval
    assert abs(g.value - exact) < 1e-11 and hi - lo < 1e-10, (g.value, exact, g.interval)
    # the interval is the solve's: it holds the exact value to the exact flow's own accuracy here
    # (its orbit to 3e-15 moves the passage's top by ~1e-14, sigma by ~1e-12: d top / d sigma ~ 0.01)
    assert lo - 2e-12 <= exact <= hi + 2e-12
