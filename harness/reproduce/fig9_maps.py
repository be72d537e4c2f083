"""Figure 9's period-adding windows, as predicted by each variant of the map.

Run ``python -m harness.reproduce.fig9_maps`` to print the table.

Parameters: (alpha, gamma) = (0.99, 0.01) (overdamped, unique inverse), r = 0.9,
compliant wall, low-velocity map (37)/(38) with (48).  Predictions of the sigma-edges
of the stable maximal period-M windows:

* ``"64"``        -- the 1D closed form (64), rho(sigma) linear from (48);
* ``"64_eq56"``   -- (64) with the nu >> 1 rho of (56);
* ``"64_tilde"``  -- (64) with rho(sigma) using |A~(sigma)| (section 6);
* ``"2d"``        -- the 2D map (37)/(38), (48), periodic orbits + bisection;
* ``"2d_tilde"``  -- the same with rho~(sigma);
* ``"phys"``, ``"phys_tilde"`` -- the map in physical coordinates (31)/(32) with A or
  A~(sigma) (Newton orbits + continuation, :func:`physical_windows`);
* ``"ode"``       -- the exact pre-impact map of the ODE (53) with a compliant wall
  (closed form, Newton orbits + continuation, :func:`ode_windows`; slow: minutes).

Run ``python -m harness.reproduce.fig9_maps [--physical] [--ode GAMMA]``.  Output of
``--physical --ode 10`` (sigma-edges; inf: no upper edge)::

    variant                     M=1              M=2               M=3               M=4
    (64), rho from (48)         [0.4454, inf]    [0.2227, 0.4454]  [0.1485, 0.1979]  [0.1113, 0.1113]
    (64), rho from (56)         [0.4580, inf]    [0.2290, 0.4580]  [0.1527, 0.2036]  [0.1145, 0.1145]
    (64), rho with A~(sigma)    [0.8015, inf]    [0.2863, 0.8015]  [0.1743, 0.2466]  [0.1253, 0.1253]
    2D map (48)                 [0.4482, inf]    [0.2248, 0.4504]  [0.1476, 0.1998]  [0.1089, 0.1102]
    2D map (48), A~(sigma)      [0.8107, inf]    [0.2898, 0.8178]  [0.1730, 0.2496]  [0.1222, 0.1238]
    map (31)/(32), A            [0.4473, inf]    [0.2246, 0.4494]  [0.1475, 0.1996]  [0.1089, 0.1101]
    map (31)/(32), A~(sigma)    [0.8078, inf]    [0.2894, 0.8147]  [0.1729, 0.2493]  [0.1221, 0.1237]
    ODE, Gamma=10               [0.8121, inf]    [0.2900, 0.8190]  [0.1731, 0.2497]  [0.1222, 0.1238]

The ODE agrees with the A~(sigma) maps to ~1e-3 in sigma; the paper's linear rho(sigma)
puts the upper edges at about half the sigma.
"""
from __future__ import annotations

import math
import sys
from typing import Any

import numpy as np

from mapcheck.compare import VARIANTS, Windows
from mapcheck.coeffs import coefficients, grazing_acceleration
from mapcheck.exact import ExactOscillator
from mapcheck.linear import invert_alpha_gamma
from mapcheck.maps import chi, from_natural, physical_map, rho_1d
from mapcheck.orbits import map_step, window_edge
from mapcheck.windows import MapParams, maximal_orbits, window_1d, windows

__all__ = ["theory_windows", "fig9_windows", "physical_windows", "ode_windows", "format_table"]

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


def _fig9_coefficients():
    inv = invert_alpha_gamma(ALPHA, GAMMA)
    return inv.nu, inv.Omega, coefficients(inv.nu, inv.Omega, R, "compliant")


