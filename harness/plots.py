"""Plots (matplotlib, Agg backend, PNG): bifurcation diagram, Poincare section, J(x).

All functions take the harness's Datasets, write a PNG and return its path; they never
open a window (the Agg backend is selected before pyplot is imported).
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import xarray as xr

from .errors import HarnessInputError

import matplotlib
import matplotlib.ticker

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after selecting the backend)

#: Colours of the sweep directions (up and down must be told apart at a glance).
DIRECTION_STYLE = {
    "fresh": dict(color="0.25", marker=".", label="fresh starts"),
    "up": dict(color="tab:blue", marker=".", label="continuation up"),
    "down": dict(color="tab:red", marker="x", label="continuation down"),
}


def _save(fig: plt.Figure, path: str | os.PathLike) -> Path:
    from .outputs import atomic_write

    try:
        with atomic_write(path, "--plot") as tmp:
            fig.savefig(tmp, dpi=130, format=Path(path).suffix.lstrip(".").lower() or "png")
    except ValueError as exc:  # e.g. an image format matplotlib does not know
        raise HarnessInputError("--plot", str(exc)) from None
    finally:
        plt.close(fig)
    return Path(path)


def bifurcation_diagram(ds: xr.Dataset, path: str | os.PathLike, variable: str = "u",
                        scan_index: int = 0) -> Path:
    """u (or v) at the section against the swept parameter, one colour per direction.

    The period of each point is drawn in a strip below, so that period-adding windows and
    hysteresis (up and down disagreeing) are visible directly.
    """
    param = ds.attrs.get("sweep.param") or [d for d in ds[variable].dims if d not in ("direction", "sample")][0]
    data = ds
    scan = ds.attrs.get("sweep.scan_param")
    if isinstance(scan, str) and scan != "none" and scan in ds.dims:
        data = ds.isel({scan: scan_index})
    fig, (ax, axp) = plt.subplots(2, 1, figsize=(8, 6), sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    x = data[param].values
    for direction in data["direction"].values:
        style = dict(DIRECTION_STYLE.get(str(direction), {"label": str(direction)}))
        sel = data.sel(direction=direction)
        y = sel[variable].values  # (param, sample)
        xs = np.repeat(x, y.shape[-1])
        ax.plot(xs, y.ravel(), linestyle="none", markersize=2.5, alpha=0.7, **style)
        axp.plot(x, sel["period"].values, linestyle="-", drawstyle="steps-mid",
                 color=style.get("color"), marker=style.get("marker"), markersize=3)
    ax.set_ylabel(f"{variable} at t = n + {ds.attrs.get('sampling.theta', 0)}")
    ax.legend(loc="best", markerscale=3)
    title = "Bifurcation diagram"
    if scan is not None and scan != "none" and scan in ds.dims:
        title += f" ({scan} = {float(ds[scan].values[scan_index]):g})"
    ax.set_title(title)
    axp.set_ylabel("period (0: none)")
    axp.yaxis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True))
    axp.set_xlabel(param)
    fig.tight_layout()
    return _save(fig, path)


def poincare_section(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """(u, v) samples of a stroboscopic run; impacting periods marked."""
    fig, ax = plt.subplots(figsize=(6, 5))
    hit = ds["impacts"].values > 0
    ax.plot(ds["u"].values[~hit], ds["v"].values[~hit], "o", ms=3, color="tab:blue", label="no impact in the period")
    ax.plot(ds["u"].values[hit], ds["v"].values[hit], "o", ms=3, color="tab:red", label="impact in the period")
    ax.set_xlabel("u")
    ax.set_ylabel("v")
    ax.set_title(f"Poincare section at theta = {ds.attrs.get('sampling.theta', 0)}: {ds.attrs.get('classification', '')}")
    ax.legend(loc="best")
    fig.tight_layout()
    return _save(fig, path)


def jacobian_plot(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """|J - P(1)| element by element against x on log-log axes (slope -1/2: square root)."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    x = ds["x"].values
    dJ = ds["J"].values - ds["P1"].values[None]
    names = {(0, 0): "J11", (0, 1): "J12", (1, 0): "J21", (1, 1): "J22"}
    for (i, j), name in names.items():
        y = np.abs(dJ[:, i, j])
        ok = (x > 0) & (y > 0)
        axes[0].loglog(x[ok], y[ok], "o-", ms=3, label=f"|{name} - P{i+1}{j+1}|")
        axes[1].semilogx(x[x > 0], ds["J"].values[x > 0, i, j], "o-", ms=3, label=name)
    xs = x[x > 0]
    if xs.size:
        ref = np.abs(dJ[:, 0, 0])[x > 0]
        axes[0].loglog(xs, ref[-1] * np.sqrt(xs[-1] / xs), "k--", lw=0.8, label="slope -1/2")
        err = ds["error"].values[x > 0]
        if np.any(err > 0):  # below this line an element is difference noise, not signal
            axes[0].loglog(xs[err > 0], err[err > 0], ":", color="0.5", lw=1.2, label="estimated error of J")
    axes[0].set_xlabel("x (wall-free penetration at t = n)")
    axes[0].set_ylabel("|J - P|")
    axes[0].legend(fontsize=8)
    axes[1].set_xlabel("x")
    axes[1].set_ylabel("J")
    axes[1].legend(fontsize=8)
    fig.suptitle(f"Jacobian of the stroboscopic map, coordinates at theta = {ds.attrs.get('jacobian.theta', 0)}")
    fig.tight_layout()
    return _save(fig, path)


