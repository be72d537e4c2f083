"""``reproduce fig6/fig7 --quick``: slopes of the FMU map's Jacobian near grazing and the
hysteretic transition, (nu, Omega) = (0.196, 7.368) (docs/theory.md section 8).

Theory: the impact contribution J11 - P11 (coordinates at t = n) goes like x^(+1/2) for soft
(beta << 1) elastic contacts (the map is O(x^(3/2)), N = I), like x^(-1/2) for soft contacts
with r < 1 (square-root term with (1 - r)) and for hard contacts (beta >> 1, the rigid map).
"""
from __future__ import annotations

import json

import pytest

from harness.reproduce import run_target

pytestmark = pytest.mark.slow  # reproduces the paper's Figures 6 and 7

#: 0.05 in the exponent: over the >= 1 decade fitted, a 12% distortion of the end points;
#: what the O(1) part and the next order (x^(1/2) relative) leave at beta <= 0.1.
TOL = 0.05


@pytest.fixture(scope="module", params=["fig6", "fig7"])
def fig(request, tmp_path_factory):
    out = tmp_path_factory.mktemp(request.param)
    run_target(request.param, out, quick=True, progress=False)
    return request.param, out, json.loads((out / f"{request.param}.json").read_text())


def test_outputs(fig) -> None:
    name, out, res = fig
    for f in ("report.md", f"{name}_jacobian.png", f"{name}_bifurcation.png"):
        assert (out / f).stat().st_size > 0, f
    assert set(res["slopes"]) >= {"10.0", "100.0", "1000.0", "10000.0"}


def test_soft_slopes(fig) -> None:
    """Soft regime (beta <= 0.1) at Gamma = 10, the only paper stiffness where it covers over
    a decade of reliable x (x >= 1e-5: below, the FMU's own error near grazing enters the
    differences); there it must hold, and the stiffer walls have no soft range that wide."""
    name, _, res = fig
    expected = 0.5 if name == "fig6" else -0.5
    soft = res["slopes"]["10.0"]["soft"]
    assert soft is not None
    assert soft["slope"] == pytest.approx(expected, abs=TOL), soft
    assert soft["x_range"][1] / soft["x_range"][0] >= 10


def test_hard_slopes_approach_minus_one_half(fig) -> None:
    """Hard regime (beta >= 5): the exponent tends to -1/2 as the wall stiffens.  At the
    paper's Gamma = 1e4 beta reaches only ~50 in the fitted range and the slope is ~-0.45
    (finite stiffness); the limit holds within TOL at Gamma = 1e6, and the distance to -1/2
    shrinks monotonically from 1e4 to 1e6."""
    _, _, res = fig
    slopes = [res["slopes"][G]["hard"]["slope"] for G in ("10000.0", "100000.0", "1000000.0")]
    assert all(s < 0 for s in slopes)
    dist = [abs(s + 0.5) for s in slopes]
    assert dist[0] > dist[1] > dist[2]
    assert slopes[-1] == pytest.approx(-0.5, abs=TOL)
    assert slopes[0] == pytest.approx(-0.5, abs=2 * TOL)


def test_hysteresis_at_gamma_1000(fig) -> None:
    """Decreasing sigma, the down scan keeps impacting below where the up scan started to
    impact: a hysteresis loop at least one grid step wide; at r = 1 the orbit held is the
    period-3 orbit (the square-root map's period-3 -> period-1 transition)."""
    name, _, res = fig
    h = res["hysteresis"]["1000.0"]
    assert h["hysteresis_width"] >= h["grid_step"] - 1e-12
    if name == "fig6":
        assert any(p == 3 for p, _ in h["down_periods_in_hysteresis"])


def test_exact_derivatives_fit_from_1e_minus_9(fig) -> None:
    """With the FMU's own derivatives the scan starts at x = 1e-9: the soft exponent holds over
    eight decades at Gamma = 10 (+1/2 at r = 1, -1/2 at r = 0.9) to 0.01, and the exact
    Jacobian agrees with the differences where both are reliable (x = 1e-4 .. 1e-2)."""
    name, _, res = fig
    assert res["method"] == "exact", "the project's FMU reports its derivatives"
    expected = 0.5 if name == "fig6" else -0.5
    soft = res["slopes"]["10.0"]["soft"]
    assert soft["x_range"][0] == pytest.approx(1e-9)
    assert soft["x_range"][1] / soft["x_range"][0] >= 1e5
    assert soft["slope"] == pytest.approx(expected, abs=0.01)
    assert soft["slope_offset_removed"] == pytest.approx(expected, abs=0.01)
    assert res["cross_check"]["max_relative_difference"] < 1e-3
