"""Figures 6 (r = 1) and 7 (r = 0.9): the FMU map's Jacobian near grazing and the
hysteretic period-3 -> period-1 transition, (nu, Omega) = (0.196, 7.368), compliant wall.

* J(x) along the grazing family (wall-free state (x, 0) at t = n, sigma = 0) for
  Gamma = 10, 1e2, 1e3, 1e4 (and, beyond the paper, 1e5 and 1e6 for the hard limit),
  in the paper's coordinates at t = n, where J11 carries the singularity (docs/theory.md
  section 8).  The impact contribution J11 - P11 is fitted on log-log axes in the soft
  (beta <= 0.1) and hard (beta >= 5) regimes, beta = r kappa sqrt(8 pi^2 x) / |A|:
  expected +1/2 soft at r = 1 (the map is O(x^(3/2)): N = I, no square root), -1/2 soft
  at r < 1 (the square-root term carries (1 - r)) and -1/2 hard (the rigid map (39)).
  With the FMU's own derivatives the scan covers x = 1e-9 .. 0.1 (with differences 1e-5 .. 0.1).
* Bifurcation diagrams of the FMU at Gamma = 10 and 1000: a quasi-static up scan from the
  non-impacting state, then a down scan from where it ended (the experiment's protocol),
  so the hysteresis of the transition shows.
"""
from __future__ import annotations

import concurrent.futures
import math
from typing import Any

import numpy as np

from mapcheck.compare import power_law_with_offset

from ..config import WALLS, SamplingSpec, SweepSpec
from ..dynamics.maps.jacobian import jacobian_vs_x, resolve_method
from ..dynamics.maps.singularity_fit import (
    HARD_BETA,
    RELIABLE,
    SOFT_BETA,
    contact_beta,
    fit_singularity,
    regime_masks,
)
from . import Context

NU, OMEGA = 0.196, 7.368
GAMMAS = (10.0, 1e2, 1e3, 1e4)
#: Stiffer walls than the paper's, for the hard limit (beta -> infinity).
GAMMAS_EXTRA = (1e5, 1e6)
R_OF = {"fig6": 1.0, "fig7": 0.9}
#: x range per Jacobian method.  Differences: x >= 1e-5, the steps must stay below x (else
#: the stencil straddles grazing), and near grazing the FMU's own error is ~1e-9 in u
#: (measured by `reproduce direct`), so below x ~ 1e-5 the differences are noise at the
#: percent level and, at r < 1, outliers appear that the Jacobian's own error estimate does
#: not flag.  The FMU's own derivatives (variational equations with saltation matrices)
#: have no step: the scan goes down to x = 1e-9, four decades further into the singularity.
X_RANGES = {"exact": (1e-9, 1e-1), "fd": (1e-5, 1e-1)}
#: Points per decade of x (quick, full).
X_PER_DECADE = {True: 3, False: 8}
#: x of the exact-vs-differences cross-check (where both are reliable).
X_CHECK = (1e-4, 1e-3, 1e-2)
#: sigma ranges of the bifurcation diagrams.  At r = 0.9 and Gamma = 10 (low velocity,
#: map (48)) the scale is (1-r)^2/(1+r)^2 ~ 1/361 of the hard wall's: the paper expands
#: that axis by 10^2.
SIGMA_RANGE = {(1.0, 10.0): (-0.1, 0.2), (1.0, 1e3): (-0.1, 0.2),
               (0.9, 10.0): (-0.002, 0.004), (0.9, 1e3): (-0.1, 0.2)}
SETTINGS = {
    True: {"sigma_num": 31, "transient": 200, "samples": 24},
    False: {"sigma_num": 121, "transient": 400, "samples": 48},
}


def beta_of(x: np.ndarray, r: float, Gamma: float) -> np.ndarray:
    """beta = r kappa sqrt(8 pi^2 x) / |A| at sigma = 0, v_n = 0 (docs/theory.md section 8)."""
    return contact_beta(x, r, Gamma, OMEGA)


def x_grid(method: str, quick: bool) -> np.ndarray:
    """The x values of the scans: log-spaced over :data:`X_RANGES` [method]."""
    lo, hi = X_RANGES[method]
    return np.geomspace(lo, hi, int(round(X_PER_DECADE[quick] * math.log10(hi / lo))) + 1)


