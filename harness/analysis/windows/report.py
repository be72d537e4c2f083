"""report.md of ``impact-harness windows``: what was compared, the table of window edges from
the four sources, the scans, the differences and the verdict."""
from __future__ import annotations

import math
from typing import Any

from mapcheck.compare import markdown_window_table

from ..context import Context
from .plots import labels_for
from .summary import attractor_label

#: Map variants (keys in the JSON); the coefficient equation depends on the wall.
VARIANT_KEYS = ("theory_64", "map", "map_A_tilde")
#: Classification tolerance of the scans (relative to the orbit's size ~ 1 + sigma).
SCAN_TOL = 1e-4


def _fmt_tol(xtol: Any) -> str:
    if isinstance(xtol, dict):
        return ", ".join(f"M = {M}: {t:.2g}" for M, t in xtol.items()) or "no window bisected"
    return f"{xtol:g}"


def _cmplx(m: Any) -> str:
    if m is None:
        return "-"
    vals = [complex(*x) if isinstance(x, (list, tuple)) else complex(x) for x in m]
    return ", ".join(f"{z.real:+.3f}" if abs(z.imag) < 1e-9 else f"{z.real:+.3f}{z.imag:+.3f}i" for z in vals)


def _all_windows_table(res: dict[str, Any], f: str) -> list[str]:
    """Every ODE window: any number of impacts per period, with kinds and multipliers."""
    rows = res["ode_windows_all"]
    if not rows:
        return []
    out = ["| period M | impacts per period | window in sigma | edge kinds (lower/upper) | multipliers inside "
           "(at the seed) | found by | basin share |", "|---|---|---|---|---|---|---|"]
    for e in rows:
        if not e["resolved"] and e.get("transient_of") == "not periodic":
            out.append(f"| {e['M']} | {e['impacts']} | no such orbit: a transient the scans misclassified at sigma = "
                       f"{e['seed_sigma']:{f}} (Newton found no period-{e['M']} orbit there; run on "
                       f"{e['transient_periods']} periods from the scan's state, the flow settles on no period up to "
                       "24) | - | - | " + ", ".join(e["found_by"]) + " |")
            continue
        if not e["resolved"] and e.get("transient_of"):
            M2, k2 = e["transient_of"]
            out.append(f"| {e['M']} | {e['impacts']} | no such orbit: a transient the scans misclassified at sigma = "
                       f"{e['seed_sigma']:{f}} (Newton found no period-{e['M']} orbit there; run on "
                       f"{e['transient_periods']} periods from the scan's state, it reaches {attractor_label(M2, k2)}, "
                       "listed) | - | - | " + ", ".join(e["found_by"]) + " |")
            continue
        if not e["resolved"]:
            out.append(f"| {e['M']} | {e['impacts']} | Newton did not converge from the scan's state at sigma = "
                       f"{e['seed_sigma']:{f}} | - | - | {', '.join(e['found_by'])} | {_share(e, f)} |")
            continue
        lo = "below the search range" if e["lo"] is None else format(e["lo"], f)
        hi = "above the search range" if e["hi"] is None else format(e["hi"], f)
        out.append(f"| {e['M']} | {e['impacts']} | [{lo}, {hi}]{_located(e)} | {e['kinds'][0]}/{e['kinds'][1]} | "
                   f"{_cmplx(e.get('multipliers_inside'))} (sigma = {e['seed_sigma']:{f}}) | {', '.join(e['found_by'])} "
                   f"| {_share(e, f)} |")
    return out


def _share(e: dict[str, Any], f: str) -> str:
    """The window's basin share in the global search: largest, where, and the mean."""
    b = e.get("basin_share")
    if not b:
        return "-"
    if b["max"] == 0:
        return f"no start reached it ({b['values']} searched sigma)"
    return (f"{100 * b['max']:.3g} % at sigma = {b['at_sigma']:{f}} (mean {100 * b['mean']:.3g} % over "
            f"{b['values']} searched sigma)")


