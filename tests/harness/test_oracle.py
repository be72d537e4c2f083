"""Stroboscopic states from the harness (real FMU through fmpy) against the closed-form oracle.

The oracle (mapcheck.exact.ExactOscillator) solves the piecewise-linear ODE exactly between
wall events, independently of the FMU and of the harness.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from harness import strobe
from harness.config import wall_name
from harness.dynamics.maps.sampling import sample_periods
from mapcheck.exact import ExactOscillator
from tests.support.fmu import harness_params as _params

FMU = Path(__file__).resolve().parents[2] / "build" / "fmu" / "ImpactOscillator.fmu"

FIG7 = dict(nu=0.196, Omega=7.368)  # underdamped case of figures 6 and 7


def _oracle(p: dict) -> ExactOscillator:
    return ExactOscillator(p["nu"], p["Omega"], p["sigma"], r=p["r"], Gamma=p["Gamma"], wall=wall_name(p["wall"]))


@pytest.mark.parametrize(
    "case, state0, theta, n_transient, tol",
    [
        (dict(sigma=0.5, wall=1), (-1.0, 0.3), 0.37, 0, 1e-8),          # Figure 9, compliant
        (dict(sigma=0.2, wall=1), (-0.05, 0.0), 0.0, 3, 1e-8),          # Figure 9, section at t = n
        (dict(sigma=8.0, wall=2), (-1.0, 0.3), 0.37, 0, 1e-8),          # rigid wall, strongly damped
        (dict(sigma=0.05, wall=2, **FIG7), (-1.0, 0.3), 0.37, 1, 1e-6),  # rigid wall, underdamped
        (dict(sigma=0.2, wall=1, Gamma=1000.0, **FIG7), (-1.0, 0.3), 0.0, 2, 1e-6),  # underdamped, stiff
    ],
    ids=["fig9-compliant", "fig9-theta0", "rigid", "rigid-fig7", "fig7-stiff"],
)
def test_strobe_equals_oracle(model, sim, case, state0, theta, n_transient, tol) -> None:
    p = _params(model, **case)
    r = strobe(sim, p, state0, theta=theta, n_transient=n_transient, n_samples=25)
    # sample times are exactly n + theta after the transient
    np.testing.assert_array_equal(r.t, theta + (n_transient + 1 + np.arange(25)))
    # the oracle also at the end of the transient, to difference its cumulative count
    times = np.concatenate([[r.t[0] - 1.0], r.t])
    states, cumulative = _oracle(p).strobe(state0[0], state0[1], times, t0=theta)
    states = states[1:]
    scale = 1.0 + np.max(np.abs(states), axis=0)
    assert np.max(np.abs(r.u - states[:, 0])) < tol * scale[0]
    assert np.max(np.abs(r.v - states[:, 1])) < tol * scale[1]
    # impacts per period: the same count in every period
    np.testing.assert_array_equal(r.impacts, np.diff(cumulative))
    assert r.impacts.sum() >= 3, "the case must exercise the wall"


def test_continuation_through_tunable_sigma_equals_oracle(model, sim) -> None:
    """Changing sigma between periods carries the state: compare with the oracle restarted
    from its own state at the switching time."""
    p = _params(model, sigma=0.6)
    sim.start(p, 0.25, (-0.5, 0.0))
    first = sample_periods(sim, 0, 10)
    sim.set_parameter("sigma", 0.3)
    second = sample_periods(sim, 0, 10)
    s1, _ = _oracle(p).strobe(-0.5, 0.0, first.t, t0=0.25)
    s2, _ = _oracle({**p, "sigma": 0.3}).strobe(s1[-1, 0], s1[-1, 1], second.t, t0=first.t[-1])
    np.testing.assert_allclose(first.u, s1[:, 0], atol=1e-8)
    np.testing.assert_allclose(second.u, s2[:, 0], atol=1e-8)
    np.testing.assert_allclose(second.v, s2[:, 1], atol=1e-8)
    assert sim.restarts == 0, "sigma is tunable: no restart is needed"


def test_time_series_equals_oracle(model, sim) -> None:
    """simulate(): u, v on a fine grid through several impacts, and the cumulative count."""
    from harness import simulate

    p = _params(model, sigma=0.5)
    out = simulate(sim, p, (-1.0, 0.3), t0=0.2, t_end=6.2, dt=0.05)
    states, cumulative = _oracle(p).strobe(-1.0, 0.3, out["t"], t0=0.2)
    np.testing.assert_allclose(out["u"], states[:, 0], atol=1e-8)
    np.testing.assert_allclose(out["v"], states[:, 1], atol=1e-7)
    np.testing.assert_array_equal(out["impacts"], cumulative)
    assert cumulative[-1] >= 3