def jacobian_scans(ctx: Context, r: float, x: np.ndarray, method: str = "auto") -> dict[float, Any]:
    sim = ctx.simulator()
    out = {}
    for G in GAMMAS + GAMMAS_EXTRA:
        p = ctx.params(nu=NU, Omega=OMEGA, r=r, Gamma=G, wall=WALLS["compliant"], sigma=0.0)
        out[G] = jacobian_vs_x(sim, p, x, theta=0.0, measure_theta=0.5, method=method)
    return out


def cross_check(ctx: Context, r: float) -> dict[str, Any]:
    """Exact against central differences at :data:`X_CHECK`: the largest relative difference
    of J11 - P11 over the stiffnesses (measured 8e-5: the differences' own error there)."""
    sim = ctx.simulator()
    x = np.asarray(X_CHECK)
    worst = 0.0
    for G in GAMMAS + GAMMAS_EXTRA:
        p = ctx.params(nu=NU, Omega=OMEGA, r=r, Gamma=G, wall=WALLS["compliant"], sigma=0.0)
        ex = jacobian_vs_x(sim, p, x, theta=0.0, measure_theta=0.5, method="exact")
        fd = jacobian_vs_x(sim, p, x, theta=0.0, measure_theta=0.5, method="fd")
        de, df = ex.J[:, 0, 0] - ex.P1[0, 0], fd.J[:, 0, 0] - fd.P1[0, 0]
        worst = max(worst, float(np.max(np.abs(de - df) / np.abs(de))))
    return {"x": x, "max_relative_difference": worst}


def fit_regimes(x: np.ndarray, scan: Any, r: float, Gamma: float) -> dict[str, Any]:
    """Slopes of |J11 - P11| in the soft and hard regimes (plain log-log with its standard
    error, :func:`harness.dynamics.maps.singularity_fit.fit_singularity`, and with the regular O(1)
    part P (N - I) removed by fitting a x^q + b)."""
    d = scan.J[:, 0, 0] - scan.P1[0, 0]
    out: dict[str, Any] = {}
    for name, fit in fit_singularity(x, d, scan.error, beta_of(x, r, Gamma)).items():
        if fit is None:
            out[name] = None
            continue
        sel = (x >= fit.x_min) & (x <= fit.x_max) & regime_masks(x, beta_of(x, r, Gamma))[name]
        sel &= scan.error < RELIABLE * np.abs(d)
        q, a, b = power_law_with_offset(x[sel], d[sel])
        out[name] = {"slope": fit.exponent, "slope_stderr": fit.stderr, "slope_offset_removed": q,
                     "x_range": [fit.x_min, fit.x_max], "beta_range": [fit.beta_min, fit.beta_max],
                     "points": fit.points}
    return out


def _scan_chain(ctx: Context, r: float, G: float, grid: np.ndarray, cfg: dict[str, Any]):
    """Up from the non-impacting state, then down from where the up scan ended."""
    from ..runs.sweeps import run_sweep

    params = ctx.params(nu=NU, Omega=OMEGA, r=r, Gamma=G, wall=WALLS["compliant"])
    sampling = SamplingSpec(theta=0.5, n_transient=cfg["transient"], n_samples=cfg["samples"], tol=1e-4)
    s0 = float(grid[0])
    # in this process: one chain is sequential, and a pool of one would add a process start per scan
    up = run_sweep(ctx.fmu, SweepSpec("sigma", grid, ("up",)), params, (-(1.0 + s0) - 1.0, 0.0), sampling,
                   backend="serial", progress=False)
    last = up.sel(direction="up").isel(sigma=-1)
    state = (float(last["u"].values[-1]), float(last["v"].values[-1]))
    down = run_sweep(ctx.fmu, SweepSpec("sigma", grid, ("down",)), params, state, sampling, backend="serial",
                     progress=False)
    return up, down