def _found_only_by_search(res: dict[str, Any]) -> list[str]:
    """The note at the top: attractors that only the global search found (the scans missed them)."""
    rows = [e for e in res.get("ode_windows_all", []) if list(e.get("found_by", [])) == ["global search"]]
    gs = res.get("global_search")
    if not gs:
        return ["**No global search was run** (--global-starts 0): only the attractors the scans' paths cross "
                "are listed.", ""]
    if not rows:
        return [f"Every attractor the global search found ({gs['starts_per_value']} fresh starts at each sigma of "
                "the grid) was also found by another route.", ""]
    names = "; ".join(f"period {e['M']} with {e['impacts']} impacts" + (
        f" in [{e['lo']:.6g}, {e['hi']:.6g}]" if e.get("resolved") and None not in (e.get("lo"), e.get("hi")) else "")
        + (f", basin share up to {100 * e['basin_share']['max']:.3g} %" if e.get("basin_share") else "")
        for e in rows)
    return [f"**The global search found {len(rows)} attractor{'s' if len(rows) > 1 else ''} that no other route "
            f"found**: {names}.", ""]


def _located(e: dict[str, Any]) -> str:
    """' (lower edge: the flip of period 2 (2/1))' where an edge was located once for two windows."""
    by = dict(e.get("located_by") or {})
    for k, how in zip(("lo", "hi"), e.get("located") or ()):
        if how.startswith("bisection") and k not in by:
            by[k] = how  # not located by the continuation: said, never silently
    return "".join(f" ({'lower' if k == 'lo' else 'upper'} edge: {by[k]})" for k in ("lo", "hi") if k in by)


def _how_found(ctx: Context, problem: Any, res: dict[str, Any], title: str | None) -> list[str]:
    """The title, the parameters, and how the ODE's windows were found and the maps compared."""
    p = res["parameters"]
    eq = problem.coefficient_eq()
    g0, g1, gn = p["sigma_grid"]
    grid_txt = (f"geometric grid of {gn} points, {res['scan_grid_step']:.3g} relative step" if res["scan_grid_geometric"]
                else f"grid of {gn} points, step {res['scan_grid_step']:.3g}")
    rho = "" if p["rho_per_sigma"] is None else f"; rho/sigma = {p['rho_per_sigma']:.6g} from {eq}"
    return [
        f"# {title or 'Windows of periodic orbits: the ODE, and the maps beside it'}",
        "",
        f"Parameters: {problem.describe()} -> nu = {p['nu']:.6f}, Omega = {p['Omega']:.6f}{rho}. "
        f"{'Quick' if ctx.quick else 'Full'} run.",
        "",
        *_found_only_by_search(res),
        "## How the ODE's windows were found",
        "",
        f"From the ODE alone: quasi-static up and down scans of the FMU over sigma in [{g0:.4g}, {g1:.4g}] "
        f"({grid_txt}, {p['transient']} transient periods per point, periods classified up to "
        f"{p['M_scan_limit']}) give every stable periodic orbit with impacts that they reach; each (period M, "
        "impacts per period) seen is then solved by Newton on the FMU's stroboscopic M-period map "
        f"(phase {problem.theta}, {p['shooting_derivatives']} Jacobian) and continued in sigma both ways (pseudo-"
        f"arclength, as `continue` does; search range [{p['shooting_sigma_range'][0]:.4g}, "
        f"{p['shooting_sigma_range'][1]:.4g}]). An orbit belongs to the window while it is stable, has the same "
        "number of impacts per period and minimal period M; each edge is the first event on the way: a flip or fold "
        "located on its test function (det(D + I), det(D - I)) to 1e-9, a graze on its defining quantity (the gap of "
        "a free passage, the entry velocity of a contact, reaching 0), reported as the midpoint of an interval that "
        "holds it, in quick and full runs alike. Where the continuation could not settle an edge, the edge is the "
        "midpoint of a bracket marched and bisected to xtol "
        f"({p['shooting_xtol_rule']}: {_fmt_tol(p['shooting_xtol'])}), and the table of every window says so; an "
        "edge not found inside the search range is reported as beyond it, never as a number. Windows narrower than the "
        "scan step can be missed by the scans: the maps' windows that the scans did not see were tried as extra "
        "Newton starts (marked 'map-guided start'); the ODE decides whether the orbit is there.",
        "",
        "Beside the scans, a global search at every sigma of the grid starts afresh from a grid plus random states "
        "over the region the attractors occupy (the wall-free orbit's, widened, and the scans' orbits there), each "
        "iterated to its attractor with the early stop of `basins`; every periodic orbit it reaches is a route to a "
        "window like the scans' (marked 'global search'), and its basin share is the fraction of those starts that "
        "reached it. Orbits of one kind (period, impacts) are one attractor only where their stroboscopic point sets "
        "coincide: two coexisting orbits of a kind are two windows. Where sigma < 0, the wall-free orbit is listed "
        "whatever the scans saw ('wall-free orbit').",
        "",
        "The maps are only compared with the ODE's windows (docs/theory.md explains each):",
        "",
        f"- **(64)**: rho in [1/(4M), 1/M^2] of the strongly damped 1D map, with rho(sigma) linear from {eq};",
        f"- **2D map**: (37)/(38) with {eq}, closed-form maximal orbits, edges by bisection;",
        "- **2D map, A~(sigma)**: the same with |A~(sigma)| = (1+sigma) 4 pi^2 - sigma Omega^2 in rho.",
        "",
    ]


