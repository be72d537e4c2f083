"""The sigma coordinate of the two-parameter curves: ln sigma above grazing, sigma itself on a
range reaching below it, where the edges of the coexisting windows lie.

Truth: the exponential and its derivative (the log axis must be the one the curves always used,
number for number); mapcheck's closed-form flow with its own Newton shooting and multipliers
(tests/support/edges.py) for a flip curve continued at negative sigma; the wall-free orbit (4),
whose amplitude 1 + sigma touches the wall at sigma = 0 whatever the other parameters.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from harness.dynamics.curves.event_curves import continue_event
from harness.dynamics.curves.graze_curves import continue_graze
from harness.dynamics.curves.sigma_axis import LINEAR, LOG, sigma_axis
from tests.support.edges import ExactFlow

#: a rigid wall with r close to 1 (docs/examples/windows-rigid): below grazing a period-2 orbit with
#: one impact coexists with the wall-free orbit up to its flip at sigma = -0.2211
RIGID = {"nu": 0.8, "Omega": 2.5, "r": 0.95, "wall": 2, "solver": 1}


def test_the_log_axis_is_the_exponential_and_the_linear_one_is_sigma() -> None:
    s = np.linspace(-8.0, 8.0, 33)
    assert all(LOG.of(float(x)) == math.exp(float(x)) and LOG.to(LOG.of(float(x))) == pytest.approx(x) for x in s)
    assert np.array_equal(LOG.of_array(s), np.exp(s)) and np.array_equal(LINEAR.of_array(s), s)
    for axis in (LOG, LINEAR):
        h = 1e-6
        fd = [(axis.of(float(x) + h) - axis.of(float(x) - h)) / (2 * h) for x in s]
        assert [axis.dsigma_ds(float(x)) for x in s] == pytest.approx(fd, rel=1e-7)
    assert sigma_axis((1e-4, 3.0)) is LOG and sigma_axis((0.0, 1.0)) is LINEAR and sigma_axis((-0.3, 0.3)) is LINEAR


def _period_2_with_one_impact(flow: ExactFlow, sigma: float) -> np.ndarray:
    """A point of the stable period-2 orbit with one impact, from starts of large amplitude (the
    wall-free orbit attracts the small ones)."""
    step = flow.step_of(sigma)
    for z0 in [(u, v) for u in np.linspace(-4, -0.2, 7) for v in np.linspace(-12, 12, 7)]:
        z = np.array(z0)
        for _ in range(300):
            *z, _c = step(*z)
        orb = flow.orbit(sigma, 2, z)
        if orb.converged and orb.stable and int(np.sum(orb.contacts)) == 1:
            return orb.z[0]
    raise AssertionError("no stable period-2 orbit with one impact")


def test_a_flip_below_grazing_continued_in_r_is_a_flip_of_the_exact_flow(sim, model) -> None:
    flow = ExactFlow(0.8, 2.5, 0.95, 10.0, "rigid")
    orb = flow.orbit(-0.2211, 2, _period_2_with_one_impact(flow, -0.25))
    p = {**model.defaults(), **RIGID}
    fc = continue_event(sim, p, "flip", 2, -0.2211, orb.z[0], "r", (0.8, 0.96), False, -1.0,
                        sigma_range=(-0.6, 0.3), max_points=40)
    assert fc.end["reason"] == "range" and fc.p2[-1] < 0.81  # the whole range of r crossed
    assert np.all(fc.sigma < 0) and np.ptp(fc.sigma) > 0.05  # below grazing, and it moves
    for i in range(len(fc.sigma)):  # every point, on the exact flow
        ex = ExactFlow(0.8, 2.5, float(fc.p2[i]), 10.0, "rigid").orbit(float(fc.sigma[i]), 2, fc.points[i])
        assert ex.converged and int(np.sum(ex.contacts)) == 1, (fc.p2[i], fc.sigma[i])
        assert np.min(np.abs(ex.multipliers + 1.0)) < 1e-6, (fc.p2[i], fc.sigma[i], ex.multipliers)


def test_the_wall_free_orbit_grazes_at_sigma_0_over_the_second_parameter(sim, model) -> None:
    s_in, w = -0.05, 2.0 * math.pi * 0.5
    z = [(1.0 + s_in) * math.cos(w) - 1.0, -2.0 * math.pi * (1.0 + s_in) * math.sin(w)]  # (4) at t = 1/2
    p = {**model.defaults(), **RIGID}
    gc = continue_graze(sim, p, 1, s_in, z, 0.02, "r", (0.8, 0.96), False, -1.0, max_points=20,
                        sigma_range=(-0.6, 0.3))
    assert gc.impacts == 0 and gc.end["reason"] == "range" and gc.p2[-1] < 0.81
    assert np.max(np.abs(gc.sigma)) < 1e-9
