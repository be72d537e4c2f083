"""What ``impact-harness chart`` writes (:func:`chart`): chart.json, the plot (:func:`plot_chart`)
and the report (:func:`chart_report`) of :func:`harness.analysis.chart.run.run_chart`."""
from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from ...errors import HarnessInputError
from .run import ChartProblem, run_chart
from .window_region import closing_evidence_lines

__all__ = ["plot_chart", "chart_figure", "chart_report", "chart", "sigma_limits"]


LINESTYLES = {"flip": "-", "fold": "-.", "ns": ":", "graze": "--", "stick": "--"}


def plot_chart(res: dict[str, Any], problem: ChartProblem, path: Path, title: str) -> None:
    """Draw :func:`chart_figure` into ``path``."""
    import matplotlib.pyplot as plt

    fig = chart_figure(res, problem, title)
    fig.savefig(path, dpi=130, bbox_inches="tight")
    plt.close(fig)


def chart_figure(res: dict[str, Any], problem: ChartProblem, title: str) -> Any:
    """sigma against the second parameter: the windows' edges continued in two parameters (lines,
    by kind; where each window closes starred, a hand-over of its boundary crossed), the per-value scans' windows beneath as bands (the
    brute-force check), the windows of maps (48) and (39) as thin lines, and beta in a second panel."""
    from ...io import plots  # noqa: F401  (Agg backend)
    import matplotlib.pyplot as plt

    from .wall_free import WALL_FREE, WALL_FREE_LABEL, draw_wall_free

    fig, (ax, bx) = plt.subplots(2, 1, figsize=(12, 9.5), sharex=True, gridspec_kw={"height_ratios": [3, 1.2]})
    cmap = plt.get_cmap("tab10")
    # a log sigma axis above grazing; an even one where the chart reaches sigma <= 0
    log_sigma = float(problem.sigma_grid[0]) > 0
    bottom, top = sigma_limits(res, problem, log_sigma)
    for M, cv in res["scans"].items():
        # the wall-free window ("1/0") in grey, apart from period 1 with an impact
        col = cmap((int(M) - 1) % 10) if M != WALL_FREE else "0.45"
        if cv["value"]:
            v = np.array(cv["value"])
            lo = np.array([np.nan if x is None else x for x in cv["lower"]], float)
            hi = np.array([np.nan if x is None else x for x in cv["upper"]], float)
            ax.fill_between(v, np.where(np.isfinite(lo), lo, bottom), np.where(np.isfinite(hi), hi, top), color=col,
                            alpha=0.15, lw=0, label=f"scans, M = {M}" if M != WALL_FREE else f"scans, {WALL_FREE_LABEL}")
            _open_end_arrows(ax, v, lo, hi, bottom, top, col, log_sigma)
            beta = np.array([np.nan if b is None else b for b in cv["beta"]], float)
            if np.any(np.isfinite(beta)):
                bx.plot(v, beta, "o-", color=col, ms=3, label=f"M = {M}")
        for key, ls in (("map_48", (0, (1, 1))), ("map_39", (0, (3, 1, 1, 1)))):
            mw = res["maps"][key].get(M, {"value": []})
            for edge in ("lower", "upper") if mw["value"] else ():
                y = np.array([np.nan if x is None else x for x in mw[edge]], float)
                ax.plot(mw["value"], y, ls=ls, color=col, lw=0.7, alpha=0.8,
                        label=f"map ({key[-2:]}), A~" if edge == "lower" and M == "1" else None)
    _draw_continued(ax, res["windows"], problem.param2, cmap, bottom, top)
    draw_wall_free(ax, res.get("wall_free"))
    if log_sigma:
        ax.set_yscale("log")
    else:
        ax.axhline(0.0, color="0.5", lw=0.6, ls=":")  # grazing: the wall-free orbit touches the wall
    ax.set_ylim(bottom, top)
    ax.set_ylabel("forcing above grazing, sigma")
    ax.set_title(title, fontsize=9)
    grid = problem.sigma_grid
    if ax.lines or ax.collections:  # outside the axes: the structure keeps the plot's space
        ax.legend(fontsize=7, ncol=1, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    else:  # a blank panel says why
        ax.text(0.5, 0.5, f"no stable maximal window (one impact per period, M <= {problem.M_max})\nin sigma "
                f"[{grid[0]:.3g}, {grid[-1]:.3g}] at any value of {problem.param2}: nothing to chart",
                transform=ax.transAxes, ha="center", va="center", fontsize=9)
    if not bx.lines:
        bx.text(0.5, 0.5, "beta (43): compliant wall only, at the seed of a window found by the scans; none here",
                transform=bx.transAxes, ha="center", va="center", fontsize=8)
    bx.axhline(1.0, color="k", lw=0.8, ls=":")
    bx.set_ylabel("beta = r v_c kappa / |A~|\n(at each window's seed)", fontsize=8)
    bx.set_yscale("log")
    bx.set_xlabel(problem.param2)
    if problem.log:
        bx.set_xscale("log")
    if bx.get_legend_handles_labels()[0]:
        bx.legend(fontsize=7, ncol=1, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    fig.tight_layout()
    return fig


def sigma_limits(res: dict[str, Any], problem: ChartProblem, log_sigma: bool) -> tuple[float, float]:
    """The sigma axis' limits from the data drawn: every continued edge point, every edge the scans
    located and every closing, with a margin (a twentieth of the span; on a log axis in ln sigma),
    within the scans' grid widened by its own span (an edge run off far beyond it is drawn to the
    axis' edge, not given the plot)."""
    g0, g1 = float(problem.sigma_grid[0]), float(problem.sigma_grid[-1])
    ys: list[float] = []
    for w in res.get("windows", []):
        for _, c in _all_curves(w):
            if c and "failed" not in c:
                ys += [float(y) for y in c["sigma"]]
    for cv in res.get("scans", {}).values():
        ys += [float(y) for k in ("lower", "upper") for y in cv.get(k, []) if y is not None]
    wf = (res.get("wall_free") or {}).get("curves", {}).get("upper") or {}
    ys += [float(y) for y in wf.get("sigma", [])]
    ys += [float(cl["sigma"]) for cl in res.get("closes", {}).values() if cl.get("sigma") is not None]
    if log_sigma:
        lo_cap, hi_cap = g0 / 10.0, g1 * 10.0
        ys = [y for y in ys if math.isfinite(y) and lo_cap <= y <= hi_cap]
        if not ys:
            return g0, g1 * 4.0
        a, b = math.log(min(ys)), math.log(max(ys))
        m = max(0.05 * (b - a), 0.1)
        return math.exp(a - m), math.exp(b + m)
    span = g1 - g0
    ys = [y for y in ys if math.isfinite(y) and g0 - span <= y <= g1 + span]
    if not ys:
        return g0, g1 + 0.25 * span
    a, b = min(ys), max(ys)
    m = max(0.05 * (b - a), 1e-3 * span)
    return max(a - m, -1.0), b + m


def _draw_continued(ax: Any, windows: list[dict[str, Any]], param2: str, cmap: Any, bottom: float,
                    top: float) -> None:
    """The continued edges of every window (hand-overs included), each closing starred and each
    hand-over of a boundary crossed."""
    seen: set[str] = set()
    for w in windows:
        col = cmap((w["M"] - 1) % 10)
        for side, c in _all_curves(w):
            if not c or "failed" in c:
                continue
            lab = f"{c['kind']} edge (continued)" if c["kind"] not in seen else None
            seen.add(c["kind"])
            ax.plot(c["p2"], c["sigma"], LINESTYLES.get(c["kind"], "-"), color=col, lw=2.0, label=lab)
        cl = w["closing"]
        for c in cl.get("codim2", []):  # a hand-over of the boundary: the window goes on past it
            if c["kind"].startswith("boundary hand-over") and bottom <= c["sigma"] <= top:
                ax.plot([c["p2"]], [c["sigma"]], "X", color=col, ms=9, mec="k", zorder=5)
        if cl["closes"] is not None:
            ax.plot([cl["closes"]], [min(cl["sigma"], top)], "*", color=col, ms=13, mec="k", zorder=5)
            clipped = cl["sigma"] >= top  # an asymptote: the star sits on the top of the axes
            ax.annotate(f"M = {w['M']} closes\n{param2} = {cl['closes']:.5g}", (cl["closes"], min(cl["sigma"], top)),
                        textcoords="offset points", xytext=(12, -30 if clipped else -4), fontsize=7, color=col,
                        bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": col, "lw": 0.5, "alpha": 0.85})


def _open_end_arrows(ax: Any, v: np.ndarray, lo: np.ndarray, hi: np.ndarray, bottom: float, top: float,
                     col: Any, log_sigma: bool = True) -> None:
    """An arrow to the axis' edge at each value whose window goes on beyond the plotted sigma
    range (an end not found in the searched range, or beyond the axis), as windows_windows.png
    draws them: the band then reaches the edge, and the arrow says it does not end there."""
    # arrows of one length in axes units, on a log or an even sigma axis
    span = math.log(top / bottom) if log_sigma else top - bottom
    for x, a, b in zip(v, lo, hi):  # a value is listed only where the window is present
        for end, beyond, sign in ((bottom, not np.isfinite(a) or a < bottom, -1), (top, not np.isfinite(b) or b > top, 1)):
            if beyond:
                tail = end * math.exp(-sign * 0.06 * span) if log_sigma else end - sign * 0.06 * span
                ax.annotate("", xy=(x, end), xytext=(x, tail),
                            arrowprops=dict(arrowstyle="->", lw=1.2, color=col))


def _all_curves(w: dict[str, Any]) -> list[tuple[str, Any]]:
    """A window's continued edges, those continued after each hand-over of its boundary included."""
    sets = [w["curves"], *(h["curves"] for h in w.get("handovers", []))]
    return [(side, cs.get(side)) for cs in sets for side in ("lower", "upper")]


def tolerance_text(problem: ChartProblem) -> str:
    """The fallback bisection's tolerance in words: absolute where ``--xtol`` set one."""
    return f"{problem.xtol_rel:g} x sigma" if problem.xtol is None else f"{problem.xtol:g} in sigma"


def _edge_text(e: Any) -> str:
    return "none in the range" if e is None else f"{e['kind']} {e['sigma']:.7g}"


def _scan_check_lines(res: dict[str, Any], problem: ChartProblem) -> list[str]:
    """The scans' edges against the continued ones, more than 1 % apart (settled at the report's top)."""
    lines = ["", "Scans against the continued edges (at each scanned value, on the edge curves' first monotone "
             "stretch; `scan_check` in chart.json; each disagreement beyond the tolerance is settled by shooting in "
             "the contradictions at the top):", ""]
    for M, chk in res["scan_check"].items():
        bad = chk["disagree"]
        lines.append(f"- M = {M}: largest relative difference {chk['max_rel_diff']:.2g}; "
                     + ("all within 1 %" if not bad else f"{len(bad)} edge(s) differ by more than 1 %: " + "; ".join(
                         f"{problem.param2} = {b['p2']:.4g} {b['side']}: scan {b['scan']:.5g} ({b['scan_kind']}) vs "
                         f"{b['continued']:.5g}" for b in bad[:6]) + (" ..." if len(bad) > 6 else "")))
    return lines


def chart_report(res: dict[str, Any], problem: ChartProblem, command: str) -> str:
    g = problem.sigma_grid
    cs = res["continuation_search"]
    from .closing_routes import closing_route_lines
    from .contradictions import contradiction_lines
    from .wall_free import coexistence_lines, row_label

    lines = [f"# Chart: windows of the ODE over (sigma, {problem.param2})", "",
             # disagreements between the two routes first, each with what settled it
             *closing_route_lines(res["closes"], problem.param2),
             *contradiction_lines(res.get("contradictions", {"found": [], "compared": None}), problem.param2),
             f"Parameters: {named_parameters(problem.params)}; "
             f"{problem.param2} from {problem.values[0]:g} to {problem.values[-1]:g}{' (log)' if problem.log else ''}.", "",
             "## Where each window closes (two-parameter continuation)", "",
             f"Method: at {problem.param2} = {problem.values[0]:g} the stable maximal orbits (one impact per period, "
             f"M <= {problem.M_max}) are found by the ODE alone (up/down/fresh scans over sigma in [{cs['sigma'][0]:.3g}, "
             f"{cs['sigma'][1]:.3g}], {cs['values']} values, and {cs['refined_values']} more in the {cs['refined_intervals']} "
             f"intervals where the attractors change or none is periodic; {cs['transient']} periods of transient), each continued in "
             "sigma to its edges; every edge is continued in (sigma, "
             f"{problem.param2}): flip/fold/NS on the extended system (orbit + test function, pseudo-arclength), "
             "grazes stepped along the curve and located across it (bisection, then secant steps on the gap). "
             "A window closes at the first candidate (an edge curve's turning point, a flip meeting the graze, its lower "
             "edge leaving the sigma range upward) that direct shooting confirms on both sides (below) and no flip/fold/NS "
             "edge curve of the window passes in p2 (every point of one has stable orbits of the window beside it).", "",
             f"| M | window at {problem.param2} = {problem.values[0]:g} | closes at {problem.param2} | sigma there | how |",
             "|---|---|---|---|---|"]
    lines += _closing_table(res, problem)
    lines += closing_evidence_lines(res["closes"], problem.param2)
    lines += _curve_lines(res, problem)
    lines += ["", "Each continued edge checked across itself at every point of its curve up to the window's closing "
              "(the edges continued after a hand-over of its boundary from there) "
              "(Newton 1e-5 away on either side, across the curve "
              f"in (ln sigma, {'ln ' if problem.log else ''}{problem.param2}): a flip has a stable orbit on one side and an unstable one on the other, a graze a "
              "stable orbit on one side and none with its contacts on the other; `edge_check` in chart.json):", ""]
    for M, chk in res["edge_check"].items():
        bad = chk["failed"]
        lines.append(f"- M = {M}: {chk['confirmed']} of {chk['checked']} confirmed"
                     + (f" (the check stopped: {chk['error']})" if chk.get("error") else "")
                     + ("" if not bad else "; not confirmed: " + "; ".join(
                         f"{b['side']} {b['kind']} at {problem.param2} = {b['p2']:.4g}, sigma = {b['sigma']:.5g} "
                         f"(one side: {b['one_side']}, other: {b['other_side']})" for b in bad[:6])))
    lines += ["", "## Brute-force check: windows measured per value", "",
              f"For {len(problem.values)} values, up/down scans of the FMU over sigma in [{g[0]:.3g}, {g[-1]:.3g}] "
              f"({len(g)} points, {'geometric' if g[0] > 0 else 'evenly spaced'}), every attractor seen continued in sigma to its edges (located as `continue` locates events; where the "
              f"continuation fails, bisected to {tolerance_text(problem)}, said in chart.json's `located`). Where a window disappears is bracketed between neighbouring values.", "",
              "| M | present at | disappears (bracket) | edge kinds at the last value | beta range |",
              "|---|---|---|---|---|"]
    for M, cv in res["scans"].items():
        pres = f"{len(cv['present_at'])} of {len(problem.values)}"
        br = cv.get("bracket")
        cl = ("present to the end" if cv["closes"] is None and cv["value"] else
              "never present" if cv["closes"] is None else
              f"{cv['closes']:.4g}" + (f" ([{br[0]:.4g}, {br[1]:.4g}])" if br else ""))
        kinds = "-" if not cv["value"] else f"{cv['kind_lower'][-1]}/{cv['kind_upper'][-1]}"
        b = [x for x in cv["beta"] if x is not None]
        br = "-" if not b else f"{min(b):.3g} to {max(b):.3g}"
        lines.append(f"| {row_label(M)} | {pres} | {cl} | {kinds} | {br} |")
    lines += _scan_check_lines(res, problem)
    lines += coexistence_lines(res.get("coexistence"), problem.param2)
    lines += ["", f"Other windows (more than one impact per period): {len(res['other_windows'])} found (chart.json).",
              "", f"Backend: {res['backend']}; scans {res['seconds']:.1f} s wall ({sum(res['task_seconds']):.1f} s in "
              f"tasks); continuation {res['continuation_seconds']:.1f} s; the wall-free window, contradictions and coexistence "
              f"{res.get('cross_check_seconds', 0.0):.1f} s.", "", f"Run: `{command}`."]
    return "\n".join(lines)


def _closing_table(res: dict[str, Any], problem: ChartProblem) -> list[str]:
    """The rows of the closing table, one per window."""
    lines: list[str] = []
    from .wall_free import row_label

    for M, cl in res["closes"].items():
        win = cl.get("window_at_start")
        wtxt = "none found" if win is None else f"{_edge_text(win[0])} .. {_edge_text(win[1])}"
        if cl["closes"] is None:
            why = cl.get("note") or "; ".join(f"{k}: {v}" for k, v in (cl.get("edges_end") or {}).items())
            lines.append(f"| {row_label(M)} | {wtxt} | does not close in {cl['searched'][0]:g} .. {cl['searched'][1]:g} | - | {why} |")
        else:
            sig = "-" if cl.get("sigma") is None else f"{cl['sigma']:.5g}"
            lines.append(f"| {row_label(M)} | {wtxt} | {cl['closes']:.6g} | {sig} | {cl['how']} |")
    return lines


def _curve_lines(res: dict[str, Any], problem: ChartProblem) -> list[str]:
    """Every edge curve: its end and turning points."""
    lines: list[str] = []
    lines += ["", "Every edge curve (chart.json, `windows[*].curves`; after a hand-over `windows[*].handovers`): "
              "its end and turning points:", ""]
    for w in res["windows"]:
        for side, c in _all_curves(w):
            if c is None:
                continue
            if "failed" in c:
                lines.append(f"- M = {w['M']} {side} ({c['kind']}): not continued: {c['failed']}")
                continue
            turns = "; ".join(f"{t['side']} at ({problem.param2} = {t['p2']:.6g}, sigma = {t['sigma']:.5g})"
                              for t in c["turns"]) or "none"
            lines.append(f"- M = {w['M']} {side} {c['kind']} edge: {len(c['sigma'])} points, turning points / "
                         f"stability changes: {turns}; ends at ({problem.param2} = {c['end']['p2']:.6g}, sigma = "
                         f"{c['end']['sigma']:.5g}): {c['end']['note']}")
    return lines


def chart(problem: ChartProblem, out: str | Path, fmu_path: str | None = None, backend: Any = None,
          workers: int | None = None, scheduler: str | None = None, command: str | None = None, *,
          run: Any = None) -> dict[str, Any]:
    """Run the chart, write chart.json, chart.png and report.md into ``out``; return the result.

    ``problem`` is checked first (:func:`~harness.analysis.chart.problem.check_problem`; build
    one from ranges with :func:`~harness.analysis.chart.problem.chart_problem`).  ``run``: the
    run object (:class:`~harness.runs.experiment.Experiment`: the FMU, backend, workers,
    scheduler) the command line built from its layers; without it one is built from
    ``fmu_path``, ``backend``, ``workers`` and ``scheduler``, with the same defaults and checks.
    ``command``: the command line recorded in the report."""
    from ...runs.experiment import Experiment
    from ..context import to_jsonable
    from .problem import check_problem

    check_problem(problem)
    if run is None:
        run = Experiment.for_python(fmu_path, workers=workers, backend=backend, scheduler=scheduler)
    fmu = run.model
    for k in list(problem.params) + [problem.param2]:
        if k not in fmu.variables:
            raise HarnessInputError("param2" if k == problem.param2 else k, f"{fmu.path.name} has no parameter {k!r}")
    for k, v in problem.params.items():
        fmu.coerce(k, v, k)  # a value the FMU cannot take, refused before any work
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    given = run.given("run", "workers")
    res = run_chart(problem, fmu.source(), run.run.backend if run.given("run", "backend") or run.run.scheduler else None,
                    run.run.workers if given else None, run.run.scheduler)
    command = command or f"chart(problem, out={str(out)!r}) from Python"
    res["parameters"] = {**problem.params, "param2": problem.param2, "values": problem.values, "log": problem.log,
                         "M_max": problem.M_max, "xtol_rel": problem.xtol_rel, "xtol": problem.xtol,
                         "sigma_grid": [float(problem.sigma_grid[0]),
                                                                 float(problem.sigma_grid[-1]), len(problem.sigma_grid)]}
    (out / "chart.json").write_text(json.dumps(to_jsonable(res), indent=1) + "\n")
    title = (f"Edges of the ODE's windows continued in (sigma, {problem.param2}) (thick), per-value scans (bands), "
             f"maps (48)/(39) (thin)\n" + named_parameters({k: v for k, v in problem.params.items()
                                                             if k != problem.param2}, 4))
    plot_chart(res, problem, out / "chart.png", title)
    (out / "report.md").write_text(chart_report(res, problem, command) + "\n")
    return res


def named_parameters(params: dict[str, Any], digits: int = 6) -> str:
    """'nu = 4.60517, ..., wall = compliant, solver = cvode': enums by name, numbers to ``digits``."""
    from ...config.defaults import solver_name, wall_name

    names = {"wall": wall_name, "solver": solver_name}
    return ", ".join(f"{k} = {names[k](v)}" if k in names else
                     (f"{k} = {v:.{digits}g}" if isinstance(v, float) else f"{k} = {v}") for k, v in params.items())

