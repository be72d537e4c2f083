"""Plots (matplotlib, Agg backend, PNG): Poincare section, J(x), time series; the sweep figures
are in :mod:`harness.io.sweep_plots`, class maps in :mod:`harness.io.class_map`.

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
        from ..config.defaults import wall_name

        try:
            name = wall_name(int(wall))
        except (TypeError, ValueError):
            name = str(wall)
        name = "no wall" if name == "none" else f"{name} wall"
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
    if "exponent" in ds:  # the fitted regimes: range shaded, exponent +- standard error
        for k, regime in enumerate(ds["regime"].values):
            q, se = float(ds["exponent"].values[k]), float(ds["exponent_stderr"].values[k])
            if np.isfinite(q):
                lo, hi = float(ds["fit_x_min"].values[k]), float(ds["fit_x_max"].values[k])
                axes[0].axvspan(lo, hi, color=("tab:green", "tab:purple", "tab:olive")[k % 3], alpha=0.08,
                                label=f"fit ({regime}): |J11 - P11| ~ x^({q:+.3f} +- {se:.1g})")
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
