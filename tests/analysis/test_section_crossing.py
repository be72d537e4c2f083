"""An orbit is what it is, not where the section cuts it: an impact time crossing the sampling phase
t = n + 1/2 is no edge, and the period-doubled orbit is found at its parent's flip from the flip's
eigenvector, under both solvers; the exact flow (:mod:`mapcheck.exact`) confirms every number.

The oscillator: a lightly damped rigid wall (nu = 0.5, Omega = 2.5, r = 0.95).  Its period-2 orbit
with one impact flips at sigma = -0.48733; the period-4 orbit with two impacts born there lives up
to its graze at sigma = -0.31444.  At sigma = -0.38569 one of its impact times crosses t = n + 1/2:
the contacts counted per sampled period move from one period to the next, the orbit does not
change.  The continuation used to end the window there ("impact-lost").
"""
from __future__ import annotations

import numpy as np
import pytest

from harness.dynamics.continuation.continue_orbit import continue_orbit, switch_at_flip
from harness.dynamics.continuation.window_branch import first_edge
from tests.support.random_oscillators import Oscillator, brute_force

OSC = Oscillator(0, 0.5, 2.5, 0.95, "rigid", 10.0)
CROSSING = -0.38569111  # an impact time of the period-4 orbit at t = n + 1/2 (section artefact)
GRAZE = -0.3144392136   # the period-4 orbit's real graze


@pytest.fixture(scope="module")
def sim():
    from harness.fmu.fmi import FmuModel
    from harness.fmu.simulator import FmuSimulator

    return FmuSimulator(FmuModel("build/fmu/ImpactOscillator.fmu").source(), instance_name="section-crossing")


def _period4(sim, solver: str):
    """The period-2 orbit continued up to its flip, and the period-4 branch switched onto there."""
    params = {**OSC.params(solver)}
    two = [a for a in brute_force(OSC, -0.5, n_starts=60, M_max=4) if (a.M, a.k) == (2, 1)]
    assert two, "the exact flow has the stable period-2 orbit at sigma = -0.5"
    br = continue_orbit(sim, params, 2, -0.5, two[0].points[0], p_range=(-0.55, -0.25), direction=1.0, max_points=60)
    flip = next(e for e in br.events if e.kind == "flip")
    child = switch_at_flip(sim, params, br, flip, p_range=(-0.55, -0.25), max_points=80)
    assert child is not None, "branch switching finds the period-4 orbit at the flip"
    return flip, child


@pytest.mark.parametrize("solver", ["closed-form", pytest.param("cvode", marks=pytest.mark.slow)])
def test_an_impact_crossing_the_section_is_no_edge_and_the_child_is_born_at_the_flip(sim, solver: str) -> None:
    flow = OSC.flow()
    flip, child = _period4(sim, solver)
    # the flip on the exact flow: the period-2 orbit's multiplier passes -1 within 1e-8 of it
    two = flow.orbit(flip.value, 2, flip.point)
    assert two.converged
    mu = [min(np.real(flow.multipliers(flip.value + d, flow.orbit(flip.value + d, 2, two.z[0]).z[0], 2)))
          for d in (-1e-8, 1e-8)]
    assert mu[0] > -1.0 > mu[1], mu
    # the child starts at the flip (born there: within 1e-6, its amplitude ~ sqrt(distance))
    assert abs(child.values[0] - flip.value) < 1e-6
    e = first_edge(child)
    assert e is not None and e.kind == "graze", [(x.kind, x.value) for x in child.events]
    assert abs(e.value - GRAZE) < 1e-7, e.value
    # no event where the impact crosses the section: the exact flow's period-4 orbit is stable with
    # two contacts on both sides of it, its multipliers continuous
    i = int(np.argmin(np.abs(child.values - CROSSING)))
    z = child.points[i][0]
    sides = [flow.orbit(CROSSING + d, 4, z) for d in (-1e-6, 1e-6)]
    assert all(o.converged and o.stable and int(np.sum(o.contacts)) == 2 for o in sides)
    m = [np.sort(np.abs(o.multipliers)) for o in sides]
    assert np.max(np.abs(m[0] - m[1])) < 1e-3
    # the graze on the exact flow: stable with two contacts 1e-7 inside, not 1e-7 beyond
    inside = flow.orbit(GRAZE - 1e-7, 4, child.points[e.index][0])
    assert inside.converged and inside.stable and int(np.sum(inside.contacts)) == 2
    beyond = flow.orbit(GRAZE + 1e-7, 4, inside.z[0])
    assert not (beyond.converged and beyond.stable and int(np.sum(beyond.contacts)) == 2)
