"""The basin figure: one colour per attractor, each attractor's stroboscopic points drawn in its
basin's colour with a marker of its own (outlined, so that a point is seen on any background),
neutral colours for the starts that reach no periodic orbit, the run's parameters in the title;
beside it the zoom into a sub-rectangle when the scan has one (its frame drawn on the whole
grid), and the uncertainty exponent's fit, log f(eps) against log eps, when it was measured."""
from __future__ import annotations

import json
import textwrap
from pathlib import Path
from typing import Any

import numpy as np

from .plots import _save, parameter_title, plt  # plt: the Agg backend, selected once for the package

#: Colours of the codes below 0 (not periodic, invalid, sticking/chatter, escaped): neutral,
#: outside the attractors' palette.
CODE_COLOURS = {-1: "#c8c8c8", -2: "#000000", -3: "#8c6d31", -4: "#ff00ff"}
CODE_NAMES = {-1: "not periodic", -2: "invalid start", -3: "sticking or chatter", -4: "escaped or failed"}
#: One marker per attractor (cycled), so that attractors stay apart in print in black and white.
MARKERS = "osD^vP*X<>"


def _colours(n: int) -> list[Any]:
    palette = plt.get_cmap("tab10" if n <= 10 else "tab20")
    return [palette(i % palette.N) for i in range(n)]


def _draw_basins(ax: Any, u0: np.ndarray, v0: np.ndarray, labels: np.ndarray, colours: list[Any]) -> None:
    from matplotlib.colors import ListedColormap

    codes = sorted(CODE_COLOURS)  # -4 .. -1, then the attractors
    cmap = ListedColormap([CODE_COLOURS[c] for c in codes] + colours)
    ax.pcolormesh(u0, v0, (labels - codes[0]).T, cmap=cmap, vmin=-0.5, vmax=len(codes) + len(colours) - 0.5,
                  shading="nearest", rasterized=True)
    ax.set_xlim(u0[0], u0[-1])
    ax.set_ylim(v0[0], v0[-1])
    ax.set_xlabel("u0 (displacement at t = theta)")
    ax.set_ylabel("v0 (velocity at t = theta)")


def _draw_points(ax: Any, ds: Any, colours: list[Any], box: tuple[float, float, float, float]) -> None:
    """Each attractor's points inside ``box`` (u1, u2, v1, v2), in its basin's colour."""
    for i in range(ds.sizes.get("attractor_index", 0)):
        p = int(ds["attractor_period"].values[i])
        pts = ds["attractor_points"].values[i, :p]
        inside = (pts[:, 0] >= box[0]) & (pts[:, 0] <= box[1]) & (pts[:, 1] >= box[2]) & (pts[:, 1] <= box[3])
        ax.plot(pts[inside, 0], pts[inside, 1], linestyle="none", marker=MARKERS[i % len(MARKERS)], markersize=9,
                markerfacecolor=colours[i], markeredgecolor="white", markeredgewidth=2.2, zorder=3)
        ax.plot(pts[inside, 0], pts[inside, 1], linestyle="none", marker=MARKERS[i % len(MARKERS)], markersize=9,
                markerfacecolor="none", markeredgecolor="black", markeredgewidth=0.9, zorder=4)


def _legend(ds: Any, labels: np.ndarray, colours: list[Any]) -> list[Any]:
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    names = json.loads(ds.attrs["basins.attractors"])
    total = labels.size
    fr = dict(zip(ds["basin_class"].values.tolist(), ds["basin_fraction_err"].values.tolist())) \
        if "basin_class" in ds else {}
    handles = []
    for i, name in enumerate(names):
        share = int(np.sum(labels == i)) / total
        err = f" +- {fr[i]:.2%}" if i in fr else ""
        handles.append(Line2D([], [], color=colours[i], marker=MARKERS[i % len(MARKERS)], markersize=9, linewidth=8,
                              markeredgecolor="black", label=f"{name}: {share:.1%}{err}"))
    for code, colour in CODE_COLOURS.items():
        count = int(np.sum(labels == code))
        if count:
            handles.append(Patch(facecolor=colour, edgecolor="black", label=f"{CODE_NAMES[code]}: {count / total:.1%}"))
    return handles


def _draw_uncertainty(ax: Any, ds: Any, suffix: str, colour: str, name: str) -> None:
    """f(eps) of the grid (eps in cells, drawn as a fraction of the box's side) and its fit."""
    cells = min(ds.sizes[f"u0{suffix}"], ds.sizes[f"v0{suffix}"]) - 1
    steps = ds[f"uncertainty_step{suffix}"].values / max(cells, 1)
    frac = ds[f"uncertainty_fraction{suffix}"].values
    ok = np.isfinite(frac) & (frac > 0)
    if not ok.any():
        return
    pre = f"basins{suffix}."
    alpha, err = ds.attrs[pre + "uncertainty_exponent"], ds.attrs[pre + "uncertainty_exponent_err"]
    ax.loglog(steps[ok], frac[ok], "o", color=colour, label=f"{name}: alpha = {alpha:.2f} +- {err:.2f}"
              if np.isfinite(alpha) else f"{name}: no fit")
    if np.isfinite(alpha):
        lo, hi = (x / max(cells, 1) for x in json.loads(ds.attrs[pre + "uncertainty_fit_cells"]))
        _fit_line(ax, steps, frac, ok, (lo, hi), alpha, colour)


