"""Numbers printed as what they are: a grid value that is 0 up to rounding is 0, and a largest edge
difference of 0 between a map and the ODE is agreement, not "does not agree"."""
from __future__ import annotations

import numpy as np

from harness.analysis.windows.summary import _closest_line
from harness.config.specs import parameter_values


def test_a_grid_through_zero_has_zero_in_it() -> None:
    args = ("start", "stop", "num", "values")
    assert 0.0 < abs(np.linspace(-0.1, 0.5, 7)[1]) < 1e-16  # linspace alone: -1.39e-17 for 0
    grid = parameter_values(-0.1, 0.5, 7, None, args)
    assert grid[1] == 0.0 and f"{grid[1]:.6g}" == "0"
    assert np.allclose(grid, np.linspace(-0.1, 0.5, 7), atol=1e-15)
    # a grid that does not pass through 0 is left alone
    assert np.array_equal(parameter_values(0.1, 0.7, 4, None, args), np.linspace(0.1, 0.7, 4))


def test_a_zero_edge_difference_is_agreement() -> None:
    res = {"windows": {"ode": {1: (0.1, 0.5)}}}
    f = {"applies": ["map"], "closest": "map", "gap": 0.0, "width": None}
    line = _closest_line(f, {"map": "2D map"}, res)
    assert "agrees" in line and "does not agree" not in line
    f = {"applies": ["map"], "closest": "map", "gap": 0.05, "width": 0.1}
    assert "does not agree" in _closest_line(f, {"map": "2D map"}, res)
