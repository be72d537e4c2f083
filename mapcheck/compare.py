"""Map vs ODE (FMU) comparisons: window tables, coordinates, fits and report tables.

The harness measures (sweep Datasets, shooting edges, Jacobians); this module holds the
comparison logic, so that it can be tested without the FMU:

* coordinates: the FMU samples the real state at t = n + theta; the maps' state is the
  pre-impact ("virtual") state at t = n (docs/theory.md section 3), related by the free
  propagator (8).  :func:`free_flight`, :func:`virtual_to_phase`, :func:`phase_to_natural`.
* windows: :func:`predicted_windows` ((64), the 2D map, the 2D map with A~, for any
  coefficients), :func:`map_windows` (any coefficients), :func:`sweep_windows` (runs of maximal period-M
  orbits in an up or down scan), :func:`scan_confirmation`, :func:`window_differences`,
  :func:`best_variant`, :func:`markdown_window_table`; starting guesses for shooting on the
  FMU from the map's orbits: :func:`maximal_orbit_section_guess` (:func:`maximal_orbit_guess`).
* direct comparison: :func:`scaled_state`, :func:`map_one_step_error`, :func:`natural_distance`.
* fits: :func:`loglog_slope` (Jacobian slopes, orders of errors), :func:`power_law_with_offset`.
"""
from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

import numpy as np

from .coeffs import Coefficients
from .linear import propagator
from .maps import from_natural, to_natural
from .windows import MapParams, maximal_orbits

__all__ = [
    "VARIANTS",
    "wall_free_state",
    "virtual_to_phase",
    "free_flight",
    "phase_to_natural",
    "maximal_orbit_guess",
    "maximal_orbit_section_guess",
    "sweep_windows",
    "map_windows",
    "predicted_windows",
    "window_differences",
    "scan_confirmation",
    "best_variant",
    "markdown_window_table",
    "loglog_slope",
    "scaled_state",
    "map_one_step_error",
    "natural_distance",
    "power_law_with_offset",
]

TWO_PI = 2.0 * math.pi

#: The map variants of Figure 9's table (key in ``fig9.json`` -> (fig9_windows key, label)).
VARIANTS: dict[str, tuple[str, str]] = {
    "theory_64": ("64", "(64), rho(sigma) from (48)"),
    "map": ("2d", "2D map (37)/(38) with (48)"),
    "map_A_tilde": ("2d_tilde", "2D map (37)/(38) with (48), A~(sigma)"),
}

Windows = dict[int, "tuple[float, float | None] | None"]


# ----------------------------------------------------------------------------------------
# Coordinates
# ----------------------------------------------------------------------------------------
def wall_free_state(sigma: float, t: float) -> np.ndarray:
    """(p, p') of (4): p(t) = (1 + sigma) cos(2 pi t) - 1, the wall-free periodic orbit."""
    return np.array([(1.0 + sigma) * math.cos(TWO_PI * t) - 1.0,
                     -TWO_PI * (1.0 + sigma) * math.sin(TWO_PI * t)])


def free_flight(z: Sequence[float], sigma: float, nu: float, Omega: float, t0: float, t1: float) -> np.ndarray:
    """Wall-free propagation (8) of the state z at time t0 to t1 (either order):
    u(t1) = P(t1 - t0) [u(t0) - p(t0)] + p(t1)."""
    z = np.asarray(z, dtype=float)
    return propagator(t1 - t0, nu, Omega) @ (z - wall_free_state(sigma, t0)) + wall_free_state(sigma, t1)


def virtual_to_phase(z: Sequence[float], sigma: float, nu: float, Omega: float, dt: float) -> np.ndarray:
    """Free-propagate a state at t = n by ``dt`` (either sign), equation (8):
    u(n + dt) = P(dt) [u(n) - p(n)] + p(n + dt).

    With ``dt = -1/2`` a virtual state at t = n (the maps' state) becomes the real state at
    n - 1/2, before the impact near n; with ``dt = 1 - theta`` a real state sampled at
    n + theta (after the impact near n) becomes the virtual state at n + 1.
    """
    return free_flight(z, sigma, nu, Omega, 0.0, dt)


