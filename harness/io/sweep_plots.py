"""Sweep figures for a talk: the bifurcation diagram (with period and Lyapunov panels) and the
2D scan's class map.

* :func:`bifurcation_diagram`: u (or v) at the section against the swept parameter, one colour
  per direction; below it the period M as a number on a linear axis (filled markers: one impact
  per orbit period, the paper's maximal orbits; open circles: more, the count written at the
  start of each run; open squares: no impact, the wall-free orbit); and, when the sweep has Lyapunov exponents, lambda_1 with its error bars, the zero
  line and the chaotic points marked.
* :func:`period_map`: a 2D scan, one panel per direction, one colour per class (each period
  with its impact count, quasi-periodic, chaotic, not converged, invalid start) and a legend
  listing only the classes that occur (:mod:`harness.io.class_map`).
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import xarray as xr

from .class_map import axis_positions, class_legend, draw_class_map, flag_names, orbit_classes, wrap_title
from .plots import DIRECTION_STYLE, _save, parameter_title, plt, section_label


#: Chaotic points in the Lyapunov panel (neither direction's colour).
CHAOTIC_COLOUR = "gold"


def _scan_slice(ds: xr.Dataset, scan_index: int) -> tuple[xr.Dataset, str | None]:
    scan = ds.attrs.get("sweep.scan_param")
    if isinstance(scan, str) and scan != "none" and scan in ds.dims:
        return ds.isel({scan: scan_index}), scan
    return ds, None


def _period_panel(axp: plt.Axes, x: np.ndarray, period: np.ndarray, impacts: np.ndarray, style: dict) -> None:
    """Period M against x: 0 is "none"; open circles where an orbit has more than one impact,
    with the count written where such a run starts; open squares where it has none."""
    colour = style.get("color")
    axp.plot(x, np.where(period >= 0, period, np.nan), linestyle="-", drawstyle="steps-mid", color=colour,
             lw=0.8, alpha=0.5)
    maximal = (period > 0) & (impacts == 1)
    other = (period > 0) & (impacts > 1)
    free = (period > 0) & (impacts == 0)
    axp.plot(x[maximal], period[maximal], linestyle="none", marker="o", ms=4, color=colour)
    axp.plot(x[other], period[other], linestyle="none", marker="o", ms=4, markerfacecolor="white",
             markeredgecolor=colour)
    axp.plot(x[free], period[free], linestyle="none", marker="s", ms=4, markerfacecolor="white",
             markeredgecolor=colour)
    axp.plot(x[period == 0], period[period == 0], linestyle="none", marker="x", ms=4, color=colour)
    previous = None
    for xi, p, k in zip(x, period, impacts):
        if p > 0 and k > 1 and (p, k) != previous:
            axp.annotate(f"{k}", (xi, p), textcoords="offset points", xytext=(0, 4), ha="center", fontsize=7,
                         color=colour)
        previous = (p, k)


def _lyapunov_panel(axl: plt.Axes, x: np.ndarray, lam: np.ndarray, err: np.ndarray, chaotic: np.ndarray,
                    sigmas: float, style: dict) -> None:
    """lambda_1 with error bars of ``sigmas`` standard errors (the classification's band),
    chaotic points as gold stars (a colour no direction uses)."""
    colour = style.get("color")
    ok = np.isfinite(lam)
    axl.errorbar(x[ok], lam[ok], yerr=sigmas * np.nan_to_num(err[ok]), linestyle="-", lw=0.8, marker=".", ms=4,
                 color=colour, ecolor=colour, elinewidth=0.8, capsize=1.5, alpha=0.85)
    chaotic = ok & chaotic
    axl.plot(x[chaotic], lam[chaotic], linestyle="none", marker="*", ms=9, markerfacecolor=CHAOTIC_COLOUR,
             markeredgecolor="black", markeredgewidth=0.5)


def bifurcation_diagram(ds: xr.Dataset, path: str | os.PathLike, variable: str = "u",
                        scan_index: int = 0) -> Path:
    """u (or v) at the section against the swept parameter, the period below it and, when the
    Dataset has exponents, lambda_1 below that; returns the path written (PNG)."""
    param = ds.attrs.get("sweep.param") or [d for d in ds[variable].dims if d not in ("direction", "sample")][0]
    data, scan = _scan_slice(ds, scan_index)
    lyap = "lyapunov" in data
    # the Dataset names its own codes and band (written by harness.runs.sweeps)
    chaotic_codes = [c for c, m in flag_names(data["dynamics"]).items() if m == "chaotic"] if lyap else []
    sigmas = float(data["dynamics"].attrs.get("sigmas", 3.0)) if lyap else 3.0
    ratios = [3, 1.3] + ([1.6] if lyap else [])
    fig, axes = plt.subplots(len(ratios), 1, figsize=(8, 6.8 if lyap else 6), sharex=True,
                             gridspec_kw={"height_ratios": ratios})
    ax, axp = axes[0], axes[1]
    x = data[param].values
    for direction in data["direction"].values:
        style = dict(DIRECTION_STYLE.get(str(direction), {"label": str(direction)}))
        sel = data.sel(direction=direction)
        y = sel[variable].values  # (param, sample)
        ax.plot(np.repeat(x, y.shape[-1]), y.ravel(), linestyle="none", markersize=2.5, alpha=0.7, **style)
        _period_panel(axp, x, sel["period"].values.astype(int), sel["orbit_impacts"].values.astype(int), style)
        if lyap:
            _lyapunov_panel(axes[2], x, sel["lyapunov"].values[:, 0], sel["lyapunov_err"].values[:, 0],
                            np.isin(sel["dynamics"].values, chaotic_codes), sigmas, style)
    ax.set_ylabel(section_label(variable, ds.attrs.get("sampling.theta", 0)))
    ax.legend(loc="best", markerscale=3, fontsize=8)
    title = f"Bifurcation diagram over {param}"
    if scan is not None:
        title += f" ({scan} = {float(ds[scan].values[scan_index]):g})"
    params = parameter_title(ds.attrs, (param,) + ((scan,) if scan else ()))
    ax.set_title(wrap_title(title + (f"\n{params}" if params else ""), 80), fontsize=10)
    from matplotlib.ticker import FuncFormatter, MaxNLocator

    axp.yaxis.set_major_locator(MaxNLocator(integer=True, nbins=6, min_n_ticks=2))
    axp.yaxis.set_major_formatter(FuncFormatter(lambda v, _: "none" if v == 0 else f"{v:g}"))
    top = max(1, int(np.max(data["period"].values, initial=1)))
    axp.set_ylim(-0.6, top * 1.15 + 0.6)
    axp.set_ylabel("period M", fontsize=9)
    axp.text(1.0, 1.02, "filled: 1 impact per orbit; open circle: more (count written); open square: no impact; "
             "x: no period",
             transform=axp.transAxes, ha="right", va="bottom", fontsize=7, color="0.3")
    if lyap:
        axl = axes[2]
        axl.axhline(0.0, color="black", lw=0.8)
        axl.set_ylabel("lambda_1\n(per period)", fontsize=9)
        axl.text(1.0, 1.02, f"bars: {sigmas:g} standard errors; stars: chaotic", transform=axl.transAxes, ha="right",
                 va="bottom", fontsize=7, color="0.3")
    axes[-1].set_xlabel(param)
    fig.tight_layout()
    return _save(fig, path)


def period_map(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """2D scan: one colour per class of orbit over (swept parameter, second parameter), one
    panel per direction, a legend with every class that occurs; returns the path written."""
    param = ds.attrs["sweep.param"]
    scan = ds.attrs["sweep.scan_param"]
    directions = list(ds["direction"].values)
    data = ds.transpose("direction", scan, param, ...)
    dyn = data["dynamics"].values if "dynamics" in data else None
    codes, classes = orbit_classes(data["period"].values, data["orbit_impacts"].values, dyn,
                                   flag_names(data["dynamics"]) if dyn is not None else None)
    fig, axes = plt.subplots(1, len(directions), figsize=(4.6 * len(directions) + 2.2, 4.6), squeeze=False)
    x = ds[param].values
    y_values = ds[scan].values
    y, scale = axis_positions(y_values)
    for j, (ax, direction) in enumerate(zip(axes[0], directions)):
        draw_class_map(ax, x, np.log10(y) if scale == "log" else y, codes[j], classes)
        ax.set_xlabel(param)
        ax.set_ylabel(scan)
        if scale != "linear":  # one row per value, labelled with it (at most ~12 labels)
            step = max(1, len(y_values) // 12)
            pos = np.log10(y) if scale == "log" else y
            ax.set_yticks(pos[::step], [f"{v:g}" for v in y_values[::step]])
        ax.set_title(str(direction), fontsize=9)
    class_legend(axes[0][-1], classes, title="orbit (share of the grid)")
    params = parameter_title(ds.attrs, (param, scan))
    fig.suptitle(wrap_title(f"Orbits over ({param}, {scan})" + (f": {params}" if params else ""),
                            40 + 45 * len(directions)), fontsize=10)
    fig.tight_layout()
    return _save(fig, path)
