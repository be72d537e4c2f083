"""The paper's near-grazing maps, each a plain vectorized function of numpy arrays.

Equation numbers refer to Molenaar, de Weger & van de Water, Nonlinearity 14 (2001)
301, as read and corrected in docs/theory.md.  All state and parameter arguments
broadcast against each other, so one call maps many orbits or parameter values.

Conventions
-----------
* Physical state (u, v) is the *pre-impact* ("virtual") state at t = n (figure 3;
  docs/theory.md section 3).
* ``r_eff`` is the restitution entering the formulas: r for a rigid wall (11), -r
  for low-velocity impacts at a compliant wall (46)-(48).
* ``variant="tilde"`` replaces A = -4 pi^2 (15) by A~(sigma) = (1+sigma) A + sigma Omega^2
  in chi, l and rho (section 6; docs/theory.md section 7, item 3).
"""
from __future__ import annotations

import numpy as np

from .coeffs import A_GRAZING, Coefficients, grazing_acceleration

__all__ = [
    "chi",
    "local_impact_map",
    "local_impact_map_delay",
    "physical_map",
    "to_natural",
    "from_natural",
    "natural_map",
    "piecewise_map",
    "nordmark_map",
    "damped_1d_map",
    "rho_1d",
]


def chi(u, v, A=A_GRAZING):
    """chi_n = v_n^2 - 2 A u_n, equation (14); an impact occurs near t = n iff chi > 0."""
    return np.asarray(v) ** 2 - 2.0 * np.asarray(A) * np.asarray(u)


def local_impact_map(u, v, nu: float, r_eff: float, A=A_GRAZING):
    """Local impact map L, equations (26)-(30) (compliant low velocity: (46)/(47), r_eff = -r).

    For chi >= 0::

        u~ = -(1 + 2r) u - (1/A)(1 + r) v (sqrt(chi) - v)        (26), sign as in docs/theory.md section 7
        v~ = v - (1 + r)(sqrt(chi) - 2 nu u)                      (27)

    and L is the identity for chi < 0 (no impact).

    Parameters
    ----------
    u, v : array_like
        Pre-impact state at t = n.
    nu : float
        Damping.
    r_eff : float
        r (rigid wall) or -r (compliant wall, low velocity).
    A : float or array_like
        Grazing acceleration, -4 pi^2 (15) or A~(sigma).

    Returns
    -------
    (ndarray, ndarray)
        Post-impact virtual state (u~, v~) at t = n.
    """
    u = np.asarray(u, dtype=float)
    v = np.asarray(v, dtype=float)
    c = chi(u, v, A)
    imp = c >= 0.0
    sq = np.sqrt(np.where(imp, c, 0.0))
    one = 1.0 + r_eff
    ut = -(1.0 + 2.0 * r_eff) * u - one * v * (sq - v) / A
    vt = v - one * (sq - 2.0 * nu * u)
    return np.where(imp, ut, u), np.where(imp, vt, v)


def local_impact_map_delay(u, v, nu: float, r: float, kappa: float, A=A_GRAZING):
    """Rigid-wall local map (26)/(27) plus the impact-delay correction for high-velocity
    impacts at a compliant wall (section 6.2, docs/theory.md section 5).

    The mass leaves the wall Delta t later than a rigid-wall impact would, with Delta t
    from (42): (2/kappa) arctan(beta), beta = r v_c kappa / |A| (43), v_c = sqrt(chi).
    Shifting the outgoing parabola by Delta t gives, to first order in Delta t::

        v~ += |A| Delta t,        u~ += Delta t ((1 + r) sqrt(chi) - v)

    Without the correction the rigid map is accurate to o(eps) only if kappa >> 1/eps.

    Returns
    -------
    (ndarray, ndarray)
    """
    u = np.asarray(u, dtype=float)
    v = np.asarray(v, dtype=float)
    ut, vt = local_impact_map(u, v, nu, r, A)
    c = chi(u, v, A)
    imp = c >= 0.0
    sq = np.sqrt(np.where(imp, c, 0.0))
    absA = np.abs(A)
    dt = (2.0 / kappa) * np.arctan(r * sq * kappa / absA)
    ut = ut + np.where(imp, dt * ((1.0 + r) * sq - v), 0.0)
    vt = vt + np.where(imp, absA * dt, 0.0)
    return ut, vt


def physical_map(u, v, sigma, c: Coefficients, variant: str = "paper", kappa: float | None = None):
    """Near-grazing map in physical coordinates, (31)/(32)::

        u_{n+1} = P L(u_n) + sigma (I - P) e1

    with L the local impact map (identity if chi_n < 0).

    Parameters
    ----------
    u, v, sigma : array_like
        Pre-impact state at t = n and the forcing parameter (5).
    c : Coefficients
        From :func:`mapcheck.coefficients`; supplies P = P(1), nu and r_eff.
    variant : {"paper", "tilde"}
        Grazing acceleration A or A~(sigma) in chi and L.
    kappa : float, optional
        If given, add the high-velocity delay correction (:func:`local_impact_map_delay`);
        only meaningful with a rigid-wall ``c`` (r_eff = r).

    Returns
    -------
    (ndarray, ndarray)
        (u_{n+1}, v_{n+1}).
    """
    sigma = np.asarray(sigma, dtype=float)
    A = grazing_acceleration(sigma, c.Omega, variant)
    if kappa is None:
        ut, vt = local_impact_map(u, v, c.nu, c.r_eff, A)
    else:
        ut, vt = local_impact_map_delay(u, v, c.nu, c.r_eff, kappa, A)
    P = c.P
    un = P[0, 0] * ut + P[0, 1] * vt + sigma * (1.0 - P[0, 0])
    vn = P[1, 0] * ut + P[1, 1] * vt - sigma * P[1, 0]
    return un, vn