def _where_maps_apply(res: dict[str, Any], labels: dict[str, str]) -> list[str]:
    applies = res.get("map_applicability", {})
    lines = ["## Where the maps apply", ""]
    for k in VARIANT_KEYS:
        why = applies.get(k)
        lines.append(f"- {labels[k]}: " + ("applies." if why is None else f"**does not apply**: {why}."))
    return lines


def _maximal_windows(res: dict[str, Any], labels: dict[str, str], digits: int) -> list[str]:
    """The table of the maximal windows from the four sources, the ODE's edge kinds, and where
    period adding truncates (``--M-max auto``)."""
    p = res["parameters"]
    table = markdown_window_table(res["windows"], labels, digits=digits, na=res.get("map_applicability", {}))
    lines = [
        "",
        "## Stable windows of maximal orbits (one impact per period), in sigma",
        "",
        table,
        "",
        "'none' in the ODE row: no stable maximal orbit of that period was seen by the scans or found from the "
        f"maps' starts in the searched range; 'none' in a map row: the map has no such window in sigma "
        f"[{p['map_sigma_range'][0]:.3g}, {p['map_sigma_range'][1]:.3g}]; n/a: the map does not apply (above).",
    ]
    kinds = res["edge_kinds"]["ode"]
    if kinds:
        lines += ["", "ODE edge kinds (lower/upper): " + ", ".join(f"M = {M}: {k[0]}/{k[1]}" for M, k in kinds.items())]
    return lines


def _every_window(res: dict[str, Any], f: str) -> list[str]:
    g0, g1, _ = res["parameters"]["sigma_grid"]
    lines = ["", "## Every periodic window of the ODE (any number of impacts per period)", ""]
    lines += (_all_windows_table(res, f)
              or [f"No stable periodic orbit with impacts was seen in sigma [{g0:.4g}, {g1:.4g}]."])
    aside = res.get("ode_set_aside") or []
    if aside:
        lines += ["", "Sampled orbits that are not windows (Newton on the FMU did not resolve them; listed in "
                  "`windows.json` under `ode_set_aside`): " + "; ".join(
                      f"period {a['M']}, {a['impacts']} impacts, seen in [{a['seen'][0]:{f}}, {a['seen'][1]:{f}}] "
                      f"by {', '.join(a['found_by'])} ({a['why']})" for a in aside) + "."]
    return lines


def _scan_confirmation(res: dict[str, Any], f: str) -> list[str]:
    """The shooting's edges against the scans' (empty when the ODE has no maximal window)."""
    conf = [(M, cf) for M, cf in res["scan_confirmation"].items() if res["windows"]["ode"].get(M)]
    if not conf:
        return []
    lines = ["", "## Confirmation by the up/down scans", "",
             "| M | shooting | lowest point in down scan | highest point in up scan |", "|---|---|---|---|"]
    for M, cf in conf:
        w = res["windows"]["ode"][M]
        lo = "beyond the range" if w[0] is None else format(w[0], f)
        hi = "beyond the range" if w[1] is None else format(w[1], f)
        lo_s = "not seen" if cf["scan_lower"] is None else (
            f"{cf['scan_lower']:{f}} ({cf['lower_minus_shooting']:+.2g})" if cf["lower_minus_shooting"] is not None
            else f"{cf['scan_lower']:{f}}")
        hi_s = "-" if w[1] is None else ("not seen" if cf["scan_upper"] is None else
                                         f"{cf['scan_upper']:{f}} ({cf['upper_minus_shooting']:+.2g})")
        lines.append(f"| {M} | [{lo}, {hi}] | {lo_s} | {hi_s} |")
    return lines + ["", "Scan minus shooting, in sigma. A scan edge is a grid point, so it lies up to one step inside "
                    "the true edge; near a flip the decaying period-2M oscillation needs many periods to fall below "
                    f"the classification tolerance ({SCAN_TOL:g}), so the down scan may lose period M some steps "
                    "inside the window (critical slowing down)."]