def hysteresis(up, down) -> dict[str, Any]:
    """Where the up scan first impacts, and where the down scan (from the up scan's end)
    returns to the non-impacting orbit, with the orbit it held just before.

    A point is impacting if any sampled period has a wall entry (the classification may
    call a slowly converging orbit non-periodic; the impact count is unambiguous).
    """
    su = up.sel(direction="up")
    sd = down.sel(direction="down")
    sig = su["sigma"].values
    hits_up = su["impacts"].values.sum(axis=-1) > 0
    hits_down = sd["impacts"].values.sum(axis=-1) > 0
    first_up = next((float(sig[i]) for i in range(len(sig)) if hits_up[i]), None)
    # walk the down scan from the top until it first stops impacting
    ret = next((i for i in range(len(sig) - 1, -1, -1) if not hits_down[i]), None)
    lowest = None if ret is None or ret + 1 >= len(sig) else ret + 1
    if ret is None and hits_down.any():
        lowest = 0  # impacting down to the end of the range
    per_d, imp_d = sd["period"].values, sd["orbit_impacts"].values
    return {
        "up_first_impacting_sigma": first_up,
        "down_return_to_nonimpacting_sigma": None if ret is None else float(sig[ret]),
        "down_lowest_impacting_sigma": None if lowest is None else float(sig[lowest]),
        "down_orbit_before_return": None if lowest is None else {"period": int(per_d[lowest]),
                                                                   "impacts": int(imp_d[lowest])},
        "hysteresis_width": (None if (first_up is None or lowest is None) else first_up - float(sig[lowest])),
        "grid_step": float(sig[1] - sig[0]),
        # orbits the down scan holds where the up scan does not impact (the hysteresis loop)
        "down_periods_in_hysteresis": sorted({(int(per_d[i]), int(imp_d[i])) for i in range(len(sig))
                                              if hits_down[i] and first_up is not None and sig[i] < first_up}),
        "up": {"sigma": sig, "period": su["period"].values, "impacts": su["orbit_impacts"].values},
        "down": {"sigma": sig, "period": per_d, "impacts": imp_d},
    }


def run(ctx: Context) -> tuple[dict[str, Any], str]:
    r = R_OF[ctx.target]
    cfg = SETTINGS[ctx.quick]
    method = resolve_method(ctx.simulator(), "auto")
    x = x_grid(method, ctx.quick)
    diag_gammas = (10.0, 1e3)
    with concurrent.futures.ThreadPoolExecutor(2) as ex:
        futs = {G: ex.submit(_scan_chain, ctx, r, G, np.linspace(*SIGMA_RANGE[(r, G)], cfg["sigma_num"]), cfg)
                for G in diag_gammas}
        scans = jacobian_scans(ctx, r, x, method)
        check = cross_check(ctx, r) if method == "exact" else None
        chains = {G: f.result() for G, f in futs.items()}
    fits = {G: fit_regimes(x, s, r, G) for G, s in scans.items()}
    hyst = {G: hysteresis(*chains[G]) for G in diag_gammas}
    files = [_plot_jacobian(ctx, r, x, scans, fits), _plot_diagrams(ctx, r, chains)]
    expected_soft = 0.5 if r == 1.0 else -0.5
    summary = {
        "soft": {G: f["soft"]["slope"] for G, f in fits.items() if f["soft"]},
        "hard": {G: f["hard"]["slope"] for G, f in fits.items() if f["hard"]},
    }
    verdict = ("soft slopes " + ", ".join(f"Gamma={G:g}: {s:+.3f}" for G, s in summary["soft"].items())
               + f" (expected {expected_soft:+.1f}); hard slopes "
               + ", ".join(f"Gamma={G:g}: {s:+.3f}" for G, s in summary["hard"].items()) + " (expected -0.5)")
    result = {
        "figure": ctx.target, "verdict": verdict, "expected": {"soft": expected_soft, "hard": -0.5},
        "slopes": fits, "summary": summary, "method": method, "cross_check": check,
        "jacobian": {G: {"x": x, "J": s.J, "P1": s.P1, "error": s.error, "beta": beta_of(x, r, G)}
                     for G, s in scans.items()},
        "hysteresis": hyst, "files": files,
        "parameters": {"nu": NU, "Omega": OMEGA, "r": r, "wall": "compliant", "Gammas": GAMMAS,
                       "Gammas_extra": GAMMAS_EXTRA, "sigma_jacobian": 0.0, "coordinates": "t = n (theta = 0)",
                       "element": "J11 - P11", "soft_beta_max": SOFT_BETA, "hard_beta_min": HARD_BETA,
                       "x_range": X_RANGES[method], "x_num": int(x.size), "sigma_ranges": {str(k[1]): v for k, v in SIGMA_RANGE.items() if k[0] == r},
                       **cfg},
    }
    return result, _report(ctx, result)