def _fit_line(ax: Any, eps: np.ndarray, frac: np.ndarray, ok: np.ndarray, fit: tuple[float, float], alpha: float,
              colour: str) -> None:
    use = ok & (eps >= fit[0] * (1 - 1e-9)) & (eps <= fit[1] * (1 + 1e-9))
    if use.any():
        c = np.mean(np.log(frac[use]) - alpha * np.log(eps[use]))
        x = np.array(fit, dtype=float)
        ax.loglog(x, np.exp(c) * x ** alpha, "-", color=colour, linewidth=1.2)


def _draw_pairs(ax: Any, ds: Any) -> None:
    """f(eps) from random pairs, with binomial error bars, and its fit."""
    eps, frac = ds["pairs_eps"].values, ds["pairs_uncertain_fraction"].values
    err = ds["pairs_uncertain_fraction_err"].values
    ok = frac > 0
    alpha = ds.attrs["basins.pairs_uncertainty_exponent"]
    ax.errorbar(eps[ok], frac[ok], yerr=err[ok], fmt="s", color="tab:blue", markersize=4, capsize=2,
                label=f"random pairs: alpha = {alpha:.2f} +- {ds.attrs['basins.pairs_uncertainty_exponent_err']:.2f}"
                if np.isfinite(alpha) else "random pairs: no fit")
    if np.isfinite(alpha):
        _fit_line(ax, eps, frac, ok, tuple(json.loads(ds.attrs["basins.pairs_fit_eps"])), alpha, "tab:blue")


def basin_figure(ds: Any, path: str | Path) -> str:
    """Draw the basins of a :func:`harness.runs.basins.scan.run_basins` (or
    :func:`harness.runs.basins.kernel_scan.run_basins_kernel`) Dataset to ``path`` (PNG).

    Returns the path written.
    """
    labels = ds["attractor"].values  # (u0, v0)
    zoom = "attractor_zoom" in ds
    n_extra = len(json.loads(ds.attrs.get("basins.zoom_attractors", "[]"))) if zoom else 0
    colours = _colours(max(ds.sizes.get("attractor_index", 0), n_extra))
    fit = "uncertainty_fraction" in ds
    panels = 1 + zoom + fit
    widths = [1.0] * (1 + zoom) + ([0.8] if fit else [])
    fig, axes = plt.subplots(1, panels, figsize=(6.0 * (1 + zoom) + 4.6 * fit, 6.6), squeeze=False,
                             gridspec_kw={"width_ratios": widths})
    ax = axes[0, 0]
    u0, v0 = ds["u0"].values, ds["v0"].values
    _draw_basins(ax, u0, v0, labels, colours)
    _draw_points(ax, ds, colours, (u0[0], u0[-1], v0[0], v0[-1]))
    ax.set_title(f"{len(u0)} x {len(v0)} starts", fontsize=10)
    if zoom:
        zu, zv = ds["u0_zoom"].values, ds["v0_zoom"].values
        from matplotlib.patches import Rectangle

        ax.add_patch(Rectangle((zu[0], zv[0]), zu[-1] - zu[0], zv[-1] - zv[0], fill=False, edgecolor="black",
                               linewidth=1.5, linestyle="--", zorder=5))
        az = axes[0, 1]
        _draw_basins(az, zu, zv, ds["attractor_zoom"].values, colours)
        _draw_points(az, ds, colours, (zu[0], zu[-1], zv[0], zv[-1]))
        az.set_title(f"zoom: u0 in [{zu[0]:g}, {zu[-1]:g}], v0 in [{zv[0]:g}, {zv[-1]:g}] ({len(zu)} x {len(zv)})",
                     fontsize=10)
    if fit:
        af = axes[0, -1]
        _draw_uncertainty(af, ds, "", "black", "whole grid")
        if zoom and "uncertainty_fraction_zoom" in ds:
            _draw_uncertainty(af, ds, "_zoom", "tab:red", "zoom (its own box)")
        if "pairs_uncertain_fraction" in ds:
            _draw_pairs(af, ds)
        af.set_xlabel("eps (fraction of the box's side)")
        af.set_ylabel("f(eps): share of eps-uncertain starts")
        af.set_title("uncertainty exponent: f ~ eps^alpha", fontsize=10)
        af.legend(fontsize=8, loc="upper left")
        af.grid(True, which="both", alpha=0.3)
    head = f"Basins of attraction at t = n + {float(ds.attrs.get('sampling.theta', 0.0)):g}: "
    extra = ""
    if "basins.entropy" in ds.attrs:
        extra = f"; S_b = {ds.attrs['basins.entropy']:.3f}, S_bb = {ds.attrs['basins.boundary_entropy']:.3f}"
    fig.suptitle("\n".join(textwrap.wrap(head + parameter_title(ds.attrs) + extra, 110)), fontsize=11)
    fig.legend(handles=_legend(ds, labels, colours), loc="lower center", ncol=3, fontsize=9, frameon=False,
               title="attractor (its stroboscopic points; share of the starts, standard error)", title_fontsize=9)
    fig.tight_layout(rect=(0, 0.12, 1, 0.93))
    return str(_save(fig, path))
