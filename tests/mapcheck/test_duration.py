"""Impact duration: (42), (45), (50) against the exact duration (41) from the closed-form ODE."""
from __future__ import annotations

import math

import numpy as np
import pytest

from mapcheck.coeffs import grazing_acceleration
from mapcheck.duration import beta, duration_42, duration_45, duration_50, duration_exact

PARS = [(0.196, 7.368), (4.605170185988091, 0.3059238689620112)]
KAPPAS = np.array([100.0, 300.0, 1000.0, 3000.0])
SIGMA, R = 0.05, 0.9


def v_c_for(beta_value: float, kappa: float, Omega: float) -> float:
    """Collision velocity giving beta (43) at this kappa."""
    return beta_value * abs(grazing_acceleration(SIGMA, Omega, "tilde")) / (R * kappa)


def test_42_arccos_and_arctan_forms_agree():
    b = np.logspace(-3, 3, 61)
    np.testing.assert_allclose(np.arccos((1 - b * b) / (1 + b * b)), 2 * np.arctan(b), rtol=1e-7, atol=1e-12)
    Om = 7.368
    vc = b * abs(grazing_acceleration(SIGMA, Om, "tilde")) / (R * 50.0)
    np.testing.assert_allclose(beta(vc, 50.0, R, SIGMA, Om), b, rtol=1e-14)


@pytest.mark.parametrize("nu, Omega", PARS)
@pytest.mark.parametrize("beta_value", [0.3, 1.0, 3.0])
def test_42_error_falls_like_one_over_kappa_squared(nu, Omega, beta_value):
    """At fixed beta, |Delta t_(42) - Delta t_exact| = O(1/kappa^2) (damping and the
    variation of the forcing during contact are neglected in (42))."""
    err = []
    for k in KAPPAS:
        vc = v_c_for(beta_value, k, Omega)
        exact = float(duration_exact(nu, Omega, SIGMA, (k / Omega) ** 2, R, vc))
        assert exact > 0
        err.append(abs(float(duration_42(vc, k, R, SIGMA, Omega)) - exact))
    slope = np.polyfit(np.log(KAPPAS), np.log(err), 1)[0]
    assert slope < -1.8, (slope, err)
    # and relative to Delta t ~ 1/kappa the error is O(1/kappa)
    dt = 2 * math.atan(beta_value) / KAPPAS[-1]
    assert err[-1] / dt < 3e-3


@pytest.mark.parametrize("nu, Omega", PARS)
def test_45_low_velocity_limit(nu, Omega):
    """(45) Delta t = 2 r v_c / |A~|: relative error ~ beta^2/3 (arctan b = b - b^3/3) + O(1/kappa)."""
    k = 1000.0
    rel = []
    for b in [0.1, 0.03, 0.01]:
        vc = v_c_for(b, k, Omega)
        exact = float(duration_exact(nu, Omega, SIGMA, (k / Omega) ** 2, R, vc))
        rel.append(abs(float(duration_45(vc, R, SIGMA, Omega)) / exact - 1))
    assert rel[0] == pytest.approx(0.1 ** 2 / 3, rel=0.2)  # + O(nu Delta t) from damping
    assert rel[-1] < 1e-4
    assert rel[0] > rel[1] > rel[2]


@pytest.mark.parametrize("nu, Omega", PARS)
def test_50_high_velocity_limit(nu, Omega):
    """(50) Delta t = pi/kappa: relative error ~ 2/(pi beta) (pi/2 - arctan b ~ 1/b)."""
    k = 3000.0
    rel = []
    for b in [10.0, 100.0]:
        vc = v_c_for(b, k, Omega)
        exact = float(duration_exact(nu, Omega, SIGMA, (k / Omega) ** 2, R, vc))
        rel.append(abs(duration_50(k) / exact - 1))
    assert rel[1] == pytest.approx(2 / (math.pi * 100.0), rel=0.1)
    assert rel[0] / rel[1] == pytest.approx(10.0, rel=0.15)


def test_exact_duration_is_vectorized():
    nu, Om = PARS[0]
    vc = np.array([0.01, 0.1])
    d = duration_exact(nu, Om, SIGMA, 1000.0, R, vc)
    assert d.shape == (2,) and np.all(d > 0) and d[1] > d[0]