def _plot_jacobian(ctx: Context, r: float, x: np.ndarray, scans: dict, fits: dict) -> str:
    from ..io import plots  # noqa: F401  (Agg backend)
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5.5))
    for G, s in scans.items():
        d = np.abs(s.J[:, 0, 0] - s.P1[0, 0])
        extra = G in GAMMAS_EXTRA
        line, = ax.loglog(x, d, "--" if extra else "-", marker="o", ms=3,
                          label=f"Gamma = {G:g}" + (" (beyond the paper)" if extra else ""))
        for name in ("soft", "hard"):
            f = fits[G][name]
            if f:
                lo, hi = f["x_range"]
                ax.axvspan(lo, hi, color=line.get_color(), alpha=0.06)
                # soft slopes at the right end of their range, hard ones at the left end: the hard
                # ranges all end at the largest x, where labels there would sit on each other
                at = hi if name == "soft" else lo
                ax.annotate(f"{f['slope']:+.2f}", (at, np.interp(at, x, d)), textcoords="offset points",
                            xytext=(3, -9) if name == "soft" else (-4, 5), ha="left" if name == "soft" else "right",
                            fontsize=7, color=line.get_color())
    ax.set_xlabel("x (penetration of the wall-free orbit at t = n)")
    ax.set_ylabel("|J11 - P11| (impact contribution, coordinates at t = n)")
    ax.set_title(f"Jacobian of the FMU's map, (nu, Omega) = ({NU}, {OMEGA}), r = {r:g}\n"
                 f"shaded: fitted soft (beta <= {SOFT_BETA:g}) / hard (beta >= {HARD_BETA:g}) ranges, slopes written",
                 fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    path = ctx.out / f"{ctx.target}_jacobian.png"
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path.name


def _plot_diagrams(ctx: Context, r: float, chains: dict) -> str:
    from ..io import plots  # noqa: F401
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(chains), figsize=(11, 4.5))
    for ax, (G, (up, down)) in zip(axes, chains.items()):
        for ds, d, style in ((up, "up", dict(color="tab:blue", marker=".", ms=3)),
                             (down, "down", dict(color="tab:red", marker="x", ms=3))):
            sel = ds.sel(direction=d)
            s = np.broadcast_to(sel["sigma"].values[:, None], sel["u"].shape)
            ax.plot(s.ravel(), sel["u"].values.ravel(), ls="none", alpha=0.6,
                    label=f"continuation {d}" + (" (from the up scan's end)" if d == "down" else ""), **style)
        ax.set_xlabel("sigma")
        ax.set_ylabel("u at t = n + 1/2")
        ax.set_title(f"ODE (FMU), Gamma = {G:g}, r = {r:g}", fontsize=9)
        ax.legend(fontsize=7, markerscale=2)
    fig.tight_layout()
    path = ctx.out / f"{ctx.target}_bifurcation.png"
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path.name


def _fmt(v: Any, spec: str = "+.3f") -> str:
    return "-" if v is None else format(v, spec)


def _what_was_compared(ctx: Context, res: dict[str, Any]) -> list[str]:
    """The title, the parameters, what was compared and the exact-vs-differences cross-check."""
    p = res["parameters"]
    r = p["r"]
    fig = ctx.target
    lines = [
        f"# Figure {fig[-1]}: Jacobian of the FMU's map and the period-3 -> period-1 transition, r = {r:g}",
        "",
        f"Parameters: (nu, Omega) = ({NU}, {OMEGA}), r = {r:g}, compliant wall. {'Quick' if ctx.quick else 'Full'} run.",
        "",
        "## What was compared",
        "",
        "The Jacobian of the FMU's stroboscopic map ("
        + ("the FMU's own derivatives: variational equations with saltation matrices at the wall events"
           if res["method"] == "exact" else "central differences, restarts from perturbed states")
        + f", x = {p['x_range'][0]:g} to {p['x_range'][1]:g}, {p['x_num']} points) along the "
        "grazing family (wall-free state (x, 0) at t = n, sigma = 0), in the paper's coordinates at t = n where J11 "
        "is the singular element (docs/theory.md section 8), against the theory's exponents of the impact contribution "
        f"J11 - P11: soft contacts (beta <= {SOFT_BETA:g}) {res['expected']['soft']:+.1f}, hard contacts "
        f"(beta >= {HARD_BETA:g}) -1/2; beta = r kappa sqrt(8 pi^2 x)/|A|. Fitted where the Jacobian's error estimate "
        "is below 5% of the value, on at least 3 points over a decade of x. 'offset removed': the exponent of "
        "a x^q + b, the regular O(1) part P (N - I) of the impact contribution removed.",
        "",
    ]
    if res["cross_check"]:
        c = res["cross_check"]
        lines += [
            "Cross-check: the exact J11 - P11 against central differences at x = "
            + ", ".join(f"{v:g}" for v in c["x"]) + f", all stiffnesses: largest relative difference "
            f"{c['max_relative_difference']:.1e} (the differences' own error).",
            "",
        ]
    elif res["method"] == "fd":
        lines += ["This FMU does not report its derivatives: the scan stops at x = 1e-5, where the differences "
                  "stop being usable.", ""]
    return lines