def phase_to_natural(u, v, sigma, c: Coefficients, theta: float = 0.5, variant: str = "tilde"):
    """Natural coordinates (33)/(34) of FMU samples taken at t = n + theta.

    Each sample (taken between impacts) is propagated freely to the virtual state at
    n + 1 and mapped by (33)/(34), with A or A~(sigma) (``variant``), so that ODE and map
    bifurcation diagrams share their axes.  Vectorized over u, v (sigma broadcast).
    """
    u, v, sigma = np.broadcast_arrays(np.asarray(u, float), np.asarray(v, float), np.asarray(sigma, float))
    P = propagator(1.0 - theta, c.nu, c.Omega)
    pu0, pv0 = (1.0 + sigma) * math.cos(TWO_PI * theta) - 1.0, -TWO_PI * (1.0 + sigma) * math.sin(TWO_PI * theta)
    du, dv = u - pu0, v - pv0
    uu = P[0, 0] * du + P[0, 1] * dv + sigma  # p(n+1) = (sigma, 0)
    vv = P[1, 0] * du + P[1, 1] * dv
    return to_natural(uu, vv, sigma, c, variant)


def maximal_orbit_guess(c: Coefficients, M: int, sigma: float, variant: str = "tilde") -> np.ndarray | None:
    """Virtual state (u, v) at t = n of the stable maximal period-M orbit of (37)/(38)
    at ``sigma`` (rho from (48), with A~(sigma) for ``variant="tilde"``), at the point
    right after the impacting step (x_1 < 0 for M > 1); None if there is none.

    Inverse coordinates (35) with the exact inverse of (33).
    """
    p = MapParams.from_coefficients(c)
    orb = maximal_orbits(p, M, c.rho(np.array([sigma]), variant))
    stable = orb.stable[:, 0]
    if not np.any(stable):
        return None
    k = int(np.argmax(stable))
    u, v = from_natural(orb.x[k, 0, 0], orb.y[k, 0, 0], sigma, c, variant)
    return np.array([float(u), float(v)])


def maximal_orbit_section_guess(c: Coefficients, M: int, sigma: float, theta: float = 0.5,
                                variant: str = "tilde") -> np.ndarray | None:
    """Real state at phase ``theta`` just after the impact of the stable maximal period-M
    orbit of (37)/(38) (None if there is none): the impacting point z_M (virtual, x_M >= 0)
    through the local impact map L (26)-(30) (r_eff of ``c``, A or A~), then free flight (8)
    forward by ``theta``.

    Forward only: backward free flight multiplies errors by e^(|s2| dt), which is ~1e21 at
    nu = 100 over half a period.
    """
    from .coeffs import grazing_acceleration
    from .maps import local_impact_map

    p = MapParams.from_coefficients(c)
    orb = maximal_orbits(p, M, c.rho(np.array([sigma]), variant))
    stable = orb.stable[:, 0]
    if not np.any(stable):
        return None
    k = int(np.argmax(stable))
    u, v = from_natural(orb.x[k, M - 1, 0], orb.y[k, M - 1, 0], sigma, c, variant)
    A = grazing_acceleration(sigma, c.Omega, variant)
    ut, vt = local_impact_map(u, v, c.nu, c.r_eff, A)
    return free_flight((float(ut), float(vt)), sigma, c.nu, c.Omega, 0.0, theta)


# ----------------------------------------------------------------------------------------
# Window tables
# ----------------------------------------------------------------------------------------
def map_windows(c: Coefficients, M_max: int, sigma_grid: np.ndarray, variant: str = "tilde") -> Windows:
    """Stable maximal period-M windows in sigma of the 2D map (37)/(38) with the
    coefficients ``c`` ((39) rigid, (48) compliant), rho from A or A~(sigma) (``variant``).
    The widest window per M; ``lo``/``hi`` None where it reaches the start/end of the grid."""
    from .windows import windows

    p = MapParams.from_coefficients(c)
    out: Windows = {}
    for M in range(1, M_max + 1):
        ws = windows(p, M, sigma_grid, lambda q: c.rho(q, variant))
        if not ws:
            out[M] = None
            continue
        w = max(ws, key=lambda w: w.hi - w.lo)
        # an edge at the end of the grid is not an edge: None (beyond the searched range)
        out[M] = (None if w.kind_lo == "range" else float(w.lo), None if w.kind_hi == "range" else float(w.hi))
    return out