def timeseries_plot(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """u(t) and v(t) of a plain simulation, with the wall at u = 0."""
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
    a1.plot(ds["t"], ds["u"], lw=0.8)
    a1.axhline(0.0, color="k", lw=0.6)
    a1.set_ylabel("u")
    a2.plot(ds["t"], ds["v"], lw=0.8, color="tab:orange")
    a2.set_ylabel("v")
    a2.set_xlabel("t (forcing periods)")
    fig.tight_layout()
    return _save(fig, path)


def period_map(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """2D scan: orbit period over (swept parameter, second parameter), one panel per direction.

    Maximal orbits (one impact per orbit period) are drawn in colour by period; other
    periodic orbits hatched grey; "not periodic" white.
    """
    param = ds.attrs["sweep.param"]
    scan = ds.attrs["sweep.scan_param"]
    directions = list(ds["direction"].values)
    fig, axes = plt.subplots(1, len(directions), figsize=(5 * len(directions), 4.2), squeeze=False)
    x = ds[param].values
    # the second axis usually has few, unevenly spaced values (Gamma = 10, 100, 1000):
    # one row per value, labelled with the value
    y_values = ds[scan].values
    y = np.arange(len(y_values))
    vmax = max(1, int(ds["period"].max()))
    for ax, direction in zip(axes[0], directions):
        sel = ds.sel(direction=direction).transpose(scan, param, ...)
        period = sel["period"].values.astype(float)
        maximal = np.where(sel["orbit_impacts"].values == 1, period, np.nan)
        other = np.where((period > 0) & (sel["orbit_impacts"].values != 1), 1.0, np.nan)
        ax.pcolormesh(x, y, other, cmap="Greys", vmin=0, vmax=2, shading="nearest")
        mesh = ax.pcolormesh(x, y, np.where(maximal > 0, maximal, np.nan), cmap="viridis", vmin=0.5,
                             vmax=vmax + 0.5, shading="nearest")
        ax.set_xlabel(param)
        ax.set_ylabel(scan)
        ax.set_yticks(y, [f"{v:g}" for v in y_values])
        ax.set_title(f"{direction}: period of maximal orbits")
        fig.colorbar(mesh, ax=ax, label="period M (1 impact per M periods)")
    fig.tight_layout()
    return _save(fig, path)
