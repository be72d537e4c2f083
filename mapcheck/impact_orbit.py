"""The one-impact period-1 orbit of the rigid wall in closed form, with its multipliers.

The classical solution (Shaw & Holmes 1983): an orbit that hits the wall u = 0 once per forcing
period, at phase phi with velocity v > 0 (rebounding with -r v), follows the free flow (8)
z(t) = P(t - t0) [z(t0) - p(t0)] + p(t) for one whole period between impacts.  Periodicity,
(0, v) = P(1) [(0, -r v) - p(phi)] + p(phi), is linear in v and p(phi):

    p(phi) = v c,    c = (I - P(1))^-1 (I + r P(1)) e2,

and p(phi) = ((1 + sigma) cos 2 pi phi - 1, -2 pi (1 + sigma) sin 2 pi phi) gives, for every v,

    1 + sigma = sqrt((1 + c1 v)^2 + (c2 v / (2 pi))^2),    tan 2 pi phi = -(c2 v / 2 pi) / (1 + c1 v).

So sigma(v) is analytic in the impact velocity, sigma(0) = 0: the branch reaches the graze at
sigma = 0 exactly, with v linear in sigma (v ~ sigma / c1) unless c1 = 0.  The multipliers are
those of the impact map (phi, v) -> (phi', v') (conjugate to the stroboscopic map's while the orbit
has one impact per period), its Jacobian from the implicit function theorem on u(phi') = 0.  A
fold is where d sigma / d v = 0 (a multiplier +1), a flip where det(J + I) = 0.

Nothing here uses the FMU, the harness or :mod:`mapcheck.exact`: it is the third route to the
numbers those two compute (tests/mapcheck/test_impact_orbit.py checks it against the exact flow).
The orbit is physical only where its free flight stays off the wall between impacts; callers
check that (on the exact flow) where it matters.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .linear import propagator
from .segments import brentq

__all__ = ["OneImpactOrbit", "one_impact_orbit", "sigma_of_v", "fold_velocity", "flip_velocities"]

TWO_PI = 2.0 * math.pi


def _c(nu: float, Omega: float, r: float) -> np.ndarray:
    P = np.asarray(propagator(1.0, nu, Omega), dtype=float)
    return np.linalg.solve(np.eye(2) - P, (np.eye(2) + r * P) @ np.array([0.0, 1.0]))


def sigma_of_v(nu: float, Omega: float, r: float, v: float) -> float:
    """sigma of the one-impact period-1 orbit with pre-impact velocity ``v``."""
    c = _c(nu, Omega, r)
    return math.hypot(1.0 + c[0] * v, c[1] * v / TWO_PI) - 1.0


@dataclass(frozen=True)
class OneImpactOrbit:
    """The orbit with impact velocity ``v``: its sigma, impact phase, multipliers and the state
    just before the impact (0, v) at t = phi."""

    v: float
    sigma: float
    phi: float
    multipliers: np.ndarray
    jacobian: np.ndarray


def one_impact_orbit(nu: float, Omega: float, r: float, v: float) -> OneImpactOrbit:
    """The one-impact period-1 orbit with pre-impact velocity ``v`` (any v; physical for v > 0
    where its flight stays off the wall)."""
    c = _c(nu, Omega, r)
    x, y = 1.0 + c[0] * v, -c[1] * v / TWO_PI
    sigma = math.hypot(x, y) - 1.0
    phi = math.atan2(y, x) / TWO_PI
    J = _impact_map_jacobian(nu, Omega, r, sigma, phi, v)
    return OneImpactOrbit(v, sigma, phi, np.linalg.eigvals(J), J)


def _impact_map_jacobian(nu: float, Omega: float, r: float, sigma: float, phi: float, v: float) -> np.ndarray:
    """d(phi', v')/d(phi, v) of the impact map at the fixed point (phi' = phi + 1, v' = v)."""
    A = np.array([[0.0, 1.0], [-Omega * Omega, -nu]])
    amp = 1.0 + sigma

    def p(t: float) -> np.ndarray:
        return np.array([amp * math.cos(TWO_PI * t) - 1.0, -TWO_PI * amp * math.sin(TWO_PI * t)])

    def pdot(t: float) -> np.ndarray:
        return np.array([-TWO_PI * amp * math.sin(TWO_PI * t), -TWO_PI ** 2 * amp * math.cos(TWO_PI * t)])

    P = np.asarray(propagator(1.0, nu, Omega), dtype=float)
    z_plus = np.array([0.0, -r * v])
    dev = z_plus - p(phi)
    dy_dv = P @ np.array([0.0, -r])
    dy_dphi = -A @ P @ dev - P @ pdot(phi)
    # at the next impact t' = phi + 1: the state (0, v), its velocity and acceleration
    y1 = P @ dev + p(phi + 1.0)
    ydot = A @ (y1 - p(phi + 1.0)) + pdot(phi + 1.0)
    out = np.empty((2, 2))
    for j, d in enumerate((dy_dphi, dy_dv)):
        dphi1 = -d[0] / ydot[0]
        out[0, j] = dphi1
        out[1, j] = d[1] + ydot[1] * dphi1
    return out


def fold_velocity(nu: float, Omega: float, r: float, v_lo: float, v_hi: float) -> float:
    """The impact velocity of the fold (d sigma / d v = 0) between ``v_lo`` and ``v_hi``."""
    c = _c(nu, Omega, r)
    k = c[1] / TWO_PI
    # d/dv of (1 + c1 v)^2 + (k v)^2 is 2 c1 (1 + c1 v) + 2 k^2 v: zero at v = -c1 / (c1^2 + k^2)
    v = -c[0] / (c[0] ** 2 + k * k)
    if not min(v_lo, v_hi) <= v <= max(v_lo, v_hi):
        raise ValueError(f"no fold for v in [{v_lo:g}, {v_hi:g}] (d sigma/dv = 0 at v = {v:g})")
    return float(v)


def flip_velocities(nu: float, Omega: float, r: float, v_lo: float, v_hi: float, n: int = 400) -> list[float]:
    """Impact velocities in [v_lo, v_hi] where a multiplier is -1 (det(J + I) = 0), each to rounding."""

    def g(v: float) -> float:
        return float(np.linalg.det(one_impact_orbit(nu, Omega, r, v).jacobian + np.eye(2)))

    vs = np.linspace(v_lo, v_hi, n + 1)
    gs = [g(v) for v in vs]
    return [brentq(g, vs[i], vs[i + 1], xtol=1e-15, rtol=1e-15)
            for i in range(n) if gs[i] * gs[i + 1] < 0]
