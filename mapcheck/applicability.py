"""Where the maps apply: a reason instead of a meaningless number.

The near-grazing maps are derived under assumptions that a parameter set can violate:

* (64) is the window of the strongly damped 1D map (54)/(55), the limit alpha -> 1, gamma -> 0
  of (37)/(38).  With alpha <= 0 the non-impacting steps x' = alpha x + y + rho do not carry x
  monotonically up to the wall, so the maximal orbit x_1 < ... < x_{M-1} < 0 <= x_M of (57) that
  (58)-(63) build does not exist; (64) says nothing there.
* The square-root term of (37)/(38) is -(1 + r_eff) times the impact velocity: with
  1 + r_eff = 0 (r = 1 at a compliant wall, low-velocity map (48)) it vanishes and the maps are
  undefined (l of (36) is infinite).
* The A~ variant puts |A~(sigma)| = |(1 + sigma) A + sigma Omega^2| in rho: where A~ reaches 0
  (Omega^2 > 4 pi^2, sigma >= 4 pi^2 / (Omega^2 - 4 pi^2)) the grazing acceleration vanishes and
  the expansion has no leading term; and rho~(sigma) saturates at rho_per_sigma |A| / (|A| - Omega^2)
  as sigma -> inf, so windows with a larger rho are out of its reach.
* A map may simply have no stable maximal period-M orbit anywhere: then it predicts no window,
  and the report says over which sigma range it looked.

:func:`map_applicability` returns, per map variant, None (it applies) or the reason it does not.
"""
from __future__ import annotations

import math
from typing import Mapping

from .coeffs import A_GRAZING

__all__ = ["map_applicability", "acceleration_vanishes_at", "VARIANT_NAMES"]

#: The map variants of ``windows`` (keys of its JSON).
VARIANT_NAMES = ("theory_64", "map", "map_A_tilde")


def acceleration_vanishes_at(Omega: float) -> float:
    """sigma where A~(sigma) = (1 + sigma) A + sigma Omega^2 = 0 (inf when it never does)."""
    b = abs(A_GRAZING) - Omega * Omega
    return math.inf if b >= 0 else abs(A_GRAZING) / (-b)


def map_applicability(nu: float, Omega: float, r: float, wall: str, alpha: float, gamma: float,
                      windows: Mapping[str, Mapping[int, object]] | None = None,
                      sigma_range: tuple[float, float] | None = None) -> dict[str, str | None]:
    """Why each map variant does not apply (None where it does).

    Parameters
    ----------
    nu, Omega, r : float
        The oscillator.
    wall : str
        The coefficients' wall ("rigid", "compliant", "compliant-high").
    alpha, gamma : float
        (9) of the oscillator.
    windows : mapping, optional
        The variants' windows {variant: {M: window or None}} as computed; a variant without a
        single window is reported as "no stable maximal orbit" over ``sigma_range``.
    sigma_range : (float, float), optional
        The sigma range the variants' windows were searched in.

    Returns
    -------
    dict
        {variant: reason or None}.
    """
    out: dict[str, str | None] = {k: None for k in VARIANT_NAMES}
    r_eff = -r if wall in ("compliant", "compliant-low") else r
    if 1.0 + r_eff == 0.0:
        why = ("1 + r_eff = 0 (r = 1 at a compliant wall with the low-velocity map (48)): the square-root term "
               "vanishes and l of (36) is infinite, so the maps (37)/(38) are undefined")
        return {k: why for k in VARIANT_NAMES}
    if alpha <= 0.0:
        out["theory_64"] = (f"alpha = {alpha:.4g} <= 0: (64) is the strongly damped limit alpha -> 1, gamma -> 0; "
                            "non-impacting steps x' = alpha x + y + rho do not carry x monotonically to the wall, "
                            "so the maximal orbits of (58)-(63) do not exist")
    s_zero = acceleration_vanishes_at(Omega)
    if windows is not None:
        lo, hi = sigma_range if sigma_range is not None else (math.nan, math.nan)
        for k in VARIANT_NAMES:
            if out[k] is None and not any(w is not None for w in windows.get(k, {}).values()):
                extra = ""
                if k == "map_A_tilde" and math.isfinite(s_zero):
                    extra = f"; A~(sigma) vanishes at sigma = {s_zero:.4g} (Omega^2 > 4 pi^2)"
                out[k] = (f"no stable maximal period-M orbit of the map for any M searched, sigma in "
                          f"[{lo:.3g}, {hi:.3g}]{extra}")
    return out