def _disagreement(res: dict[str, Any], labels: dict[str, str]) -> list[str]:
    """Map edge minus ODE edge per variant and period (empty when nothing was compared)."""
    diffs = res["differences_to_ode"]
    Ms = [M for M, w in res["windows"]["ode"].items() if w is not None]
    if not (diffs and Ms):
        return []
    lines = ["", "## Where the maps and the ODE disagree", "",
             "| variant | " + " | ".join(f"M = {M} (lo, hi)" for M in Ms) + " | max abs |",
             "|---|" + "---|" * (len(Ms) + 1)]
    for name, d in diffs.items():
        cells = [("-" if d[M][0] is None else f"{d[M][0]:+.4g}") + ", " + ("-" if d[M][1] is None else f"{d[M][1]:+.4g}")
                 for M in Ms]
        score = res["max_abs_difference_to_ode"][name]
        score_txt = "no end to compare" if score is None or math.isnan(score) else f"{score:.4g}"
        lines.append(f"| {labels[name]} | " + " | ".join(cells) + f" | {score_txt} |")
    return lines + ["", "(map edge minus ODE edge, in sigma; -: an end open (beyond the range) in one source and "
                    "not in the other, or both open, which counts as agreement; inf: a window the ODE has is missing "
                    "in the map.)"]


def _coexistence(res: dict[str, Any]) -> list[str]:
    """Where the ODE's attractors coexist (from the table of every window)."""
    from .summary import fmt_sigma

    rows = res.get("coexistence", [])
    lines = ["", "## Coexisting attractors (bistability)", ""]
    if not rows:
        return lines + ["No two stable attractors coexist in the searched range (as far as the scans saw)."]
    lines += ["| sigma from | to | attractors |", "|---|---|---|"]
    lines += [f"| {fmt_sigma(c['lo'], 'below')} | {fmt_sigma(c['hi'], 'above')} | {'; '.join(c['attractors'])} |"
              for c in rows]
    return lines + ["", "Overlaps of the windows in the table above; which attractor a run reaches there depends on "
                    "where it starts (`impact-harness basins`)."]


def _verdict(ctx: Context, res: dict[str, Any]) -> list[str]:
    """The summary (each sentence derived from the tables above) and the figures."""
    lines = ["", "## Verdict", ""] + [f"- {line}" for line in res["summary"]]
    what = {"map": "the maps' bifurcation diagrams", "ode": "the FMU's up/down scans", "windows": "the windows"}
    figs = [f"`{f}` ({what.get(f[len(ctx.target) + 1:-4], 'figure')})" for f in res.get("files", []) if f.endswith(".png")]
    return lines + ["", "Figures: " + ", ".join(figs) + ("" if any("_map.png" in f for f in figs) else
                                                           "; no map figure: no 2D map applies (above)") + "."]


def report(ctx: Context, problem: Any, res: dict[str, Any], title: str | None = None) -> str:
    """report.md: the ODE's windows (every attractor seen, shot to its edges), where each map
    applies, the table, the scans, the differences, the verdict."""
    labels = labels_for(problem)
    ode_los = [w[0] for w in res["windows"]["ode"].values() if w and w[0]]
    digits = 4 if min(ode_los or [1.0]) > 0.01 else 6
    f = f".{digits}f"
    lines = (_how_found(ctx, problem, res, title) + _where_maps_apply(res, labels)
             + _maximal_windows(res, labels, digits) + _every_window(res, f) + _scan_confirmation(res, f)
             + _coexistence(res) + _disagreement(res, labels) + _verdict(ctx, res))
    return "\n".join(lines)
