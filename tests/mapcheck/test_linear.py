"""Linear part: propagator (7) at every damping, (9), and the (alpha, gamma) inverse."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import expm

from mapcheck.linear import (
    alpha_gamma,
    eigenvalues,
    invert_alpha_gamma,
    propagator,
    propagator_k2,
    propagator_minus_identity,
    underdamped_branches,
)

# overdamped (figure 9, figure 1), underdamped (figures 6/7), critically and nearly critically damped
PARAMS = [
    (4.605170185988091, 0.3059238689620112),
    (0.196, 7.368),
    (2.0, 1.0),
    (2.0, 1.0 + 1e-9),
    (2.0, 1.0 - 1e-9),
    (0.5, 1.0),
]


@pytest.mark.parametrize("nu, Omega", PARAMS)
def test_propagator_is_matrix_exponential(nu, Omega):
    """P(t) = expm(M t) for M = [[0, 1], [-Omega^2, -nu]], the generator of (3)."""
    M = np.array([[0.0, 1.0], [-Omega ** 2, -nu]])
    t = np.array([-0.5, 1e-9, 0.01, 0.3, 1.0, 2.7])
    P = propagator(t, nu, Omega)
    for k, tk in enumerate(t):
        ref = expm(M * tk)
        np.testing.assert_allclose(P[k], ref, rtol=1e-12, atol=1e-14 * np.abs(ref).max())


@pytest.mark.parametrize("nu, Omega", [p for p in PARAMS if abs(p[0] - 2 * p[1]) > 1e-3])
def test_eigenvalue_form_of_7(nu, Omega):
    """Away from critical damping (where (7) is 0/0) the printed form (7) in s1, s2 agrees."""
    s1, s2 = eigenvalues(nu, Omega)
    t = 0.7
    e1, e2 = np.exp(s1 * t), np.exp(s2 * t)
    P7 = np.array([[s2 * e1 - s1 * e2, e2 - e1], [s1 * s2 * (e1 - e2), s2 * e2 - s1 * e1]]) / (s2 - s1)
    np.testing.assert_allclose(propagator(t, nu, Omega), P7.real, rtol=1e-11, atol=1e-13)


@pytest.mark.parametrize("nu, Omega", PARAMS)
def test_identities_and_9(nu, Omega):
    P = propagator(1.0, nu, Omega)
    # P11 - nu P12 = P22 (docs/theory.md section 2)
    assert abs(P[0, 0] - nu * P[0, 1] - P[1, 1]) < 1e-14 * max(1.0, abs(P).max())
    alpha, gamma = alpha_gamma(nu, Omega)
    s1, s2 = eigenvalues(nu, Omega)
    assert math.isclose(alpha, (np.exp(s1) + np.exp(s2)).real, rel_tol=1e-12, abs_tol=1e-14)
    assert math.isclose(gamma, math.exp(-nu), rel_tol=1e-14)
    assert math.isclose(np.linalg.det(P), gamma, rel_tol=1e-12)
    d = nu * nu - 4 * Omega ** 2
    if d > 0:
        assert math.isclose(alpha, 2 * math.exp(-nu / 2) * math.cosh(math.sqrt(d) / 2), rel_tol=1e-13)
    elif d < -1e-6:
        psi = math.sqrt(-d) / 2
        assert math.isclose(alpha, 2 * math.sqrt(gamma) * math.cos(psi), rel_tol=1e-12, abs_tol=1e-14)
        assert math.isclose(P[0, 1], math.sqrt(gamma) * math.sin(psi) / psi, rel_tol=1e-12, abs_tol=1e-14)


def test_propagator_minus_identity_small_t_relative_accuracy():
    """P(t) - I for tiny t has small *relative* error (no cancellation against I)."""
    nu, k2 = 4.6, 0.09
    M = np.array([[0.0, 1.0], [-k2, -nu]])
    for t in [1e-12, 1e-8, 1e-6]:
        E = propagator_minus_identity(t, nu, k2)
        taylor = M * t + M @ M * t ** 2 / 2 + M @ M @ M * t ** 3 / 6  # truncation ~ t^4
        np.testing.assert_allclose(E, taylor, rtol=1e-10)
        assert abs(E[0, 0]) < 1e-3 * t  # -k2 t^2 / 2: would be lost in round-off of P11 - 1


def test_large_stiffness_and_long_times_do_not_overflow():
    P = propagator_k2(np.array([400.0]), 50.0, 0.1)[0]
    assert np.all(np.isfinite(P))
    P = propagator_k2(np.array([1e-9]), 0.196, 1e18)[0]
    np.testing.assert_allclose(P, expm(np.array([[0, 1], [-1e18, -0.196]]) * 1e-9), rtol=1e-10, atol=1e-6)


def test_inverse_overdamped_is_unique():
    """Figure 9 and figure 1: real eigenvalues, unique inverse (docs/theory.md section 2)."""
    inv = invert_alpha_gamma(0.99, 0.01)
    assert inv.branch is None and inv.sign_P12 == 1.0
    assert math.isclose(inv.nu, 4.605170185988091, rel_tol=1e-15)
    assert math.isclose(inv.Omega, 0.3059238689620112, rel_tol=1e-12)
    a, g = alpha_gamma(inv.nu, inv.Omega)
    assert math.isclose(a, 0.99, rel_tol=1e-13) and math.isclose(g, 0.01, rel_tol=1e-13)
    P = propagator(1.0, inv.nu, inv.Omega)
    assert abs(P[0, 1] - 0.2124265) < 1e-7 and abs(P[1, 1] - 0.0058699) < 1e-7
    inv1 = invert_alpha_gamma(0.25, 0.01)
    assert math.isclose(alpha_gamma(inv1.nu, inv1.Omega)[0], 0.25, rel_tol=1e-13)


def test_inverse_underdamped_branch_is_explicit():
    nu, Omega = 0.196, 7.368
    a, g = alpha_gamma(nu, Omega)
    with pytest.raises(ValueError, match="branch"):
        invert_alpha_gamma(a, g)
    psis = underdamped_branches(a, g, 6)
    psi_true = math.sqrt(4 * Omega ** 2 - nu ** 2) / 2
    k = int(np.argmin(np.abs(np.array(psis) - psi_true)))
    assert abs(psis[k] - psi_true) < 1e-10 and psis[k] > 2 * math.pi  # 2 pi + psi0
    signs = set()
    for b in range(6):
        inv = invert_alpha_gamma(a, g, branch=b)
        # every branch reproduces (alpha, gamma) ...
        a2, g2 = alpha_gamma(inv.nu, inv.Omega)
        assert math.isclose(a2, a, rel_tol=1e-10, abs_tol=1e-12) and math.isclose(g2, g, rel_tol=1e-12)
        # ... and sign_P12 is the sign of P12 (= c1) on that branch
        assert np.sign(propagator(1.0, inv.nu, inv.Omega)[0, 1]) == inv.sign_P12
        signs.add(inv.sign_P12)
    assert signs == {1.0, -1.0}  # the ambiguity is real: c1 differs between branches
    inv = invert_alpha_gamma(a, g, branch=k)
    assert math.isclose(inv.Omega, Omega, rel_tol=1e-12)