def predicted_windows(c: Coefficients, M_max: int, sigma_grid: np.ndarray) -> dict[str, Windows]:
    """The three map predictions of the sigma-edges of the stable maximal period-M windows.

    Parameters
    ----------
    c : Coefficients
        :func:`mapcheck.coeffs.coefficients` of the parameter set ((39) rigid wall, (48)
        compliant wall).
    M_max : int
    sigma_grid : ndarray
        Sorted sigma grid for the 2D maps' window search (each window is bisected from it).

    Returns
    -------
    dict
        ``{"theory_64": {M: (lo, hi)}, "map": ..., "map_A_tilde": ...}``: (64) with rho
        linear in sigma; the 2D map (37)/(38) with rho linear in sigma; the same with
        |A~(sigma)| in rho.  ``hi`` None where a window has no upper edge (M = 1) or
        reaches the end of the grid; a window None where there is none.
    """
    from .windows import window_1d

    t64: Windows = {}
    for M in range(1, M_max + 1):
        lo, hi = window_1d(M)
        t64[M] = None if lo > hi else (lo / c.rho_per_sigma, None if not math.isfinite(hi) else hi / c.rho_per_sigma)
    return {"theory_64": t64, "map": map_windows(c, M_max, sigma_grid, "paper"),
            "map_A_tilde": map_windows(c, M_max, sigma_grid, "tilde")}


def equal_runs(keep: Sequence[bool], *labels: Sequence[Any]) -> list[tuple[int, int]]:
    """Maximal index runs (first, last) where ``keep`` holds and every array in ``labels`` is
    constant: the windows of a scan (period, impacts), the stable parts of a branch."""
    keep = np.asarray(keep, dtype=bool)
    labels = tuple(np.asarray(a) for a in labels)
    out: list[tuple[int, int]] = []
    k, n = 0, len(keep)
    while k < n:
        if not keep[k]:
            k += 1
            continue
        j = k
        while j + 1 < n and keep[j + 1] and all(a[j + 1] == a[k] for a in labels):
            j += 1
        out.append((k, j))
        k = j + 1
    return out


def sweep_windows(values: np.ndarray, period: np.ndarray, impacts: np.ndarray) -> dict[int, tuple[float, float]]:
    """Windows of maximal period-M orbits (period M, one impact per period) seen in a scan.

    Parameters
    ----------
    values : ndarray (K,)
        Sorted sigma grid.
    period, impacts : ndarray of int (K,)
        The harness's classification at each grid point (``period``, ``orbit_impacts``).

    Returns
    -------
    dict
        M -> (lowest, highest) sigma of the longest run of maximal period-M points.
        Grid points only: the true edge lies within one grid step outside.
    """
    values = np.asarray(values, dtype=float)
    keep = (np.asarray(period) > 0) & (np.asarray(impacts) == 1)
    best: dict[int, tuple[int, float, float]] = {}
    for k, j in equal_runs(keep, period):
        M = int(period[k])
        if M not in best or j - k + 1 > best[M][0]:
            best[M] = (j - k + 1, float(values[k]), float(values[j]))
    return {M: (lo, hi) for M, (_, lo, hi) in sorted(best.items())}


