"""Plots of the map-vs-ODE window comparison (:mod:`harness.analysis.windows.compare_windows`).

Every title names the parameter set; axes carry natural labels.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from mapcheck.bifurcation import PiecewiseMap, orbit_diagram
from mapcheck.compare import phase_to_natural
from mapcheck.windows import MapParams, window_1d

__all__ = ["plot_all"]


def labels_for(problem: Any) -> dict[str, str]:
    """Legend labels of the four sources for a ``WindowProblem``."""
    eq = problem.coefficient_eq()
    wall = f"Gamma = {problem.Gamma:g}" if problem.wall == "compliant" else "rigid wall"
    return {"ode": f"ODE (FMU, {wall}, shooting)", "theory_64": f"(64), rho(sigma) from {eq}",
            "map": f"2D map (37)/(38) with {eq}", "map_A_tilde": f"2D map (37)/(38) with {eq}, A~(sigma)"}


def _wrap(text: str, width: int = 90) -> str:
    import textwrap

    return "\n".join(textwrap.wrap(text, width))


def _save(fig, path) -> str:
    import matplotlib.pyplot as plt

    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path.name


def plot_all(ctx: Any, problem: Any, st: Any, ds: Any, windows: dict[str, Any],
             applies: dict[str, str | None] | None = None, every: list[dict[str, Any]] | None = None) -> list[str]:
    """TARGET_map.png (map, linear rho and A~), TARGET_ode.png (FMU up/down), TARGET_windows.png.

    A map variant that does not apply (``applies[variant]`` a reason) is not drawn: its panel
    says why; when neither 2D map applies, TARGET_map.png is not written."""
    applies = applies or {}
    from ...io import plots  # noqa: F401  (selects the Agg backend)

    try:
        c = problem.coefficients()
    except (ValueError, ArithmeticError):
        c = None
    # a figure of two "does not apply" panels shows nothing: left out (the report says why)
    maps = ([_plot_maps(ctx, problem, st, c, applies)]
            if c is not None and not (applies.get("map") and applies.get("map_A_tilde")) else [])
    return maps + [_plot_ode_scans(ctx, problem, st, ds, windows, c, applies),
                   _plot_windows(ctx, problem, st, windows, applies, every)]


def _plot_maps(ctx: Any, problem: Any, st: Any, c: Any, applies: dict[str, str | None]) -> str:
    """TARGET_map.png: the map's bifurcation diagram with rho linear in sigma and with A~(sigma),
    the (64) window edges over it."""
    import matplotlib.pyplot as plt

    eq = problem.coefficient_eq()
    params = problem.describe()
    grid = st.scan_grid
    n_map = int(st.extra.get("map_points", 4 * len(grid) + 1))
    sig = np.geomspace(grid[0], grid[-1], n_map) if st.log_sigma else np.linspace(grid[0], grid[-1], n_map)
    fig, axes = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    for ax, variant, key, what in ((axes[0], "paper", "map", f"rho linear in sigma {eq}"),
                                   (axes[1], "tilde", "map_A_tilde", f"rho with |A~(sigma)|, {eq}")):
        if c is None or applies.get(key):
            ax.text(0.5, 0.5, "map does not apply:\n" + _wrap(applies.get(key) or "no coefficients"),
                    ha="center", va="center", transform=ax.transAxes, fontsize=8)
            ax.set_title(f"map (37)/(38), {what}\n{params}", fontsize=9)
            ax.set_xlim(float(grid[0]), float(grid[-1]))
            continue
        f = PiecewiseMap(MapParams.from_coefficients(c))
        with np.errstate(all="ignore"):
            od = orbit_diagram(f, c.rho(sig, variant), 0.0, 0.0, n_transient=400, n_keep=32, mode="down")
        x = od.x[:, 0, :]
        # an iterate that ran away (the map has no bounded attractor there) is not a point of it
        x = np.where(np.isfinite(x) & (np.abs(x) < 1e3), x, np.nan)
        ax.plot(np.repeat(sig, x.shape[-1]), x.ravel(), ",", color="k", alpha=0.6,
                label="map iterates (down scan; runaway iterates left out)")
        first = True
        for M in (range(1, (problem.M_max or 8) + 1) if not applies.get("theory_64") else ()):
            lo, hi = window_1d(M)
            if lo > hi:
                continue
            for rho_edge in (lo, hi):
                if math.isfinite(rho_edge):
                    s_edge = float(c.sigma_of_rho(rho_edge, variant))
                    if math.isfinite(s_edge) and grid[0] <= s_edge <= grid[-1]:
                        ax.axvline(s_edge, color="tab:green", lw=0.8, ls="--", label="(64) window edges" if first else None)
                        first = False
        ax.set_ylabel("x, pre-impact position (natural coordinates)")
        ax.set_title(f"map (37)/(38), {what}\n{params}", fontsize=9)
        ax.legend(loc="lower left", fontsize=8)
    axes[1].set_xlabel("forcing amplitude above grazing, sigma")
    if st.log_sigma:
        axes[1].set_xscale("log")
    fig.tight_layout()
    return _save(fig, ctx.out / f"{ctx.target}_map.png")


def _plot_ode_scans(ctx: Any, problem: Any, st: Any, ds: Any, windows: dict[str, Any], c: Any,
                    applies: dict[str, str | None]) -> str:
    """TARGET_ode.png: the FMU's up/down scans (in the A~ map's natural coordinates where that
    map applies) with the shooting's window edges."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4.8))
    for direction, style in (("up", dict(color="tab:blue", marker=".", ms=2)),
                             ("down", dict(color="tab:red", marker="x", ms=2))):
        sel = ds.sel(direction=direction)
        s = np.broadcast_to(sel["sigma"].values[:, None], sel["u"].shape)
        x = sel["u"].values
        if c is not None and not applies.get("map_A_tilde"):
            x, _ = phase_to_natural(sel["u"].values, sel["v"].values, s, c, problem.theta, "tilde")
        ax.plot(s.ravel(), x.ravel(), ls="none", alpha=0.6, label=f"FMU, sigma stepped {direction}", **style)
    first = True
    for M, w in windows["ode"].items():
        for e in (w or ()):
            if e is not None:
                ax.axvline(e, color="tab:green", lw=0.8, ls="--", label="ODE window edges (shooting)" if first else None)
                first = False
    ax.set_xlabel("forcing amplitude above grazing, sigma")
    ax.set_ylabel("x, pre-impact position\n(natural coordinates, A~)" if c is not None and not applies.get("map_A_tilde")
                  else f"u at t = n + {problem.theta:g}")
    if st.log_sigma:
        ax.set_xscale("log")
    ax.set_title(f"ODE (FMU): quasi-static up/down scans\n{problem.describe()}", fontsize=9)
    ax.legend(loc="lower left", fontsize=8, markerscale=3)
    fig.tight_layout()
    return _save(fig, ctx.out / f"{ctx.target}_ode.png")