def _fitted_slopes(res: dict[str, Any]) -> list[str]:
    """The exponents of J11 - P11 per stiffness, soft and hard contacts apart."""
    lines = [
        "## Fitted slopes",
        "",
        "| Gamma | soft slope | soft, offset removed | soft x range | soft beta range | hard slope | hard, offset removed | hard x range | hard beta range |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for G, f in res["slopes"].items():
        s, h = f["soft"], f["hard"]
        tag = " (beyond the paper)" if G in GAMMAS_EXTRA else ""
        lines.append(
            f"| {G:g}{tag} | {_fmt(s and s['slope'])} | {_fmt(s and s['slope_offset_removed'])} | "
            + ("-" if not s else f"{s['x_range'][0]:.1e}-{s['x_range'][1]:.1e}") + " | "
            + ("-" if not s else f"{s['beta_range'][0]:.2g}-{s['beta_range'][1]:.2g}") + " | "
            + f"{_fmt(h and h['slope'])} | {_fmt(h and h['slope_offset_removed'])} | "
            + ("-" if not h else f"{h['x_range'][0]:.1e}-{h['x_range'][1]:.1e}") + " | "
            + ("-" if not h else f"{h['beta_range'][0]:.2g}-{h['beta_range'][1]:.2g}") + " |")
    return lines + ["", "'-': the regime covers less than a decade of reliable x at this stiffness.", ""]


def _hysteresis_table(res: dict[str, Any]) -> list[str]:
    """Where the up and down scans start and stop impacting, per stiffness."""
    lines = [
        "## Bifurcation diagrams (Gamma = 10 and 1000)",
        "",
        "Up scan from the non-impacting orbit, then down scan from where the up scan ended.",
        "",
        "| Gamma | up scan: first impacting sigma | down scan: lowest impacting sigma (orbit there; period 0: not periodic within the tolerance) | down scan: non-impacting again at | hysteresis width |",
        "|---|---|---|---|---|",
    ]
    for G, h in res["hysteresis"].items():
        orb = h["down_orbit_before_return"]
        orb_s = "-" if orb is None else f"period {orb['period']}, {orb['impacts']} impact(s)"
        lines.append(f"| {G:g} | {_fmt(h['up_first_impacting_sigma'], '.4g')} | "
                     f"{_fmt(h['down_lowest_impacting_sigma'], '.4g')} ({orb_s}) | "
                     f"{_fmt(h['down_return_to_nonimpacting_sigma'], '.4g')} | {_fmt(h['hysteresis_width'], '.3g')} |")
    return lines


def _verdict(fig: str, res: dict[str, Any]) -> list[str]:
    """Soft regime against the theory; the hard regime's approach to -1/2 as the wall stiffens."""
    hard = {G: f["hard"]["slope"] for G, f in res["slopes"].items() if f["hard"]}
    h4 = res["slopes"].get(1e4, {}).get("hard")
    b4 = h4["beta_range"][1] if h4 else float("nan")
    return [
        "",
        "## Verdict, and where theory and FMU disagree",
        "",
        f"Soft regime: {res['verdict'].split('; hard')[0]}. Hard regime: the FMU's exponent approaches -1/2 only "
        "as the wall stiffens: " + ", ".join(f"Gamma = {G:g}: {s:+.3f}" for G, s in hard.items())
        + f". At the paper's stiffest wall (1e4, beta up to {b4:.0f} in the fit) the slope is about "
        f"{_fmt(hard.get(1e4))}, also with the regular O(1) part removed, so the difference from -1/2 is a "
        "finite-stiffness effect, not an offset; it shrinks as Gamma grows (the walls beyond the paper).",
        "",
        f"Figures: `{fig}_jacobian.png` (|J11 - P11| against x, fitted ranges shaded, slopes annotated), "
        f"`{fig}_bifurcation.png` (FMU up/down scans at Gamma = 10 and 1000).",
    ]


def _report(ctx: Context, res: dict[str, Any]) -> str:
    return "\n".join(_what_was_compared(ctx, res) + _fitted_slopes(res) + _hysteresis_table(res)
                     + _verdict(ctx.target, res))