def scan_confirmation(shooting: Windows, up: Mapping[int, tuple[float, float]],
                      down: Mapping[int, tuple[float, float]]) -> dict[int, dict[str, float | None]]:
    """Compare shooting edges with quasi-static scans.

    The lower edge is compared with the lowest maximal period-M point of the down scan,
    the upper edge with the highest of the up scan (the order in which a continuation
    reaches them; M = 1 and M = 2 overlap with hysteresis).  Differences are scan minus
    shooting: >= -(grid step) if the scans never see a stable maximal orbit where the
    shooting finds none.
    """
    out: dict[int, dict[str, float | None]] = {}
    for M, w in shooting.items():
        if w is None:
            continue
        lo_scan = down.get(M, (None, None))[0]
        hi_scan = up.get(M, (None, None))[1] if w[1] is not None else None
        out[M] = {
            "scan_lower": lo_scan, "scan_upper": hi_scan,
            "lower_minus_shooting": None if (lo_scan is None or w[0] is None) else lo_scan - w[0],
            "upper_minus_shooting": None if (hi_scan is None or w[1] is None) else hi_scan - w[1],
        }
    return out


def window_differences(reference: Windows, other: Windows) -> dict[int, tuple[float | None, float | None]]:
    """Per period, (other - reference) at the lower and upper edges (None where either is
    missing, unresolved or unbounded)."""
    out: dict[int, tuple[float | None, float | None]] = {}
    for M, ref in reference.items():
        w = other.get(M)
        if ref is None or w is None:
            out[M] = (None, None)
            continue
        dlo = None if (ref[0] is None or w[0] is None) else w[0] - ref[0]
        dhi = None if (ref[1] is None or w[1] is None) else w[1] - ref[1]
        out[M] = (dlo, dhi)
    return out


def best_variant(ode: Windows, variants: Mapping[str, Windows]) -> tuple[str, dict[str, float]]:
    """The variant whose edges are closest to the ODE's (largest absolute difference over
    every finite edge); returns (name, {name: max |difference|}).  Two ends that are both
    unbounded (beyond the range in both) agree: they count as a difference of 0, not as no
    comparison at all; a window the ODE has and the variant lacks is an infinite difference; a
    variant with no end comparable to the ODE's scores nan (and is never the best)."""
    score: dict[str, float] = {}
    for name, w in variants.items():
        diffs = [abs(d) for pair in window_differences(ode, w).values() for d in pair if d is not None]
        open_both = [0.0 for M, ref in ode.items() if ref is not None and w.get(M) is not None
                     for i in (0, 1) if ref[i] is None and w[M][i] is None]
        missing = sum(1 for M in ode if ode[M] is not None and w.get(M) is None)
        diffs += open_both
        # nothing comparable (every window open where the other is bounded): nan, not a difference
        score[name] = math.inf if missing else (max(diffs) if diffs else math.nan)
    ranked = {k: v for k, v in score.items() if not math.isnan(v)} or score
    return min(ranked, key=ranked.get), score


def _fmt_window(w: Any, digits: int = 4) -> str:
    if w is None:
        return "none"
    # an edge that is None: no upper edge (maps, M = 1) or not bracketed inside the range
    lo = "below range" if w[0] is None else f"{w[0]:.{digits}f}"
    hi = "above range" if w[1] is None else f"{w[1]:.{digits}f}"
    return f"[{lo}, {hi}]"


def markdown_window_table(rows: Mapping[str, Windows], labels: Mapping[str, str] | None = None,
                          digits: int = 4, na: Mapping[str, str | None] | None = None) -> str:
    """Markdown table: one row per source, one column per period M; a source whose ``na``
    entry is a reason (the map does not apply) shows "n/a" in every cell."""
    Ms = sorted({M for w in rows.values() for M in w})
    head = "| source | " + " | ".join(f"M = {M}" for M in Ms) + " |"
    sep = "|---|" + "---|" * len(Ms)
    lines = [head, sep]
    for name, w in rows.items():
        label = (labels or {}).get(name, name)
        if (na or {}).get(name):
            lines.append(f"| {label} | " + " | ".join("n/a" for _ in Ms) + " |")
            continue
        lines.append(f"| {label} | " + " | ".join(_fmt_window(w.get(M), digits) for M in Ms) + " |")
    return "\n".join(lines)