def _window_rows(windows: dict[str, Any], applies: dict[str, str | None], every: list[dict[str, Any]] | None,
                 labels: dict[str, str]) -> list[tuple[str, list[tuple[float | None, float | None, int]]]]:
    """The rows of the windows figure: one per ODE attractor (period M, k impacts; the wall-free
    orbit included), then one per map that applies (its maximal windows)."""
    from .summary import attractor_label

    rows = []
    if every is not None:
        for e in every:
            if e.get("resolved"):
                rows.append((f"ODE: {attractor_label(e['M'], e['impacts'])}", [(e["lo"], e["hi"], e["M"])], False))
    else:
        rows.append((labels["ode"], [(w[0], w[1], M) for M, w in windows["ode"].items() if w is not None], False))
    for k in ("theory_64", "map", "map_A_tilde"):
        if not applies.get(k):
            rows.append((labels[k], [(w[0], w[1], M) for M, w in windows[k].items() if w is not None], True))
    return rows


def bar_lanes(spans: list[tuple[float, float]]) -> tuple[list[int], int]:
    """A lane for each interval (lo, hi) of one row such that intervals in one lane do not overlap
    (the first lane free at its start, in order of the starts), and the number of lanes used."""
    order = sorted(range(len(spans)), key=lambda j: spans[j])
    ends: list[float] = []  # the right end of each lane so far
    lane = [0] * len(spans)
    for j in order:
        lo, hi = spans[j]
        k = next((k for k, e in enumerate(ends) if e < lo), len(ends))
        if k == len(ends):
            ends.append(hi)
        ends[k] = hi
        lane[j] = k
    return lane, max(1, len(ends))


