"""Orbit classification on sequences whose period is known by construction."""
from __future__ import annotations

import numpy as np
import pytest

from harness.dynamics.maps.classify import NOT_PERIODIC, classify_orbit, classify_samples, windows


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
    from harness.dynamics.maps.classify import still_settling

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


SIZES = [1e-3, 1e-1, 10.0, 1e3]  # orbit sizes over six decades


@pytest.mark.parametrize("size", SIZES)
@pytest.mark.parametrize("factor,periodic", [(0.1, True), (5.0, False)], ids=["below", "above"])
def test_noise_a_few_times_below_or_above_the_scaled_threshold(size: float, factor: float, periodic: bool) -> None:
    """Random noise of standard deviation ``factor`` times the threshold tol (1 + size) on every
    sample of a period-3 orbit of size ``size``: at 1/10 of it (the largest of the 2 x 37
    differences is below 1/2 of the threshold but for a 7-sigma event) the orbit is periodic, at 5
    times it (every difference is a 7-sigma spread, so some exceed the threshold for every shift)
    it is not, at every size.  A threshold without the orbit's size fails the periodic side at
    sizes 10 and 1e3, one with the size squared the other side at 1e3."""
    tol = 1e-5
    pts = [(size / 2, 0.0), (-size / 2, size / 4), (0.0, -size / 4)]
    threshold = tol * (1.0 + size)
    u, v, imp = _cycle(pts, [1, 0, 0], 40, noise=factor * threshold, seed=int(np.log10(size)) + 10)
    c = classify_orbit(u, v, imp, tol=tol)
    assert (c.period == 3) is periodic, (c, threshold)
    if not periodic:
        assert c.period == NOT_PERIODIC and c.residual > threshold


@pytest.mark.parametrize("size", SIZES)
@pytest.mark.parametrize("factor,settling", [(0.3, False), (3.0, True)], ids=["below", "above"])
def test_settling_threshold_scales_with_the_orbit_on_both_sides(size: float, factor: float, settling: bool) -> None:
    """A period-2 orbit of size ``size`` approached through a decaying period-4 modulation (the
    samples look like period 4): still settling while the modulation's 2-shift differences start
    above the threshold tol (1 + size) (3 times it), converged when they start below it (0.3
    times): the transient is over once it is within the periodicity tolerance, at every size."""
    from harness.dynamics.maps.classify import still_settling

    tol = 1e-5
    k = np.arange(40)
    threshold = tol * (1.0 + size)
    # m_k = eps 0.99^k (+1, +1, -1, -1, ...): |m_{k+2} - m_k| = eps 0.99^k (1 + 0.99^2) ~ 2 eps at first
    eps = factor * threshold / 2.0
    u = 0.5 * size * (-1.0) ** k + eps * 0.99 ** k * (-1.0) ** (k // 2)
    v = 0.25 * size * (-1.0) ** k
    early = np.abs(u[2:] - u[:-2])[:9].mean()
    assert bool(early > threshold) is settling  # the construction is on the intended side
    assert bool(still_settling(u, v, period=4, tol=tol)) is settling
