"""Orbit classification on sequences whose period is known by construction."""
from __future__ import annotations

import numpy as np
import pytest

from harness.dynamics.classify import NOT_PERIODIC, classify_orbit, classify_samples, windows


def _cycle(points: list[tuple[float, float]], impacts: list[int], n: int, noise: float = 0.0, seed: int = 0):
    rng = np.random.default_rng(seed)
    k = len(points)
    u = np.array([points[i % k][0] for i in range(n)]) + noise * rng.standard_normal(n)
    v = np.array([points[i % k][1] for i in range(n)]) + noise * rng.standard_normal(n)
    imp = np.array([impacts[i % k] for i in range(n)])
    return u, v, imp


@pytest.mark.parametrize("period", [1, 2, 3, 5])
def test_period_and_impacts_of_a_constructed_cycle(period: int) -> None:
    pts = [(0.01 * (i + 1), -0.3 * i) for i in range(period)]
    imps = [1] + [0] * (period - 1)
    u, v, imp = _cycle(pts, imps, 40, noise=1e-9)
    c = classify_orbit(u, v, imp, tol=1e-6)
    assert (c.period, c.impacts) == (period, 1)
    assert c.label == f"P{period}, 1 impact"


def test_noise_above_tolerance_is_not_periodic() -> None:
    u, v, imp = _cycle([(0.1, 0.2), (0.3, 0.4)], [1, 0], 40, noise=1e-3)
    assert classify_orbit(u, v, imp, tol=1e-6).period == NOT_PERIODIC


def test_chaotic_sequence_is_not_periodic() -> None:
    # logistic map at r = 4: chaotic, no period up to N/2
    x = np.empty(60)
    x[0] = 0.2
    for i in range(59):
        x[i + 1] = 4 * x[i] * (1 - x[i])
    c = classify_orbit(x, np.zeros_like(x), np.zeros(60, dtype=int))
    assert c.period == NOT_PERIODIC and c.impacts == -1 and c.label == "not periodic"


def test_impact_pattern_must_repeat_too() -> None:
    # the states repeat every period but the impacts only every 2 periods: period 2
    u = np.full(30, 0.5)
    v = np.zeros(30)
    imp = np.array([1, 0] * 15)
    c = classify_orbit(u, v, imp)
    assert (c.period, c.impacts) == (2, 1)


def test_tolerance_is_relative_to_the_orbit_size() -> None:
    # the same absolute noise 1e-4: small against an orbit of size 200, not against 0.02
    u, v, imp = _cycle([(100.0, 0.0), (-100.0, 50.0)], [0, 0], 20, noise=1e-4)
    assert classify_orbit(u, v, imp, tol=1e-5).period == 2
    u, v, imp = _cycle([(0.01, 0.0), (-0.01, 0.005)], [0, 0], 20, noise=1e-4)
    assert classify_orbit(u, v, imp, tol=1e-5).period == NOT_PERIODIC


def test_non_finite_samples_are_not_periodic() -> None:
    u = np.array([0.1, np.nan, 0.1, 0.1])
    assert classify_orbit(u, np.zeros(4), np.zeros(4, dtype=int)).period == NOT_PERIODIC


def test_classify_samples_keeps_leading_dims() -> None:
    a = _cycle([(0.1, 0.0)], [1], 20)
    b = _cycle([(0.1, 0.0), (0.2, 0.0), (0.3, 0.0)], [0, 0, 1], 20)
    u = np.stack([a[0], b[0]])
    v = np.stack([a[1], b[1]])
    imp = np.stack([a[2], b[2]])
    period, impacts = classify_samples(u, v, imp)
    assert period.tolist() == [1, 3] and impacts.tolist() == [1, 1]


def test_windows_groups_runs_of_maximal_orbits() -> None:
    sigma = np.array([0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7])
    period = np.array([0, 3, 3, 0, 2, 2, 1])
    impacts = np.array([-1, 1, 1, -1, 1, 2, 1])  # the P2 at 0.6 has 2 impacts: not maximal
    assert windows(sigma, period, impacts) == [(3, 0.2, 0.3), (2, 0.5, 0.5), (1, 0.7, 0.7)]
    assert windows(sigma, period) == [(3, 0.2, 0.3), (2, 0.5, 0.6), (1, 0.7, 0.7)]


def test_still_settling_tells_a_converging_alternation_from_a_true_period_two() -> None:
    from harness.dynamics.classify import still_settling

    k = np.arange(40)
    converging = 0.5 + 1e-3 * (-0.97) ** k      # period 1 approached with multiplier -0.97
    true_p2 = 0.5 + 1e-3 * (-1.0) ** k          # a genuine period-2 orbit
    zeros = np.zeros(40)
    assert still_settling(converging, zeros, period=2)
    assert not still_settling(true_p2, zeros, period=2)
    assert not still_settling(true_p2, zeros, period=1)  # no shorter period to settle to


@pytest.mark.parametrize("size", [0.02, 1.0, 200.0])
@pytest.mark.parametrize("factor,periodic", [(0.9, True), (1.1, False)], ids=["below", "above"])
def test_periodicity_threshold_scales_with_the_orbit_on_both_sides(size: float, factor: float, periodic: bool) -> None:
    """The threshold is tol (1 + amplitude), amplitude = the orbit's largest peak-to-peak range:
    a deviation of 0.9 times the threshold is periodic, of 1.1 times is not, for orbits of
    size 0.02, 1 and 200 (a threshold not scaled, or scaled by the wrong power, fails one side).
    The deviation is one spike at the last sample, so every shift's residual is exactly its
    height (no random noise whose maximum is only known statistically)."""
    tol = 1e-5
    u, v, imp = _cycle([(size / 2, 0.0), (-size / 2, size / 4)], [1, 0], 30)
    threshold = tol * (1.0 + size)
    u[-1] += factor * threshold
    c = classify_orbit(u, v, imp, tol=tol)
    assert (c.period == 2) is periodic
    if not periodic:
        assert c.period == NOT_PERIODIC and c.residual == pytest.approx(factor * threshold, rel=1e-6)
