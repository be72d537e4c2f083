"""The chord error of a continued edge read between two points of its curve
(:mod:`harness.analysis.chart.curve_interpolation`), against curves known in closed form."""
from __future__ import annotations

import math

import numpy as np
import pytest

from harness.analysis.chart.edge_curves import _edge_at
from harness.analysis.chart.curve_interpolation import chord_error


def _curve(p2: np.ndarray, sigma: np.ndarray) -> dict:
    return {"p2": p2.tolist(), "sigma": sigma.tolist(), "kind": "flip", "turns": [], "end": {}}


def test_a_power_law_is_read_exactly_and_its_chord_error_vanishes() -> None:
    p2 = np.geomspace(10.0, 1000.0, 9)
    c = _curve(p2, 0.3 * p2 ** 0.7)  # a straight line in (ln p2, ln sigma)
    for v in (13.0, 170.0, 900.0):
        assert _edge_at(c, v) == pytest.approx(0.3 * v ** 0.7, rel=1e-12)
        assert chord_error(c, v) < 1e-12 * v


@pytest.mark.parametrize("a", [0.5, 2.0, 6.0])
def test_the_chord_error_covers_the_chord_on_a_curved_edge(a: float) -> None:
    """ln sigma = a (e^q - 1 - q), q = ln(p2 / 10): convex in (ln p2, ln sigma) and not a parabola,
    points 12 % apart as on Figure 9's steep stretch; the estimate covers the chord's true error and
    is not 5x larger."""
    def exact(p: np.ndarray) -> np.ndarray:
        q = np.log(p / 10.0)
        return np.exp(a * (np.expm1(q) - q))

    p2 = 10.0 * np.exp(np.arange(0.0, 1.2, 0.12))
    c = _curve(p2, exact(p2))
    for v in 10.0 * np.exp(np.linspace(0.13, 1.0, 7)):
        true = abs(_edge_at(c, v) - float(exact(np.array(v))))
        est = chord_error(c, v)
        assert true <= est * (1 + 1e-9) + 1e-15
        assert est <= 5.0 * true + 1e-12


def test_outside_the_curve_or_on_too_few_points_nothing_is_estimated() -> None:
    p2 = np.geomspace(10.0, 100.0, 5)
    c = _curve(p2, p2)
    assert chord_error(c, 5.0) == 0.0 and chord_error(c, 200.0) == 0.0
    assert chord_error(_curve(p2[:2], p2[:2]), 20.0) == 0.0
    assert chord_error({"kind": "flip", "failed": "no start"}, 20.0) == 0.0
