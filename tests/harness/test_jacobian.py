"""Jacobian of the stroboscopic map measured on the real FMU (docs/theory.md sections 6 and 8).

Independent truths: the free-flight Jacobian P(1) from mapcheck.linear (closed form (7)),
det J = r^2 e^{-nu} across one impact (section 6), and the square-root singularity of the
map near grazing: |J - P| ~ x^{-1/2} for r < 1 at low impact velocity (section 8).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from harness import HarnessInputError, jacobian_vs_x, map_jacobian
from mapcheck.linear import propagator
from tests.support.fmu import harness_params as _params

FMU = Path(__file__).resolve().parents[2] / "build" / "fmu" / "ImpactOscillator.fmu"


@pytest.mark.parametrize("nu, Omega", [(4.605170185988091, 0.3059238689620112), (0.196, 7.368)])
def test_free_flight_jacobian_is_the_propagator(model, sim, nu, Omega) -> None:
    p = _params(model, nu=nu, Omega=Omega, wall=0, sigma=0.2)
    res = map_jacobian(sim, p, (-0.7, 0.4), theta=0.3)
    np.testing.assert_allclose(res.J, propagator(1.0, nu, Omega), atol=1e-6)
    assert res.error < 1e-6


@pytest.mark.parametrize("method", ["fd", "exact"])
@pytest.mark.parametrize("nu, Omega", [(4.605170185988091, 0.3059238689620112), (0.196, 7.368)])
def test_each_method_gives_the_propagator(model, sim, nu, Omega, method) -> None:
    """The differences too, not only the default (exact) path: a difference quotient with the
    wrong step (f(x+h) - f(x-h)) / h doubles J."""
    p = _params(model, nu=nu, Omega=Omega, wall=0, sigma=0.2)
    res = map_jacobian(sim, p, (-0.7, 0.4), theta=0.3, method=method)
    np.testing.assert_allclose(res.J, propagator(1.0, nu, Omega), rtol=1e-6, atol=1e-7)


@pytest.fixture(scope="module")
def fig9_scans(model, sim):
    p = _params(model, sigma=0.0)
    x = np.geomspace(1e-5, 1e-2, 7)
    return p, x, {theta: jacobian_vs_x(sim, p, x, theta=theta) for theta in (0.0, 0.5)}


def _slope(x: np.ndarray, y: np.ndarray) -> float:
    return float(np.polyfit(np.log(x), np.log(np.abs(y)), 1)[0])


def test_square_root_singularity_in_J11_at_t_equal_n(fig9_scans) -> None:
    """At t = n with v = 0 (the paper's coordinates) J11 carries the singularity, J12 not."""
    p, x, scans = fig9_scans
    s = scans[0.0]
    P1 = propagator(1.0, p["nu"], p["Omega"])
    np.testing.assert_allclose(s.P1, P1, atol=1e-12)
    d = s.J - P1
    assert _slope(x, d[:, 0, 0]) == pytest.approx(-0.5, abs=0.05)
    # J12 is generic there: bounded (at x = 1e-5 a singular element would be O(10), as at
    # theta = 1/2 below) and far smaller than J11 - P11
    assert np.all(np.abs(d[:, 0, 1]) < 0.05)
    assert np.all(np.abs(d[:, 0, 1]) < 0.01 * np.abs(d[:, 0, 0]))


def test_every_element_singular_at_another_phase(fig9_scans) -> None:
    p, x, scans = fig9_scans
    d = scans[0.5].J - scans[0.5].P1
    for i, j in [(0, 0), (0, 1), (1, 0), (1, 1)]:
        assert _slope(x, d[:, i, j]) == pytest.approx(-0.5, abs=0.08), (i, j)


def test_determinant_across_one_impact(fig9_scans) -> None:
    """det J = r^2 e^{-nu} (docs/theory.md section 6), whatever the coordinates."""
    p, x, scans = fig9_scans
    expected = p["r"] ** 2 * math.exp(-p["nu"])
    for s in scans.values():
        np.testing.assert_allclose(np.linalg.det(s.J), expected, rtol=5e-3)


def test_jacobian_input_errors(model, sim) -> None:
    p = _params(model)
    with pytest.raises(HarnessInputError, match=r"\[0, 1\)"):
        map_jacobian(sim, p, (0.0, 0.0), theta=1.0)
    with pytest.raises(HarnessInputError, match="empty range"):
        jacobian_vs_x(sim, p, [], theta=0.0)