def _newton_windows(step_of, guess_variant: str, M_max: int, xtol: float, sigma_max: float) -> dict[int, tuple]:
    """Windows of a map without closed-form orbits: start inside the natural map's window
    (``guess_variant`` rho), guess the orbit with (35), continue it both ways (Newton)."""
    nu, Om, c = _fig9_coefficients()
    p = MapParams.from_coefficients(c)
    grid = np.linspace(0.0, sigma_max, 6001)
    rho_of = (lambda q: c.rho(q, guess_variant))
    out: dict[int, tuple] = {}
    for M in range(1, M_max + 1):
        ws = windows(p, M, grid, rho_of)
        if not ws:
            out[M] = None
            continue
        w = ws[0]
        hi = w.hi if w.kind_hi != "range" else 1.25 * w.lo
        s0 = 0.5 * (w.lo + hi)
        dp = min(0.02, (hi - w.lo) / 6.3)  # not a half-integer: the march never lands on the guide edge
        orb = maximal_orbits(p, M, rho_of(np.array([s0])))
        k = int(np.argmax(orb.stable[:, 0]))
        u0, v0 = from_natural(orb.x[k, 0, 0], orb.y[k, 0, 0], s0, c, guess_variant)
        kw = dict(tol=1e-11, scale=np.array([1e-2, 1e-1]))
        try:
            lo_e = window_edge(step_of, M, s0, [float(u0), float(v0)], -1.0, dp, 0.0, xtol=xtol, **kw)
            hi_e = window_edge(step_of, M, s0, [float(u0), float(v0)], +1.0, dp, sigma_max, xtol=xtol, **kw)
        except ValueError:
            out[M] = None
            continue
        out[M] = (lo_e[0], np.inf if hi_e[1] == "range" else hi_e[0])
    return out


def physical_windows(variant: str = "paper", M_max: int = 4, xtol: float = 1e-8,
                     sigma_max: float = 3.0) -> dict[int, tuple]:
    """Windows of the physical-coordinate map (31)/(32) (A, or A~(sigma) in chi and L)."""
    nu, Om, c = _fig9_coefficients()

    def step_of(s: float):
        A = grazing_acceleration(s, Om, variant)
        return map_step(physical_map, s, c, variant, contact=lambda u, v: chi(u, v, A) >= 0)

    return _newton_windows(step_of, variant, M_max, xtol, sigma_max)


def ode_windows(Gamma: float = 10.0, M_max: int = 4, xtol: float = 1e-5, sigma_max: float = 1.6) -> dict[int, tuple]:
    """Windows of the exact stroboscopic (pre-impact) map of the ODE with a compliant wall.

    Slow (closed-form integration inside Newton + bisection): minutes per window.
    """
    nu, Om, c = _fig9_coefficients()

    def step_of(s: float):
        osc = ExactOscillator(nu, Om, s, r=R, Gamma=Gamma, wall="compliant")

        def st(u: float, v: float):
            u1, v1, k = osc.pre_impact_map(u, v)
            return float(u1), float(v1), int(k)
        return st

    return _newton_windows(step_of, "tilde", M_max, xtol, sigma_max)


def _clean(w: Any) -> "tuple[float, float | None] | None":
    if w is None:
        return None
    if isinstance(w[0], tuple):  # several windows of one period: keep the widest
        w = max(w, key=lambda e: e[1] - e[0])
    lo, hi = float(w[0]), float(w[1])
    return (lo, None if not math.isfinite(hi) else hi)


def theory_windows(M_max: int = 4) -> dict[str, Windows]:
    """The three map predictions of Figure 9's window edges in sigma.

    Returns
    -------
    dict
        ``{"theory_64": {M: (lo, hi)}, "map": ..., "map_A_tilde": ...}``; ``hi = None``
        where a window has no upper edge (M = 1).  (64) with rho(sigma) of (48); the 2D map
        (37)/(38) with (48) and rho linear in sigma; the same with |A~(sigma)| in rho.
    """
    res = fig9_windows(M_max=M_max)
    return {name: {M: _clean(res[key][M]) for M in range(1, M_max + 1)} for name, (key, _) in VARIANTS.items()}


def format_table(res: dict[str, dict[int, tuple]]) -> str:
    """Plain-text table of :func:`fig9_windows`."""
    names = {
        "phys": "map (31)/(32), A",
        "phys_tilde": "map (31)/(32), A~(sigma)",
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
        lines.append(names.get(key, key).ljust(28) + "".join(cell.ljust(22) for cell in cells))
    return "\n".join(lines)


if __name__ == "__main__":
    res = fig9_windows()
    if "--physical" in sys.argv:
        res["phys"] = physical_windows("paper")
        res["phys_tilde"] = physical_windows("tilde")
    if "--ode" in sys.argv:
        G = float(sys.argv[sys.argv.index("--ode") + 1])
        res[f"ODE, Gamma={G:g}"] = ode_windows(G)
    print(format_table(res))
