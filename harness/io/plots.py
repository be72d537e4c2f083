"""Plots (matplotlib, Agg backend, PNG): bifurcation diagram, Poincare section, J(x).

All functions take the harness's Datasets, write a PNG and return its path; they never
open a window (the Agg backend is selected before pyplot is imported).
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import xarray as xr

from ..errors import HarnessInputError

import matplotlib

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


WALL_NAMES = {0: "no wall", 1: "compliant wall", 2: "rigid wall"}


def parameter_title(attrs: dict, exclude: tuple[str, ...] = ()) -> str:
    """The run's physical parameters as a title line, e.g. ``"nu = 4.605, Omega = 0.3059
    ((alpha, gamma) = (0.99, 0.01)), r = 0.9, compliant wall Gamma = 10"``; parameters
    in ``exclude`` (the swept ones) are left out."""
    m = {k[len("model."):]: v for k, v in attrs.items() if k.startswith("model.")}
    parts = []
    if "nu" in m and "Omega" in m and not {"nu", "Omega"} & set(exclude):
        from mapcheck.linear import alpha_gamma

        a, g = alpha_gamma(float(m["nu"]), float(m["Omega"]))
        parts.append(f"nu = {float(m['nu']):.4g}, Omega = {float(m['Omega']):.4g} "
                     f"((alpha, gamma) = ({float(a):.3g}, {float(g):.3g}))")
    else:
        parts += [f"{k} = {float(m[k]):.4g}" for k in ("nu", "Omega") if k in m and k not in exclude]
    parts += [f"{k} = {float(m[k]):.4g}" for k in ("sigma", "r") if k in m and k not in exclude]
    wall = m.get("wall")
    if wall is not None and "wall" not in exclude:
        try:
            name = WALL_NAMES.get(int(wall), f"wall {wall}")
        except (TypeError, ValueError):
            name = f"{wall} wall"
        if name == "compliant wall" and "Gamma" in m and "Gamma" not in exclude:
            name += f" Gamma = {float(m['Gamma']):.4g}"
        parts.append(name)
    return ", ".join(parts)


def section_label(variable: str, theta: float) -> str:
    """Axis label of a stroboscopic sample, e.g. "position u at t = n + 1/2 (n = 0, 1, ...)"."""
    what = {"u": "position u", "v": "velocity v"}.get(variable, variable)
    theta = float(theta)
    phase = "t = n" if theta == 0 else ("t = n + 1/2" if theta == 0.5 else f"t = n + {theta:g}")
    return f"{what} at {phase}"


def period_labels(period: np.ndarray, impacts: np.ndarray) -> tuple[np.ndarray, list[str]]:
    """Rows of the period strip: one per (period M, impacts k per orbit period), labelled
    "M(k)" (so a period-2 orbit with one impact, "2(1)", is told from one with two, "2(2)");
    row 0 is "none" (no period found).  Returns (row index per point, labels)."""
    period = np.asarray(period).astype(int)
    impacts = np.asarray(impacts).astype(int)
    pairs = sorted({(int(p), int(k)) for p, k in zip(period.ravel(), impacts.ravel()) if p > 0})
    index = {pk: i + 1 for i, pk in enumerate(pairs)}
    rows = np.array([index.get((int(p), int(k)), 0) for p, k in zip(period.ravel(), impacts.ravel())],
                    dtype=float).reshape(period.shape)
    return rows, ["none"] + [f"{p}({k})" for p, k in pairs]


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
    rows, labels = period_labels(data["period"].values, data["orbit_impacts"].values)
    directions = list(data["direction"].values)
    for j, direction in enumerate(directions):
        style = dict(DIRECTION_STYLE.get(str(direction), {"label": str(direction)}))
        sel = data.sel(direction=direction)
        y = sel[variable].values  # (param, sample)
        xs = np.repeat(x, y.shape[-1])
        ax.plot(xs, y.ravel(), linestyle="none", markersize=2.5, alpha=0.7, **style)
        axp.plot(x, np.take(rows, j, axis=data["period"].dims.index("direction")), linestyle="-",
                 drawstyle="steps-mid", color=style.get("color"), marker=style.get("marker"), markersize=3)
    ax.set_ylabel(section_label(variable, ds.attrs.get("sampling.theta", 0)))
    ax.legend(loc="best", markerscale=3)
    exclude = (param,) + ((scan,) if isinstance(scan, str) else ())
    title = f"Bifurcation diagram over {param}"
    if scan is not None and scan != "none" and scan in ds.dims:
        title += f" ({scan} = {float(ds[scan].values[scan_index]):g})"
    params = parameter_title(ds.attrs, exclude)
    ax.set_title(title + (f"\n{params}" if params else ""), fontsize=10)
    axp.set_ylabel("period M\n(impacts per period)", fontsize=9)
    axp.set_yticks(range(len(labels)), labels, fontsize=8 if len(labels) < 12 else 6)
    axp.set_ylim(-0.5, len(labels) - 0.5)
    axp.set_xlabel(param)
    fig.tight_layout()
    return _save(fig, path)


def poincare_section(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """(u, v) samples of a stroboscopic run; impacting periods marked."""
    fig, ax = plt.subplots(figsize=(6, 5))
    hit = ds["impacts"].values > 0
    ax.plot(ds["u"].values[~hit], ds["v"].values[~hit], "o", ms=3, color="tab:blue", label="no impact in the period")
    ax.plot(ds["u"].values[hit], ds["v"].values[hit], "o", ms=3, color="tab:red", label="impact in the period")
    theta = ds.attrs.get("sampling.theta", 0)
    ax.set_xlabel(section_label("u", theta))
    ax.set_ylabel(section_label("v", theta))
    params = parameter_title(ds.attrs)
    ax.set_title(f"Poincare section: {ds.attrs.get('classification', '')}" + (f"\n{params}" if params else ""),
                 fontsize=10)
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
    params = parameter_title(ds.attrs, ("sigma",))
    fig.suptitle(f"Jacobian of the stroboscopic map, coordinates at theta = {ds.attrs.get('jacobian.theta', 0)}"
                 + (f"\n{params}" if params else ""), fontsize=10)
    fig.tight_layout()
    return _save(fig, path)


def timeseries_plot(ds: xr.Dataset, path: str | os.PathLike) -> Path:
    """u(t) and v(t) of a plain simulation, with the wall at u = 0."""
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
    a1.plot(ds["t"], ds["u"], lw=0.8)
    a1.axhline(0.0, color="k", lw=0.6)
    a1.set_ylabel("position u (wall at 0)")
    params = parameter_title(ds.attrs)
    if params:
        a1.set_title(params, fontsize=10)
    a2.plot(ds["t"], ds["v"], lw=0.8, color="tab:orange")
    a2.set_ylabel("velocity v")
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
        params = parameter_title(ds.attrs, (param, scan))
        ax.set_title(f"{direction}: period of maximal orbits" + (f"\n{params}" if params else ""), fontsize=9)
        fig.colorbar(mesh, ax=ax, label="period M (1 impact per M periods)")
    fig.tight_layout()
    return _save(fig, path)
