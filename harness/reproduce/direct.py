"""Direct state comparison near grazing: the map's one-step prediction against the FMU.

The FMU's pre-impact map (the exact counterpart of (31)/(32), docs/theory.md section 3): a
virtual state at t = n is propagated freely back to n - 1/2, the FMU integrates with the
wall to n + 1/2, and the result is propagated freely to n + 1.  Along rays
(x, y, rho) = l eps (a, b, s) in natural coordinates the error of the map's image, in natural
coordinates (O(eps)), is fitted as C eps^q; the expansion predicts q = 3/2.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from mapcheck.coeffs import coefficients
from mapcheck.compare import (
    free_flight,
    loglog_slope,
    map_one_step_error,
    natural_distance,
    scaled_state,
    virtual_to_phase,
)
from mapcheck.exact import ExactOscillator
from mapcheck.linear import invert_alpha_gamma

from ..config.defaults import WALLS
from . import Context
from .fig9_maps import ALPHA, GAMMA, R

#: Rays (a, b, s) in natural coordinates: (x, y, rho) = l eps (a, b, s); x > 0: an impact.
DIRECTIONS = ((1.0, 0.0, 0.0), (1.0, 1.0, 1.0), (0.5, -1.0, 1.0), (2.0, 0.5, -1.0))
#: The FMU's walls compared, each with (Gamma, map coefficients' wall).  Compliant at Gamma = 10:
#: the low-velocity map (48) (beta ~ sqrt(eps) -> 0); rigid: (39).
CASES = {"compliant": (10.0, "compliant"), "rigid": (10.0, "rigid")}
#: The FMU's own error at each point is measured against the closed-form solution of the
#: ODE (mapcheck.exact, same pre-impact construction); near grazing it grows (low impact
#: velocity: ~1e-9 compliant, ~3e-8 rigid in u at eps = 1e-4).  Points are fitted only
#: where the map's error is NOISE_FACTOR times the FMU's (a 3% perturbation of a point
#: changes the fitted slope by < 0.02 over a decade), and for
#: eps <= 0.1, which keeps the impact velocity sqrt(chi) ~ 0.3 low (beta ~ 0.007 at
#: Gamma = 10, the low-velocity regime of (48)).
NOISE_FACTOR = 30.0
EPS_MAX_FIT = 0.1
SETTINGS = {True: {"eps": np.geomspace(1e-4, 1e-1, 7)}, False: {"eps": np.geomspace(1e-6, 1e-1, 26)}}


def fmu_pre_impact_map(sim: Any, params: dict[str, Any], z: np.ndarray, sigma: float,
                       nu: float, Omega: float) -> tuple[np.ndarray, int]:
    """Virtual state at t = n -> virtual state at n + 1 through the FMU; wall entries."""
    start = virtual_to_phase(z, sigma, nu, Omega, -0.5)
    sim.start({**params, "sigma": float(sigma)}, -0.5, (float(start[0]), float(start[1])))
    sim.advance(0.5)
    u, v, n = sim.read()
    # the state at 1/2 is past the impact near 0: free flight to the virtual state at 1
    return free_flight(np.array([u, v]), sigma, nu, Omega, 0.5, 1.0), n


def _errors(sim: Any, params: dict[str, Any], c: Any, d: tuple, eps: np.ndarray, nu: float, Om: float,
            wall: str, Gamma: float) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """Map error and the FMU's own error (against the closed form) along one ray."""
    errs, fmu_errs, contacts = [], [], []
    for e in eps:
        u, v, s = scaled_state(float(e), d, c)
        z1, n = fmu_pre_impact_map(sim, params, np.array([u, v]), s, nu, Om)
        ue, ve, _ = ExactOscillator(nu, Om, s, r=R, Gamma=Gamma, wall=wall).pre_impact_map(u, v)
        errs.append(map_one_step_error(u, v, s, z1[0], z1[1], c))
        fmu_errs.append(natural_distance(z1, (float(ue), float(ve)), s, c))
        contacts.append(n)
    return np.array(errs), np.array(fmu_errs), contacts


