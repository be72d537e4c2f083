"""The rigid wall's one-impact period-1 orbit in closed form (:mod:`mapcheck.impact_orbit`)
against the exact flow (:mod:`mapcheck.exact`) with mapcheck's own Newton shooting: two routes
that share nothing but the propagator.  The closed form is the truth of the continuation's fold,
flip and graze on COCO's impact example (tests/harness/test_graze_location.py)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from mapcheck.exact import ExactOscillator
from mapcheck.impact_orbit import flip_velocities, fold_velocity, one_impact_orbit, sigma_of_v
from mapcheck.linear import propagator
from mapcheck.orbits import solve_periodic_orbit

THETA = 0.5


def coco(omega: float) -> tuple[float, float]:
    """(nu, Omega) of Recipes for Continuation's Example 15.2, x'' + 0.1 x' + x = A cos(omega t)
    with the wall at x = 1: time in forcing periods (t' = omega t / 2 pi), lengths in the gap."""
    return 0.2 * math.pi / omega, 2.0 * math.pi / omega


def section_state(nu: float, Omega: float, orb, theta: float = THETA) -> np.ndarray:
    """The orbit's state at t = theta (mod 1), by the free flow (8) from its rebound (0, -r v) at phi."""
    tau = (theta - orb.phi) % 1.0
    amp = 1.0 + orb.sigma

    def p(t: float) -> np.ndarray:
        return np.array([amp * math.cos(2 * math.pi * t) - 1.0, -2 * math.pi * amp * math.sin(2 * math.pi * t)])

    z_plus = np.array([0.0, -0.8 * orb.v])
    return np.asarray(propagator(tau, nu, Omega), dtype=float) @ (z_plus - p(orb.phi)) + p(orb.phi + tau)


@pytest.mark.parametrize("omega", [0.8, 1.0, 1.32, 2.0])
@pytest.mark.parametrize("v", [0.2, 0.5, 1.0])
def test_the_closed_form_orbit_is_the_exact_flows(omega: float, v: float) -> None:
    """At every impact velocity the closed form's orbit is a period-1 orbit of the exact flow with
    one impact, and its impact map's multipliers are the stroboscopic map's (shooting with
    finite differences on the exact flow, good to ~3e-4 next to the graze where the map bends
    like a square root within the difference step)."""
    nu, Om = coco(omega)
    orb = one_impact_orbit(nu, Om, 0.8, v)
    z = section_state(nu, Om, orb)
    ex = ExactOscillator(nu, Om, orb.sigma, 0.8, 10.0, "rigid")
    u1, v1, n = ex.state_at(z[0], z[1], THETA, THETA + 1.0)
    if n != 1:
        pytest.skip(f"not physical at v = {v} (the flight reaches the wall {n} times)")
    assert np.max(np.abs(np.array([u1, v1]) - z)) < 1e-10
    shot = solve_periodic_orbit(lambda a, b: ex.state_at(a, b, THETA, THETA + 1.0), z, 1, tol=1e-12,
                                scale=np.array([1e-2, 1e-1]), rel_h=1e-7)
    assert shot.converged and np.max(np.abs(shot.z[0] - z)) < 1e-10
    assert np.allclose(np.sort_complex(shot.multipliers), np.sort_complex(orb.multipliers), rtol=1e-5, atol=5e-4)


@pytest.mark.parametrize("omega", [0.8, 1.0, 1.32, 2.0, 3.0])
def test_the_branch_grazes_at_sigma_zero_with_a_velocity_linear_in_sigma(omega: float) -> None:
    """sigma(0) = 0 and sigma(v) / v tends to c1 (not 0): the impact velocity vanishes linearly at
    the graze; the multipliers blow up like 1/v (the stroboscopic map's square-root singularity)."""
    nu, Om = coco(omega)
    assert sigma_of_v(nu, Om, 0.8, 0.0) == 0.0
    slopes = [sigma_of_v(nu, Om, 0.8, v) / v for v in (1e-5, 1e-6, 1e-7)]
    assert abs(slopes[2]) > 1e-4 and abs(slopes[2] - slopes[1]) < 1e-2 * abs(slopes[2])
    big = [np.abs(one_impact_orbit(nu, Om, 0.8, v).multipliers).max() * v for v in (1e-4, 1e-5)]
    assert big[1] == pytest.approx(big[0], rel=1e-2)


def test_fold_and_flip_are_where_a_multiplier_is_plus_and_minus_one() -> None:
    """The fold (d sigma/dv = 0, in closed form) has a multiplier +1; each flip found by the
    multipliers has one at -1, and the exact flow's multiplier crosses -1 there."""
    nu, Om = coco(1.0)
    fold = one_impact_orbit(nu, Om, 0.8, fold_velocity(nu, Om, 0.8, 0.0, 1.0))
    assert np.min(np.abs(fold.multipliers - 1.0)) < 1e-9
    nu, Om = coco(0.8)
    (v_flip,) = flip_velocities(nu, Om, 0.8, 0.5, 5.0)
    flip = one_impact_orbit(nu, Om, 0.8, v_flip)
    assert np.min(np.abs(flip.multipliers + 1.0)) < 1e-9
    for dv, outside in ((-1e-3, False), (1e-3, True)):
        orb = one_impact_orbit(nu, Om, 0.8, v_flip + dv)
        ex = ExactOscillator(nu, Om, orb.sigma, 0.8, 10.0, "rigid")
        shot = solve_periodic_orbit(lambda a, b: ex.state_at(a, b, THETA, THETA + 1.0), section_state(nu, Om, orb), 1,
                                    tol=1e-12, scale=np.array([1e-2, 1e-1]))
        assert shot.converged and (np.min(shot.multipliers.real) < -1.0) == (np.min(orb.multipliers.real) < -1.0)