def _A_and_l(sigma, c: Coefficients, variant: str):
    A = grazing_acceleration(sigma, c.Omega, variant)
    return A, c.l_of(A)


def to_natural(u, v, sigma, c: Coefficients, variant: str = "paper"):
    """Natural coordinates, (33)/(34), with l from (36)::

        x = l chi,   chi = v^2 - 2 A u (including v^2)
        y = -l [P22 chi + 2 A P12 v + 2 A sigma (P22 - gamma)]

    Returns
    -------
    (ndarray, ndarray)
    """
    sigma = np.asarray(sigma, dtype=float)
    A, l = _A_and_l(sigma, c, variant)
    ch = chi(u, v, A)
    P12, P22 = c.P[0, 1], c.P[1, 1]
    x = l * ch
    y = -l * (P22 * ch + 2.0 * A * P12 * np.asarray(v) + 2.0 * A * sigma * (P22 - c.gamma))
    return x, y


def from_natural(x, y, sigma, c: Coefficients, variant: str = "paper", exact: bool = True):
    """Inverse of (33)/(34), equation (35)::

        v = -[y + P22 x + 2 A l sigma (P22 - gamma)] / (2 l A P12)
        u = (v^2 - x/l) / (2A)          (exact inverse of (33); default)
        u = -x / (2 A l)                (the paper's linear inverse, ``exact=False``)

    Returns
    -------
    (ndarray, ndarray)
    """
    sigma = np.asarray(sigma, dtype=float)
    x = np.asarray(x, dtype=float)
    A, l = _A_and_l(sigma, c, variant)
    P12, P22 = c.P[0, 1], c.P[1, 1]
    v = -(np.asarray(y) + P22 * x + 2.0 * A * l * sigma * (P22 - c.gamma)) / (2.0 * l * A * P12)
    u = (v * v - x / l) / (2.0 * A) if exact else -x / (2.0 * A * l)
    return u, v


def piecewise_map(x, y, rho, alpha, gamma, c1, c2, c3):
    """The generic square-root map, (37)/(38)::

        x < 0:   x' = alpha x + y + rho,                  y' = -gamma x
        x >= 0:  x' = -c1 sqrt(x) + c2 x + y + rho,       y' = c3 x

    It contains the Nordmark map (1)/(2) (c1 = 1, c2 = 0, c3 = -r^2 gamma) and the
    1D map (54)/(55) (alpha = 1, gamma = 0, c1 = 1, c2 = 1, c3 = 0, y = 0).  Both
    branches agree at x = 0, so the side on which x = 0 is counted is immaterial.
    """
    x = np.asarray(x, dtype=float)
    imp = x >= 0.0
    sq = np.sqrt(np.where(imp, x, 0.0))
    xn = np.where(imp, -c1 * sq + c2 * x, alpha * x) + y + rho
    yn = np.where(imp, c3, -gamma) * x
    return xn, yn


def natural_map(x, y, rho, c: Coefficients):
    """Map (37)/(38) with the coefficients of ``c``: (39) rigid, (48) compliant low velocity.

    ``rho`` is the bifurcation parameter: ``c.rho(sigma)`` or ``c.rho(sigma, "tilde")``
    for the A~(sigma) variant (only rho changes in natural coordinates).
    """
    return piecewise_map(x, y, rho, c.alpha, c.gamma, c.c1, c.c2, c.c3)


def nordmark_map(x, y, rho, alpha: float, gamma: float, r: float):
    """Nordmark map, equations (1)/(2)::

        x <= 0:  x' = alpha x + y + rho,    y' = -gamma x
        x > 0:   x' = -sqrt(x) + y + rho,   y' = -r^2 gamma x

    The impact branch has Jacobian determinant r^2 gamma (docs/theory.md section 6).
    """
    return piecewise_map(x, y, rho, alpha, gamma, 1.0, 0.0, -r * r * gamma)


def damped_1d_map(x, rho):
    """Strongly damped 1D map, equations (54)/(55)::

        x < 0:   x' = x + rho
        x >= 0:  x' = -sqrt(x) + x + rho
    """
    x = np.asarray(x, dtype=float)
    return x + rho - np.sqrt(np.maximum(x, 0.0))


def rho_1d(sigma, nu: float, Omega: float, r_eff: float, A=A_GRAZING):
    """rho of the 1D map, equation (56) (written for the compliant wall, r_eff = -r)::

        rho = nu Omega^2 sigma / (2 |A| (1 + r_eff)^2)

    It is the nu >> 1 limit of (48): 1 - alpha + gamma ~ Omega^2/nu, P12 ~ 1/nu.
    """
    return nu * Omega ** 2 * np.asarray(sigma, dtype=float) / (2.0 * np.abs(A) * (1.0 + r_eff) ** 2)
