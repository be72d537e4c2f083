"""report.md of ``impact-harness windows``: what was compared, the table of window edges from
the four sources, the scans, the differences and the verdict."""
from __future__ import annotations

from typing import Any

from mapcheck.compare import markdown_window_table

from . import Context
from .windows_plots import labels_for

#: Map variants (keys in the JSON); the coefficient equation depends on the wall.
VARIANT_KEYS = ("theory_64", "map", "map_A_tilde")
#: Classification tolerance of the scans (relative to the orbit's size ~ 1 + sigma).
SCAN_TOL = 1e-4


def _span(values: list) -> str:
    v = [x for x in values if x is not None]
    return "none measured" if not v else f"{min(v):+.4g} to {max(v):+.4g}"


def _fmt_tol(xtol: Any) -> str:
    if isinstance(xtol, dict):
        return ", ".join(f"M = {M}: {t:.2g}" for M, t in xtol.items())
    return f"{xtol:g}"


def report(ctx: Context, problem: Any, res: dict[str, Any], title: str | None = None) -> str:
    """report.md: what was compared, the table, the scans, the differences, the verdict."""
    labels = labels_for(problem)
    p = res["parameters"]
    digits = 4 if min([w[0] for w in res["windows"]["map_A_tilde"].values() if w] or [1.0]) > 0.01 else 6
    table = markdown_window_table(res["windows"], labels, digits=digits)
    eq = problem.coefficient_eq()
    grid_txt = (f"geometric grid, {res['scan_grid_step']:.3g} relative step" if res["scan_grid_geometric"]
                else f"{res['scan_grid_step']:.3g} grid")
    lines = [
        f"# {title or 'Windows of maximal period-M orbits: maps vs ODE'}",
        "",
        f"Parameters: {problem.describe()} -> nu = {p['nu']:.6f}, Omega = {p['Omega']:.6f}; "
        f"rho/sigma = {p['rho_per_sigma']:.6g} from {eq}. {'Quick' if ctx.quick else 'Full'} run.",
        "",
        "## What was compared",
        "",
        "The sigma-edges of the stable maximal period-M windows (one impact per M forcing periods), from four "
        "sources (docs/theory.md explains each):",
        "",
        f"- **(64)**: rho in [1/(4M), 1/M^2] of the strongly damped 1D map, with rho(sigma) linear from {eq};",
        f"- **2D map**: (37)/(38) with {eq}, closed-form maximal orbits, edges by bisection;",
        "- **2D map, A~(sigma)**: the same with |A~(sigma)| = (1+sigma) 4 pi^2 - sigma Omega^2 in rho;",
        f"- **ODE**: the FMU. Newton shooting on its stroboscopic M-period map at phase {problem.theta} (one impact "
        "per period), started inside the A~ map's window; lower edges where a multiplier leaves the unit circle, "
        "upper edges where an extra contact appears. Each edge is the midpoint of a bracket that the shooting "
        f"found and bisected to xtol ({_fmt_tol(p['shooting_xtol'])}); an edge it could not bracket is "
        f"'unresolved'. Confirmed by quasi-static up/down scans on a {grid_txt} ({p['transient']} transient "
        "periods per point).",
        "",
        "## Window edges in sigma",
        "",
        table,
        "",
        "ODE edge kinds (lower, upper): " + ", ".join(f"M = {M}: {k[0]}/{k[1]}" for M, k in res["edge_kinds"]["ode"].items()),
    ]
    if res["ode_unresolved"]:
        lines += ["", "Unresolved ODE edges (no bracket inside the search range "
                  f"[{p['shooting_sigma_range'][0]:.4g}, {p['shooting_sigma_range'][1]:.4g}]; last sigma with a "
                  "stable maximal orbit given): " + "; ".join(
                      f"M = {M} {side}: beyond {res['ode_edge_intervals'][M][0 if side == 'lower' else 1][0]}"
                      if res["ode_edge_intervals"][M][0 if side == "lower" else 1][0] is not None
                      else f"M = {M} {side}: no stable maximal orbit found in the map's window"
                      for M, sides in res["ode_unresolved"].items() for side in sides)]
    lines += [
        "",
        "## Confirmation by the up/down scans",
        "",
        "| M | shooting | lowest point in down scan | highest point in up scan |",
        "|---|---|---|---|",
    ]
    f = f".{digits}f"
    for M, cf in res["scan_confirmation"].items():
        w = res["windows"]["ode"][M]
        if w is None:
            continue
        lo = "unresolved" if w[0] is None else format(w[0], f)
        hi = "none" if w[1] is None else format(w[1], f)
        lo_s = "not seen" if cf["scan_lower"] is None else f"{cf['scan_lower']:{f}} ({cf['lower_minus_shooting']:+.2g})" \
            if cf["lower_minus_shooting"] is not None else f"{cf['scan_lower']:{f}}"
        hi_s = "-" if w[1] is None else ("not seen" if cf["scan_upper"] is None else
                                         f"{cf['scan_upper']:{f}} ({cf['upper_minus_shooting']:+.2g})")
        lines.append(f"| {M} | [{lo}, {hi}] | {lo_s} | {hi_s} |")
    lines += [
        "",
        f"Scan minus shooting, in sigma. Lower edges: "
        f"{_span([cf['lower_minus_shooting'] for cf in res['scan_confirmation'].values()])}; upper edges: "
        f"{_span([cf['upper_minus_shooting'] for cf in res['scan_confirmation'].values()])}. "
        "A scan edge is a grid point, so it lies up to one step inside the true edge. Near a flip the multiplier "
        "is near -1 and the decaying period-2M oscillation needs many periods to fall below the classification "
        f"tolerance ({SCAN_TOL:g}), so the down scan loses period M some steps inside the window (critical "
        "slowing down); near an upper edge one grid step can knock the orbit onto a coexisting attractor, so the "
        "up scan may leave the window early.",
        "",
        "## Where the maps and the ODE disagree",
        "",
        "| variant | " + " | ".join(f"M = {M} (lo, hi)" for M in res["windows"]["ode"]) + " | max abs |",
        "|---|" + "---|" * (len(res["windows"]["ode"]) + 1),
    ]
    for name, d in res["differences_to_ode"].items():
        cells = []
        for M in res["windows"]["ode"]:
            lo, hi = d[M]
            cells.append(("-" if lo is None else f"{lo:+.4g}") + ", " + ("-" if hi is None else f"{hi:+.4g}"))
        lines.append(f"| {labels[name]} | " + " | ".join(cells) + f" | {res['max_abs_difference_to_ode'][name]:.4g} |")
    mmax = {k: max([M for M, w in ws.items() if w is not None and w[0] is not None and (w[1] is None or w[1] >= w[0])]
                   or [0]) for k, ws in res["windows"].items()}
    best = res["best_variant"]
    lines += [
        "",
        "(map edge minus ODE edge, in sigma; inf: a window the ODE has is missing in the variant.)",
        "",
        "## Verdict",
        "",
        f"{labels[best]} agrees best with the ODE: largest edge difference "
        f"{res['max_abs_difference_to_ode'][best]:.2g} in sigma (variant `{best}`). "
        f"Highest period with a stable maximal window: (64) M = {mmax['theory_64']}, 2D map M = {mmax['map']}, "
        f"2D map with A~ M = {mmax['map_A_tilde']}, ODE M = {mmax['ode']} (searched up to M = {problem.M_max}).",
        "",
        f"Figures: `{ctx.target}_map.png` (the map's bifurcation diagrams, rho linear and with A~), "
        f"`{ctx.target}_ode.png` (the FMU's up/down scans in natural coordinates), `{ctx.target}_windows.png` "
        "(the four window tables).",
    ]
    return "\n".join(lines)


# ----------------------------------------------------------------------------------------
# One call
# ----------------------------------------------------------------------------------------
