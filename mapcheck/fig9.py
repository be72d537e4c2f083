"""Figure 9's period-adding windows, as predicted by each variant of the map.

Run ``python -m mapcheck.fig9`` to print the table.

Parameters: (alpha, gamma) = (0.99, 0.01) (overdamped, unique inverse), r = 0.9,
compliant wall, low-velocity map (37)/(38) with (48).  Predictions of the sigma-edges
of the stable maximal period-M windows:

* ``"64"``        -- the 1D closed form (64), rho(sigma) linear from (48);
* ``"64_eq56"``   -- (64) with the nu >> 1 rho of (56);
* ``"64_tilde"``  -- (64) with rho(sigma) using |A~(sigma)| (section 6);
* ``"2d"``        -- the 2D map (37)/(38), (48), periodic orbits + bisection;
* ``"2d_tilde"``  -- the same with rho~(sigma).
"""
from __future__ import annotations

import numpy as np

from .coeffs import coefficients
from .linear import invert_alpha_gamma
from .maps import rho_1d
from .windows import MapParams, window_1d, windows

__all__ = ["fig9_windows", "format_table"]

ALPHA, GAMMA, R = 0.99, 0.01, 0.9


def fig9_windows(M_max: int = 4, sigma_max: float = 3.0, n_grid: int = 12001) -> dict[str, dict[int, tuple]]:
    """Sigma-edges (lo, hi) of the stable maximal period-M windows for every variant.

    Returns
    -------
    dict
        variant -> {M: (sigma_lo, sigma_hi) or None}.  ``hi = inf`` where the window
        extends beyond the scanned range (period 1 has no upper edge).
    """
    inv = invert_alpha_gamma(ALPHA, GAMMA)
    c = coefficients(inv.nu, inv.Omega, R, "compliant")
    k56 = float(rho_1d(1.0, inv.nu, inv.Omega, c.r_eff))
    out: dict[str, dict[int, tuple]] = {k: {} for k in ("64", "64_eq56", "64_tilde", "2d", "2d_tilde")}
    grid = np.linspace(-0.5, sigma_max, n_grid)
    p = MapParams.from_coefficients(c)
    for M in range(1, M_max + 1):
        lo, hi = window_1d(M)
        if lo <= hi:
            out["64"][M] = (lo / c.rho_per_sigma, hi / c.rho_per_sigma)
            out["64_eq56"][M] = (lo / k56, hi / k56)
            out["64_tilde"][M] = (float(c.sigma_of_rho(lo, "tilde")), float(c.sigma_of_rho(hi, "tilde")))
        else:
            out["64"][M] = out["64_eq56"][M] = out["64_tilde"][M] = None
        for key, rho_of in (("2d", c.rho), ("2d_tilde", lambda s: c.rho(s, "tilde"))):
            ws = windows(p, M, grid, rho_of)
            ws = [(w.lo, np.inf if w.kind_hi == "range" else w.hi) for w in ws]
            out[key][M] = ws[0] if len(ws) == 1 else (tuple(ws) if ws else None)
    return out


def format_table(res: dict[str, dict[int, tuple]]) -> str:
    """Plain-text table of :func:`fig9_windows`."""
    names = {
        "64": "(64), rho from (48)",
        "64_eq56": "(64), rho from (56)",
        "64_tilde": "(64), rho with A~(sigma)",
        "2d": "2D map (48)",
        "2d_tilde": "2D map (48), A~(sigma)",
    }
    Ms = sorted(next(iter(res.values())).keys())
    lines = ["variant".ljust(28) + "".join(f"M={M}".ljust(22) for M in Ms)]
    for key, row in res.items():
        cells = []
        for M in Ms:
            w = row[M]
            cells.append("none" if w is None else f"[{w[0]:.4f}, {w[1]:.4f}]")
        lines.append(names[key].ljust(28) + "".join(cell.ljust(22) for cell in cells))
    return "\n".join(lines)


if __name__ == "__main__":
    print(format_table(fig9_windows()))
