"""Map coefficients (39) and (48), the length scale l (36), and the grazing acceleration.

``coefficients(nu, Omega, r, wall)`` is an interface used by outside scripts: keep
the name and the attributes ``alpha, gamma, P, c1, c2, c3, l, rho_per_sigma``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .linear import propagator

__all__ = [
    "A_GRAZING",
    "grazing_acceleration",
    "effective_r",
    "Coefficients",
    "coefficients",
]

A_GRAZING = -4.0 * math.pi ** 2
"""A = -4 pi^2, equation (15): the acceleration of p(t) at t = n for sigma = 0."""


def grazing_acceleration(sigma, Omega: float, variant: str = "paper"):
    """Acceleration at u = v = 0, t = n used in chi, l and rho.

    Parameters
    ----------
    sigma : float or array_like
    Omega : float
    variant : {"paper", "tilde"}
        ``"paper"``: A = -4 pi^2 (15), as in the paper's maps.
        ``"tilde"``: A~(sigma) = (1 + sigma) A + sigma Omega^2 (section 6, below (43));
        equals A_n of (19) at u = v = 0.

    Returns
    -------
    float or ndarray
    """
    if variant == "paper":
        if np.ndim(sigma):
            return np.full(np.shape(sigma), A_GRAZING)
        return A_GRAZING
    if variant == "tilde":
        return (1.0 + np.asarray(sigma, dtype=float)) * A_GRAZING + np.asarray(sigma, dtype=float) * Omega ** 2
    raise ValueError(f"variant must be 'paper' or 'tilde', not {variant!r}")


def effective_r(r: float, wall: str) -> float:
    """Restitution entering the maps: r for the rigid wall (11), -r for low-velocity
    impacts at a compliant wall (section 6.1: (46)-(48) follow from (28)-(30), (39) by r -> -r).

    High-velocity compliant impacts use the rigid-wall map ((39), section 6.2): pass
    ``wall="rigid"`` (or "compliant-high") for them.
    """
    if wall in ("rigid", "compliant-high"):
        return r
    if wall in ("compliant", "compliant-low"):
        return -r
    raise ValueError(f"wall must be 'rigid', 'compliant' (low velocity) or 'compliant-high', not {wall!r}")


@dataclass(frozen=True)
class Coefficients:
    """Coefficients of the near-grazing map in natural coordinates, (37)-(39) / (48).

    Attributes
    ----------
    nu, Omega, r : float
        Oscillator parameters; ``r`` as given (physical restitution).
    wall : str
        "rigid" (39) or "compliant" (48, low velocity) or "compliant-high" (39).
    r_eff : float
        r for (39), -r for (48).
    alpha, gamma : float
        Tr P(1) and det P(1), equation (9).
    P : ndarray, shape (2, 2)
        Free propagator P(1), equation (7).
    c1, c2, c3 : float
        c1 = sign(P12), c2 = alpha - 2(1+r)P22 + (1+r)^2 P22^2,
        c3 = (1+2r) gamma - (1+r)^2 P22^3 (with r -> r_eff; P22^3 as CORRECTED in
        docs/theory.md section 7).
    l : float
        Length scale (36): 1 / (4 A^2 (1+r_eff)^2 P12^2), with A = -4 pi^2.
    rho_per_sigma : float
        rho / sigma = (1 - alpha + gamma) / (2 |A| (1+r_eff)^2 P12^2), (39)/(48).
    """

    nu: float
    Omega: float
    r: float
    wall: str
    r_eff: float
    alpha: float
    gamma: float
    P: np.ndarray = field(repr=False)
    c1: float
    c2: float
    c3: float
    l: float
    rho_per_sigma: float

    def rho(self, sigma, variant: str = "paper"):
        """Bifurcation parameter rho(sigma).

        ``"paper"``: rho = rho_per_sigma * sigma (39)/(48).  ``"tilde"``: |A| replaced
        by |A~(sigma)| (section 6), rho = (1 - alpha + gamma) sigma / (2 |A~| (1+r)^2 P12^2).
        """
        sigma = np.asarray(sigma, dtype=float)
        if variant == "paper":
            return self.rho_per_sigma * sigma
        At = grazing_acceleration(sigma, self.Omega, "tilde")
        return self.rho_per_sigma * sigma * abs(A_GRAZING) / np.abs(At)

    def sigma_of_rho(self, rho, variant: str = "paper"):
        """Inverse of :meth:`rho` (closed form: rho is a Moebius function of sigma)."""
        rho = np.asarray(rho, dtype=float)
        if variant == "paper":
            return rho / self.rho_per_sigma
        # rho = k sigma |A| / (|A| + sigma (|A| - Omega^2)) for sigma > -1
        k, a, b = self.rho_per_sigma, abs(A_GRAZING), abs(A_GRAZING) - self.Omega ** 2
        # rho~ increases to k a / b as sigma -> inf: larger rho has no sigma (inf returned)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(rho * b >= k * a, np.inf, rho * a / (k * a - rho * b))

    def l_of(self, A) -> np.ndarray:
        """l of (36) for a given grazing acceleration A (e.g. A~(sigma))."""
        return 1.0 / (4.0 * np.asarray(A) ** 2 * (1.0 + self.r_eff) ** 2 * self.P[0, 1] ** 2)


def coefficients(nu: float, Omega: float, r: float, wall: str = "rigid") -> Coefficients:
    """Coefficients of the map (37)/(38): (39) for ``wall="rigid"``, (48) for ``"compliant"``.

    Parameters
    ----------
    nu, Omega : float
        Damping and natural frequency (3).
    r : float
        Restitution coefficient (physical, 0 < r <= 1).
    wall : {"rigid", "compliant", "compliant-high"}
        "compliant" means low-velocity impacts at a compliant wall (48): r -> -r.
        "compliant-high" (high-velocity impacts, section 6.2) uses (39).

    Returns
    -------
    Coefficients

    Examples
    --------
    Figure 9's parameters: the period-1 flip rho = 1/4 lies at sigma = 0.445 with rho linear in
    sigma, at sigma = 0.80 with |A~(sigma)| (docs/theory.md section 7):

    >>> from mapcheck import invert_alpha_gamma
    >>> inv = invert_alpha_gamma(0.99, 0.01)
    >>> c = coefficients(inv.nu, inv.Omega, 0.9, "compliant")
    >>> round(float(c.sigma_of_rho(0.25)), 4), round(float(c.sigma_of_rho(0.25, "tilde")), 4)
    (0.4454, 0.8015)
    """
    re = effective_r(r, wall)
    P = propagator(1.0, nu, Omega)
    P12, P22 = float(P[0, 1]), float(P[1, 1])
    alpha = float(P[0, 0] + P[1, 1])
    gamma = float(math.exp(-nu))
    one = 1.0 + re
    if one == 0.0:
        raise ValueError("1 + r_eff = 0 (r = 1 at a compliant wall): no square-root term, l undefined")
    c1 = float(np.sign(P12)) or 1.0
    c2 = alpha - 2.0 * one * P22 + one ** 2 * P22 ** 2
    c3 = (1.0 + 2.0 * re) * gamma - one ** 2 * P22 ** 3
    l = 1.0 / (4.0 * A_GRAZING ** 2 * one ** 2 * P12 ** 2)
    rho_per_sigma = (1.0 - alpha + gamma) / (2.0 * abs(A_GRAZING) * one ** 2 * P12 ** 2)
    return Coefficients(float(nu), float(Omega), float(r), wall, re, alpha, gamma, P,
                        c1, c2, c3, l, rho_per_sigma)