# ----------------------------------------------------------------------------------------
# Fits
# ----------------------------------------------------------------------------------------
def loglog_slope(x: Sequence[float], y: Sequence[float]) -> float:
    """Least-squares slope of log|y| against log x (power-law exponent)."""
    x = np.asarray(x, dtype=float)
    y = np.abs(np.asarray(y, dtype=float))
    ok = (x > 0) & (y > 0) & np.isfinite(y)
    if np.count_nonzero(ok) < 2:
        return math.nan
    return float(np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)[0])


# ----------------------------------------------------------------------------------------
# Direct state comparison (item 6)
# ----------------------------------------------------------------------------------------
def scaled_state(eps: float, direction: Sequence[float], c: Coefficients) -> tuple[float, float, float]:
    """The physical state (u, v, sigma) at (x, y, rho) = l eps (a, b, s) in natural coordinates.

    The map (37)/(38) is an expansion in the size of (x, y, rho); its error is
    O(eps^(3/2)) (docs/theory.md section 4).  The factor l of (36) makes eps the same physical
    size for every wall (chi = x / l ~ eps: impact velocity ~ sqrt(eps)); l differs by
    (1+r)^2/(1-r)^2 between the rigid (39) and the compliant (48) map.  Inverse (35) (exact
    inverse of (33)) with A; sigma = rho / (rho/sigma) of (39)/(48).
    """
    a, b, s = direction
    sigma = s * c.l * eps / c.rho_per_sigma
    u, v = from_natural(a * c.l * eps, b * c.l * eps, sigma, c, "paper")
    return float(u), float(v), float(sigma)


def map_one_step_error(u: float, v: float, sigma: float, u1_ode: float, v1_ode: float,
                       c: Coefficients, variant: str = "paper") -> float:
    """|natural coordinates of the map's image - those of the ODE's image| / l.

    The map is (31)/(32) in physical coordinates (with L from (26)-(30), r_eff of ``c``);
    both images are expressed in the natural coordinates (33)/(34), where the state is
    O(eps) and the map's error is O(eps^(3/2)) (docs/theory.md section 4); divided by l (36)
    so that the error is in the units of chi for every wall.
    """
    from .maps import physical_map

    um, vm = physical_map(u, v, sigma, c, variant)
    return natural_distance((um, vm), (u1_ode, v1_ode), sigma, c, variant)


def natural_distance(za: Sequence[float], zb: Sequence[float], sigma: float, c: Coefficients,
                     variant: str = "paper") -> float:
    """max(|x_a - x_b|, |y_a - y_b|) / l of two physical states in natural coordinates (33)/(34)."""
    xa, ya = to_natural(za[0], za[1], sigma, c, variant)
    xb, yb = to_natural(zb[0], zb[1], sigma, c, variant)
    return float(max(abs(xa - xb), abs(ya - yb))) / c.l


def power_law_with_offset(x: Sequence[float], y: Sequence[float], q_range: tuple[float, float] = (-1.0, 1.0),
                          n_q: int = 2001) -> tuple[float, float, float]:
    """Fit y = a x^q + b (signed y): the exponent q of a power law on top of a constant.

    The impact contribution to the map's Jacobian, J - P, is the sum of a regular part
    P (N - I) (O(1), (28)/(29)) and the singular part ~ x^(-1/2) (or ~ x^(1/2) where N = I,
    r = 1 at a soft wall); the constant would bend a plain log-log slope.  For each q on
    a grid, (a, b) are linear least squares; the q with the smallest relative residual
    wins.

    Returns
    -------
    (q, a, b)
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    best = (math.nan, math.nan, math.nan, math.inf)
    w = 1.0 / np.maximum(np.abs(y), 1e-300)  # relative residuals: every decade counts
    for q in np.linspace(q_range[0], q_range[1], n_q):
        if abs(q) < 1e-9:
            continue  # x^0 is the constant itself
        A = np.stack([x ** q, np.ones_like(x)], axis=1) * w[:, None]
        coef, *_ = np.linalg.lstsq(A, y * w, rcond=None)
        res = float(np.sum((A @ coef - y * w) ** 2))
        if res < best[3]:
            best = (float(q), float(coef[0]), float(coef[1]), res)
    return best[0], best[1], best[2]