def run(ctx: Context) -> tuple[dict[str, Any], str]:
    inv = invert_alpha_gamma(ALPHA, GAMMA)
    nu, Om = inv.nu, inv.Omega
    eps = SETTINGS[ctx.quick]["eps"]
    sim = ctx.simulator()
    rows: dict[str, Any] = {}
    for wall, (G, mwall) in CASES.items():
        c = coefficients(nu, Om, R, mwall)
        params = ctx.params(wall=WALLS[wall], Gamma=G, r=R)
        rows[wall] = {}
        for d in DIRECTIONS:
            errs, fmu_errs, contacts = _errors(sim, params, c, d, eps, nu, Om, wall, G)
            fit = (errs >= NOISE_FACTOR * fmu_errs) & (eps <= EPS_MAX_FIT * (1 + 1e-9))
            rows[wall][str(d)] = {"direction": d, "eps": eps, "error": errs, "fmu_error": fmu_errs,
                                  "contacts": contacts, "fitted": fit, "order": loglog_slope(eps[fit], errs[fit])}
    orders = {w: {k: r["order"] for k, r in rw.items()} for w, rw in rows.items()}
    worst = min(o for rw in orders.values() for o in rw.values())
    verdict = f"one-step error of the map ~ eps^q with q >= {worst:.2f} on every ray (expansion: 3/2)"
    files = [_plot(ctx, rows)]
    result = {"figure": "direct", "orders": orders, "min_order": worst, "rows": rows, "verdict": verdict,
              "files": files,
              "parameters": {"alpha": ALPHA, "gamma": GAMMA, "nu": nu, "Omega": Om, "r": R,
                             "walls": {w: {"wall": WALLS[w], "Gamma": v[0], "map": v[1]} for w, v in CASES.items()},
                             "eps": eps, "directions": DIRECTIONS}}
    return result, _report(ctx, result)


def _plot(ctx: Context, rows: dict[str, Any]) -> str:
    from ..io import plots  # noqa: F401  (Agg backend)
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(rows), figsize=(10, 4), sharey=True)
    for ax, (wall, rw) in zip(np.atleast_1d(axes), rows.items()):
        for key, r in rw.items():
            ax.loglog(r["eps"], r["error"], "o-", ms=3, label=f"(a, b, s) = {r['direction']}: q = {r['order']:.2f}")
        e = np.asarray(next(iter(rw.values()))["eps"])
        ref = next(iter(rw.values()))["error"][-1] * (e / e[-1]) ** 1.5
        ax.loglog(e, ref, "k--", lw=0.8, label="eps^1.5")
        ax.set_xlabel("eps  ((x, y, rho) = l eps (a, b, s))")
        ax.set_title(f"{wall} wall: map (31) vs FMU, one step", fontsize=10)
        ax.legend(fontsize=7)
    np.atleast_1d(axes)[0].set_ylabel("max error in (x, y) / l")
    fig.tight_layout()
    path = ctx.out / "direct_error.png"
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path.name


def _report(ctx: Context, res: dict[str, Any]) -> str:
    p = res["parameters"]
    lines = [
        "# Direct comparison: one step of the map vs the FMU near grazing",
        "",
        f"Parameters: (alpha, gamma) = ({ALPHA}, {GAMMA}) (nu = {p['nu']:.6f}, Omega = {p['Omega']:.6f}), r = {R}; "
        "compliant wall Gamma = 10 against the low-velocity map (48), rigid wall against (39). "
        f"{'Quick' if ctx.quick else 'Full'} run.",
        "",
        "## What was compared",
        "",
        "From a virtual (pre-impact) state (u, v) at t = n with forcing sigma, the map (31)/(32) gives the next "
        "virtual state; the FMU gives it exactly (free flight back to n - 1/2, the FMU with the wall to n + 1/2, free "
        "flight to n + 1). Along rays (x, y, rho) = l eps (a, b, s) in the natural coordinates (33)/(34) "
        "(physical state by the inverse (35)), the largest error of the image in natural coordinates, divided by l (36), is fitted as C eps^q.",
        "",
        "## Fitted orders q",
        "",
        "| ray (a, b, s) | " + " | ".join(res["orders"]) + " |",
        "|---|" + "---|" * len(res["orders"]),
    ]
    keys = list(next(iter(res["orders"].values())))
    for k in keys:
        lines.append(f"| {k} | " + " | ".join(f"{res['orders'][w][k]:.3f}" for w in res["orders"]) + " |")
    lines += [
        "",
        f"eps from {p['eps'][0]:.1e} to {p['eps'][-1]:.1e}. The FMU's own error at each point is measured against "
        "the closed-form solution (mapcheck.exact); its largest value in the same units: "
        + ", ".join(f"{w} {max(r['fmu_error'].max() for r in rw.values()):.1e}" for w, rw in res["rows"].items())
        + f" (it grows towards grazing, where the impact velocity is small). Fitted are the points where the map's "
        f"error is at least {NOISE_FACTOR:g} times the FMU's, with eps <= {EPS_MAX_FIT:g}. Errors at the largest eps: "
        + "; ".join(f"{w}: {max(r['error'][-1] for r in rw.values()):.2e}" for w, rw in res["rows"].items()) + ".",
        "",
        "## Verdict",
        "",
        f"The map's one-step error is O(eps^q) with q >= {res['min_order']:.2f} on every ray and both walls: the "
        "maps are correct to the order the expansion claims (3/2); where they disagree with the ODE it is by "
        "these higher-order terms, which grow relative to the state like eps^(1/2) away from grazing.",
        "",
        "Figure: `direct_error.png`.",
    ]
    return "\n".join(lines)