def _plot_windows(ctx: Any, problem: Any, st: Any, windows: dict[str, Any], applies: dict[str, str | None],
                  every: list[dict[str, Any]] | None = None) -> str:
    """TARGET_windows.png: every window, one row per ODE attractor and per map that applies; an
    end beyond the searched range is drawn to the axis' edge with an arrow, never left out."""
    import matplotlib.pyplot as plt

    x_lo, x_hi = float(st.sigma_range[0]), float(st.sigma_range[1])
    # the maps' windows are searched over their own (positive) sigma grid: an open lower end is
    # below that grid's start, not below the plot's
    map_lo = max(x_lo, float(st.table_grid[0]))
    rows = _window_rows(windows, applies, every, labels_for(problem))
    fig, ax = plt.subplots(figsize=(8, 1.6 + 0.45 * max(1, len(rows))))
    cmap = plt.get_cmap("tab10")
    seen: set[int] = set()
    for i, (_, wins, is_map) in enumerate(rows):
        bars = [((map_lo if is_map else x_lo) if lo is None else max(lo, x_lo), x_hi if hi is None else min(hi, x_hi),
                 lo, hi, M) for lo, hi, M in wins]
        bars = [b for b in bars if b[1] >= b[0]]  # a window wholly outside the plotted range is not drawn
        lane, n_lanes = bar_lanes([(a, b) for a, b, *_ in bars])
        for (a, b, lo, hi, M), k in zip(bars, lane):
            # overlapping windows of one row (a map's period-1 and period-2 windows) side by side in
            # lanes of the row, each visible
            y = i + (k - 0.5 * (n_lanes - 1)) * 0.7 / n_lanes
            ax.plot([a, b], [y, y], lw=8 / n_lanes, solid_capstyle="butt", color=cmap((M - 1) % 10),
                    label=f"period {M}" if M not in seen else None)
            seen.add(M)
            for end, open_, sign in ((a, lo is None or lo < x_lo, -1), (b, hi is None or hi > x_hi, 1)):
                if open_:  # beyond the searched (or plotted) range: an arrow to its end
                    ax.annotate("", xy=(end, y), xytext=(end - sign * 0.04 * (x_hi - x_lo), y),
                                arrowprops=dict(arrowstyle="->", lw=1.5, color="k"))
    ax.set_yticks(range(len(rows)), [r[0] for r in rows], fontsize=8)
    ax.set_xlabel("forcing amplitude above grazing, sigma")
    if st.log_sigma and x_lo > 0:
        ax.set_xscale("log")
    ax.set_xlim(x_lo, x_hi)
    ax.set_ylim(-0.6, len(rows) - 0.4)
    if not any(w for _, w, _ in rows):
        ax.text(0.5, 0.5, "no stable window in the searched range", transform=ax.transAxes, ha="center")
    ax.set_title("Stable windows in sigma (an arrow: the window goes on beyond the searched range)\n"
                 f"{problem.describe()}", fontsize=9)
    if seen:  # the periods in increasing order
        h, lab = ax.get_legend_handles_labels()
        order = sorted(range(len(lab)), key=lambda j: int(lab[j].split()[-1]))
        ax.legend([h[j] for j in order], [lab[j] for j in order], loc="upper center", bbox_to_anchor=(0.5, -0.25),
                  fontsize=8, ncol=8, frameon=False)
    fig.tight_layout()
    return _save(fig, ctx.out / f"{ctx.target}_windows.png")
