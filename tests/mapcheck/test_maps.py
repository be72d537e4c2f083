"""Identities and limits of the maps and coefficients (39), (48), (1)/(2), (54)-(56)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from mapcheck import coefficients
from mapcheck.coeffs import A_GRAZING, grazing_acceleration
from mapcheck.exact import ExactOscillator
from mapcheck.linear import propagator
from mapcheck.maps import (
    chi,
    damped_1d_map,
    from_natural,
    local_impact_map,
    natural_map,
    nordmark_map,
    physical_map,
    piecewise_map,
    rho_1d,
    to_natural,
)

FIG9 = (4.605170185988091, 0.3059238689620112)
UNDER = (0.196, 7.368)
RNG = np.random.default_rng(1)


def test_r_minus_one_is_identity():
    """r_eff = -1 (elastic low-velocity compliant impact, r = 1): L is the identity (section 6.1)."""
    u = RNG.uniform(-1e-2, 1e-2, 200)
    v = RNG.uniform(-1e-1, 1e-1, 200)
    ut, vt = local_impact_map(u, v, 0.7, -1.0)
    np.testing.assert_array_equal(ut, u)
    np.testing.assert_array_equal(vt, v)
    assert np.any(chi(u, v) > 0)  # impacting states were among them


def test_local_map_is_identity_without_impact():
    u = -RNG.uniform(1e-4, 1e-2, 50)
    v = 1e-3 * RNG.standard_normal(50)
    v = np.where(v * v - 2 * A_GRAZING * u < 0, v, 0.0)
    ut, vt = local_impact_map(u, v, 0.7, 0.9)
    np.testing.assert_array_equal(ut, u)
    np.testing.assert_array_equal(vt, v)


@pytest.mark.parametrize("par", [FIG9, UNDER, (0.5, 1.0)])
@pytest.mark.parametrize("wall", ["rigid", "compliant"])
def test_coefficients_match_39_and_48(par, wall):
    r = 0.9
    c = coefficients(*par, r, wall)
    P = propagator(1.0, *par)
    re = r if wall == "rigid" else -r
    P12, P22 = P[0, 1], P[1, 1]
    assert c.r_eff == re
    np.testing.assert_array_equal(c.P, P)
    assert math.isclose(c.alpha, np.trace(P), rel_tol=1e-14)
    assert math.isclose(c.gamma, math.exp(-par[0]), rel_tol=1e-14)
    assert c.c1 == np.sign(P12)
    assert math.isclose(c.c2, c.alpha - 2 * (1 + re) * P22 + (1 + re) ** 2 * P22 ** 2, rel_tol=1e-14)
    assert math.isclose(c.c3, (1 + 2 * re) * c.gamma - (1 + re) ** 2 * P22 ** 3, rel_tol=1e-12, abs_tol=1e-16)
    assert math.isclose(c.l, 1 / (4 * A_GRAZING ** 2 * (1 + re) ** 2 * P12 ** 2), rel_tol=1e-14)
    assert math.isclose(c.rho_per_sigma,
                        (1 - c.alpha + c.gamma) / (2 * abs(A_GRAZING) * (1 + re) ** 2 * P12 ** 2), rel_tol=1e-14)


def test_compliant_rescales_rho_by_361():
    """Section 6.1/6.3: rho rescales by (1+r)^2/(1-r)^2 = 361 at r = 0.9."""
    cr, cc = coefficients(*FIG9, 0.9, "rigid"), coefficients(*FIG9, 0.9, "compliant")
    assert math.isclose(cc.rho_per_sigma / cr.rho_per_sigma, 361.0, rel_tol=1e-12)


def test_nordmark_impact_branch_determinant():
    """(2): the impact branch has Jacobian determinant r^2 gamma (finite differences)."""
    alpha, gamma, r = 0.4, 0.3, 0.8
    x, y, h = 0.37, -0.2, 1e-6
    f = lambda x_, y_: np.array(nordmark_map(x_, y_, 0.1, alpha, gamma, r))
    J = np.column_stack([(f(x + h, y) - f(x - h, y)) / (2 * h), (f(x, y + h) - f(x, y - h)) / (2 * h)])
    assert math.isclose(np.linalg.det(J), r * r * gamma, rel_tol=1e-8)
    # the non-impacting branch (1) has determinant gamma
    J0 = np.column_stack([(f(-x + h, y) - f(-x - h, y)) / (2 * h), (f(-x, y + h) - f(-x, y - h)) / (2 * h)])
    assert math.isclose(np.linalg.det(J0), gamma, rel_tol=1e-8)


@pytest.mark.parametrize("wall", ["rigid", "compliant"])
def test_exact_map_across_one_impact_has_determinant_r2_gamma(wall):
    """The independent reason for Nordmark's r^2 gamma: the exact pre-impact map across one
    impact (closed-form ODE) has Jacobian determinant r^2 e^{-nu} (docs/theory.md section 6)."""
    nu, Om = UNDER
    r = 0.7
    osc = ExactOscillator(nu, Om, 0.0, r=r, Gamma=50.0, wall=wall)
    u0, v0, h = 2e-3, 1e-3, 1e-7
    cols = []
    for du, dv in [(h, 0), (0, h)]:
        up, vp, kp = osc.pre_impact_map(u0 + du, v0 + dv)
        um, vm, km = osc.pre_impact_map(u0 - du, v0 - dv)
        assert kp == km == 1
        cols.append([(up - um) / (2 * h), (vp - vm) / (2 * h)])
    det = np.linalg.det(np.array(cols, dtype=float).T)
    assert math.isclose(det, r * r * math.exp(-nu), rel_tol=1e-5)


def test_damped_1d_map_is_large_nu_limit_of_48():
    """(54)-(56) is the nu >> 1 limit of (37)/(38) with (48): alpha -> 1, gamma -> 0, c2 -> 1,
    c3 -> 0, and rho of (48) -> rho of (56); the deviations shrink like 1/nu."""
    Om, r = 0.3, 0.9
    devs = []
    for nu in [10.0, 100.0, 1000.0]:
        c = coefficients(nu, Om, r, "compliant")
        rho56 = float(rho_1d(1.0, nu, Om, -r))
        devs.append(max(abs(c.alpha - 1), abs(c.gamma), abs(c.c2 - 1), abs(c.c3),
                        abs(c.rho_per_sigma / rho56 - 1), abs(nu * c.P[0, 1] - 1)))
        assert c.c1 == 1.0
    devs = np.array(devs)
    assert devs[-1] < 1e-2
    assert np.all(devs[1:] / devs[:-1] < 0.15)  # ~ 1/nu per decade
    # and the maps themselves: the 2D map with these limits equals the 1D map
    x = np.linspace(-0.5, 0.5, 11)
    xn, yn = piecewise_map(x, 0.0, 0.1, 1.0, 0.0, 1.0, 1.0, 0.0)
    np.testing.assert_allclose(xn, damped_1d_map(x, 0.1), rtol=0, atol=1e-15)
    np.testing.assert_array_equal(yn, 0.0)


@pytest.mark.parametrize("variant", ["paper", "tilde"])
def test_natural_coordinates_round_trip(variant):
    c = coefficients(*UNDER, 0.9, "rigid")
    u = RNG.uniform(-1e-3, 1e-3, 100)
    v = RNG.uniform(-1e-2, 1e-2, 100)
    s = RNG.uniform(-0.3, 0.3, 100)
    x, y = to_natural(u, v, s, c, variant)
    u2, v2 = from_natural(x, y, s, c, variant)
    np.testing.assert_allclose(u2, u, rtol=0, atol=1e-15)
    np.testing.assert_allclose(v2, v, rtol=0, atol=1e-15)
    # the paper's linear inverse of (33) differs by the v^2 term only
    A = grazing_acceleration(s, c.Omega, variant)
    u3, _ = from_natural(x, y, s, c, variant, exact=False)
    np.testing.assert_allclose(u3 - u, -v * v / (2 * A), rtol=1e-9, atol=1e-18)


def test_natural_map_linear_branch_gives_y_next_minus_gamma_x():
    """(37): y_{n+1} = -gamma x_n, from the definitions (33)/(34) and the exact linear map."""
    for par in [FIG9, UNDER]:
        c = coefficients(*par, 0.9, "rigid")
        u = -RNG.uniform(1e-5, 1e-4, 20)
        v = RNG.uniform(-1e-6, 1e-6, 20)
        s = 1e-5
        un, vn = physical_map(u, v, s, c)  # chi < 0: the exact free map (32)
        x, y = to_natural(u, v, s, c)
        xn, yn = to_natural(un, vn, s, c)
        xm, ym = natural_map(x, y, c.rho(s), c)
        scale = np.abs(x).max()
        # v^2 terms make the natural map exact only to O(chi^2 / chi) relative
        assert np.max(np.abs(ym - yn)) < 1e-3 * scale
        assert np.max(np.abs(xm - xn)) < 1e-3 * scale


def test_maps_are_vectorized_over_states_and_parameters():
    c = coefficients(*FIG9, 0.9, "compliant")
    u = RNG.uniform(-1e-3, 1e-3, (4, 5))
    v = RNG.uniform(-1e-2, 1e-2, (4, 5))
    s = np.linspace(-0.1, 0.3, 5)
    U, V = physical_map(u, v, s, c, "tilde")
    for i in range(4):
        for j in range(5):
            uu, vv = physical_map(u[i, j], v[i, j], s[j], c, "tilde")
            assert U[i, j] == uu and V[i, j] == vv
    X, Y = natural_map(u, v, c.rho(s, "tilde"), c)
    assert X.shape == (4, 5) and Y.shape == (4, 5)


def test_tilde_rho_and_its_inverse():
    c = coefficients(*FIG9, 0.9, "compliant")
    s = np.linspace(-0.5, 2.0, 26)
    rt = c.rho(s, "tilde")
    At = (1 + s) * A_GRAZING + s * c.Omega ** 2
    np.testing.assert_allclose(rt, (1 - c.alpha + c.gamma) * s / (2 * np.abs(At) * (1 + c.r_eff) ** 2 * c.P[0, 1] ** 2),
                               rtol=1e-13, atol=1e-16)
    np.testing.assert_allclose(c.sigma_of_rho(rt, "tilde"), s, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(c.sigma_of_rho(c.rho(s)), s, rtol=1e-12, atol=1e-14)
