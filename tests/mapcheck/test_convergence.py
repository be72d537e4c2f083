"""Convergence order of the near-grazing maps against the exact pre-impact map.

With (u, v, sigma) = eps (a, b, c) the error of each map against the exact
stroboscopic map of the ODE (closed form, docs/theory.md section 3) must fall like
eps^1.5: the maps keep all terms through O(eps) (x ~ eps, sqrt(x) ~ eps^0.5).
The slope is fitted over four decades of eps.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from mapcheck import coefficients
from mapcheck.exact import ExactOscillator
from mapcheck.maps import natural_map, physical_map, to_natural

FIG9 = (4.605170185988091, 0.3059238689620112)
UNDER = (0.196, 7.368)
MID = (0.5, 1.0)
EPS = np.logspace(-2, -6, 5)
DIRECTIONS = [(1.0, 0.0, 0.0), (1.0, 1.0, 1.0), (0.5, -1.0, 0.3)]


def errors(par, r, exact_wall, map_wall, direction, eps_list, *, Gamma=10.0, kappa_of_eps=None,
           variant="paper", delay=False, coeffs=None):
    """Errors (physical map, natural map) against the exact map, one row per eps."""
    nu, Om = par
    c = coeffs or coefficients(nu, Om, r, map_wall)
    out = []
    for eps in eps_list:
        a, b, cc = direction
        u, v, s = eps * a, eps * b, eps * cc
        kappa = None
        if kappa_of_eps is not None:
            kappa = kappa_of_eps(eps)
            Gamma = (kappa / Om) ** 2
        osc = ExactOscillator(nu, Om, s, r=r, Gamma=Gamma, wall=exact_wall)
        ue, ve, k = osc.pre_impact_map(u, v)
        assert k == 1  # exactly one impact / wall entry near t = 0
        um, vm = physical_map(u, v, s, c, variant, kappa=kappa if delay else None)
        x, y = to_natural(u, v, s, c, variant)
        xm, ym = natural_map(x, y, c.rho(s, variant), c)
        xe, ye = to_natural(ue, ve, s, c, variant)
        # natural coordinates measured in units of chi (x = l chi)
        out.append((max(abs(um - ue), abs(vm - ve)), max(abs(xm - xe), abs(ym - ye)) / c.l))
    return np.array(out)


def slopes(err, eps_list=EPS):
    return np.polyfit(np.log(eps_list), np.log(err), 1)[0]


@pytest.mark.parametrize("par", [FIG9, UNDER, MID])
@pytest.mark.parametrize("direction", DIRECTIONS)
def test_rigid_wall_map_order_1p5(par, direction):
    """(31)/(32) and (37)/(38) with (39) against the rigid-wall ODE."""
    s = slopes(errors(par, 0.9, "rigid", "rigid", direction, EPS))
    assert np.all(np.abs(s - 1.5) < 0.1), s


@pytest.mark.parametrize("par", [FIG9, UNDER, MID])
@pytest.mark.parametrize("direction", DIRECTIONS)
def test_compliant_low_velocity_map_order_1p5(par, direction):
    """(37)/(38) with (48) (r -> -r) against the compliant-wall ODE at fixed Gamma = 10
    (beta ~ sqrt(eps) -> 0: low-velocity impacts)."""
    s = slopes(errors(par, 0.9, "compliant", "compliant", direction, EPS))
    assert np.all(np.abs(s - 1.5) < 0.1), s


@pytest.mark.parametrize("par", [FIG9, UNDER])
def test_high_velocity_compliant_map_order_1p5(par):
    """Section 6.2: with kappa = eps^-1.5 (beta ~ eps^-1) the rigid map (39) is accurate to
    O(eps^1.5) for a compliant wall; with kappa = eps^-1 the delay pi/kappa costs the order
    (error ~ eps), and the delay correction of docs/theory.md section 5 restores it."""
    eps = np.logspace(-2, -5, 4)
    d = (1.0, 0.5, 0.5)
    s_hi = slopes(errors(par, 0.9, "compliant", "compliant-high", d, eps, kappa_of_eps=lambda e: e ** -1.5), eps)
    assert np.all(np.abs(s_hi - 1.5) < 0.12), s_hi
    e_lo = errors(par, 0.9, "compliant", "compliant-high", d, eps, kappa_of_eps=lambda e: e ** -1.0)
    e_cor = errors(par, 0.9, "compliant", "compliant-high", d, eps, kappa_of_eps=lambda e: e ** -1.0, delay=True)
    s_lo, s_cor = slopes(e_lo, eps), slopes(e_cor, eps)
    assert np.all(np.abs(s_lo - 1.0) < 0.15), s_lo
    assert s_cor[0] > 1.35, s_cor  # physical map with the delay correction
    assert e_cor[-1, 0] < 0.05 * e_lo[-1, 0]


@pytest.mark.parametrize("wall", ["rigid", "compliant"])
def test_tilde_variant_order_1p5(wall):
    """The A~(sigma) variant changes only higher-order terms: still O(eps^1.5)."""
    s = slopes(errors(UNDER, 0.9, wall, wall, (1.0, 1.0, 1.0), EPS, variant="tilde"))
    assert np.all(np.abs(s - 1.5) < 0.1), s


def test_order_test_detects_the_ocr_reading_of_c3():
    """Sensitivity check: with the OCR reading c3 = (1+2r) gamma - (1+r)^2 P22^2 (not P22^3,
    docs/theory.md section 4) the natural map is only O(eps) accurate where P22 is not small."""
    c = coefficients(*UNDER, 0.9, "rigid")
    P22 = c.P[1, 1]
    wrong = dataclasses.replace(c, c3=(1 + 2 * c.r_eff) * c.gamma - (1 + c.r_eff) ** 2 * P22 ** 2)
    s = slopes(errors(UNDER, 0.9, "rigid", "rigid", (1.0, 0.0, 0.0), EPS, coeffs=wrong))
    assert abs(s[1] - 1.0) < 0.1, s
