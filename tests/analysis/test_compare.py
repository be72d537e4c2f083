"""mapcheck.compare on synthetic data (no FMU): the pieces the reproductions rely on."""
from __future__ import annotations

import math

import numpy as np
import pytest

from mapcheck.coeffs import coefficients
from mapcheck.compare import (
    best_variant,
    free_flight,
    loglog_slope,
    map_one_step_error,
    power_law_with_offset,
    scaled_state,
    sweep_windows,
    wall_free_state,
)
from mapcheck.maps import physical_map, to_natural


def test_sweep_windows_keeps_maximal_runs() -> None:
    s = np.linspace(0.0, 1.0, 11)
    period = np.array([3, 3, 0, 2, 2, 2, 4, 2, 1, 1, 1])
    impacts = np.array([1, 1, -1, 1, 1, 1, 2, 1, 1, 1, 1])
    w = sweep_windows(s, period, impacts)
    assert w == {3: (0.0, pytest.approx(0.1)), 2: (pytest.approx(0.3), pytest.approx(0.5)), 1: (pytest.approx(0.8), 1.0)}


def test_power_law_fits() -> None:
    x = np.geomspace(1e-5, 1e-2, 12)
    assert loglog_slope(x, 3.0 * x ** -0.5) == pytest.approx(-0.5, abs=1e-12)
    q, a, b = power_law_with_offset(x, 3.0 * x ** -0.5 - 2.0)
    assert q == pytest.approx(-0.5, abs=1e-3) and b == pytest.approx(-2.0, rel=1e-2)


def test_free_flight_keeps_the_wall_free_orbit() -> None:
    """p(t) of (4) solves the wall-free ODE: free flight maps it onto itself."""
    nu, Om, sigma = 0.196, 7.368, 0.3
    z = free_flight(wall_free_state(sigma, 0.2), sigma, nu, Om, 0.2, 0.9)
    np.testing.assert_allclose(z, wall_free_state(sigma, 0.9), atol=1e-12)


def test_one_step_error_is_zero_for_the_map_itself() -> None:
    c = coefficients(4.605170185988091, 0.3059238689620112, 0.9, "compliant")
    u, v, s = scaled_state(1e-3, (1.0, 0.5, 0.5), c)
    x, y = to_natural(u, v, s, c)
    assert x == pytest.approx(c.l * 1e-3, rel=1e-9) and y == pytest.approx(0.5 * c.l * 1e-3, rel=1e-9)
    u1, v1 = physical_map(u, v, s, c)
    assert map_one_step_error(u, v, s, float(u1), float(v1), c) == 0.0


def test_best_variant_uses_the_largest_edge_difference() -> None:
    ode = {1: (0.8, None), 2: (0.3, 0.8)}
    variants = {"a": {1: (0.45, None), 2: (0.22, 0.45)}, "b": {1: (0.81, None), 2: (0.29, 0.82)}}
    best, score = best_variant(ode, variants)
    assert best == "b" and score["b"] == pytest.approx(0.02) and math.isclose(score["a"], 0.35)


def test_best_variant_counts_ends_unbounded_in_both_as_agreement() -> None:
    """Identical rows with open ends (beyond the range in the ODE and in the map) agree (0), while
    a window the map lacks stays an infinite difference."""
    ode = {1: (None, None), 2: (0.3, None)}
    same = {1: (None, None), 2: (0.3, None)}
    lacking = {1: (None, None), 2: None}
    best, score = best_variant(ode, {"same": same, "lacking": lacking})
    assert best == "same" and score["same"] == 0.0 and math.isinf(score["lacking"])
