"""One colour per class, with a discrete legend: 2D scans (period maps) and basins.

A class map draws a grid of integer class codes, each class in its own colour, and a legend
that lists only the classes that occur (no colour bar running over values that never appear).
:func:`orbit_classes` turns a sweep's ``period``, ``orbit_impacts`` and ``dynamics`` into such
codes: one class per (period, impacts per period) found, then quasi-periodic, chaotic, not
converged, no period (no exponents computed) and invalid start.
"""
from __future__ import annotations

import textwrap
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from .plots import plt  # the Agg backend, selected once for the package

#: Colours of the classes that are not periodic orbits: greys from dark (chaotic) to light,
#: black for starts that could not be run, outside the periodic palette.
NON_PERIODIC_COLOURS = {
    "chaotic": "#4d4d4d",
    "quasi-periodic": "#8c8c8c",
    "not converged": "#c4c4c4",
    "no period (no exponents)": "#ececec",
    "invalid start": "#000000",
}


@dataclass(frozen=True)
class PlotClass:
    """One class of a class map.

    Attributes
    ----------
    label : str
        Legend text, e.g. ``"P3, 1 impact"``.
    colour : Any
        A matplotlib colour.
    count : int
        Grid cells in the class (the legend gives the share).
    """

    label: str
    colour: Any
    count: int


def periodic_palette(n: int) -> list[Any]:
    """``n`` distinct colours for periodic classes (tab10 without its grey, then tab20)."""
    base = [c for i, c in enumerate(plt.get_cmap("tab10").colors) if i != 7]
    if n > len(base):
        base = list(plt.get_cmap("tab20").colors)
    return [base[i % len(base)] for i in range(n)]


def impacts_label(period: int, impacts: int) -> str:
    """``"P3, 1 impact"``, ``"P6, 2 impacts"``."""
    return f"P{period}, {impacts} impact{'' if impacts == 1 else 's'}"


def flag_names(variable: Any) -> dict[int, str]:
    """code -> meaning of a CF flag variable (``flag_values``, ``flag_meanings``), e.g. the
    sweeps' ``dynamics``: {-1: "unclassified", 0: "not_converged", 1: "periodic", ...}.  The
    Dataset describes its own codes, so the figures need nothing from the layer that made them."""
    values = np.atleast_1d(variable.attrs.get("flag_values", []))
    meanings = str(variable.attrs.get("flag_meanings", "")).split()
    return {int(v): m for v, m in zip(values, meanings)}


def orbit_classes(period: np.ndarray, orbit_impacts: np.ndarray, dynamics: np.ndarray | None = None,
                  names: dict[int, str] | None = None) -> tuple[np.ndarray, list[PlotClass]]:
    """Class codes of a sweep's points, and the classes that occur.

    Parameters
    ----------
    period, orbit_impacts : array_like of int
        The sweep's variables (period 0: none found; -1: the point was not run, an invalid start).
    dynamics : array_like of int, optional
        The sweep's ``dynamics``; splits the points without a period into quasi-periodic,
        chaotic, not converged and no exponents.
    names : dict, optional
        Meaning of each ``dynamics`` code (:func:`flag_names` of the variable; "chaotic",
        "quasi_periodic", "not_converged", ...).

    Returns
    -------
    codes : ndarray of int
        Index into ``classes`` per point, same shape as ``period``.
    classes : list of PlotClass
        Periodic classes sorted by (period, impacts), then the non-periodic ones that occur.
    """
    period = np.asarray(period).astype(int)
    impacts = np.asarray(orbit_impacts).astype(int)
    dyn = np.full(period.shape, -1) if dynamics is None else np.asarray(dynamics).astype(int)
    meaning = {code: m.replace("_", "-" if m == "quasi_periodic" else " ") for code, m in (names or {}).items()}
    label = np.empty(period.shape, dtype=object)
    pairs = sorted({(int(p), int(k)) for p, k in zip(period.ravel(), impacts.ravel()) if p > 0})
    for idx in np.ndindex(period.shape):
        p, m = period[idx], meaning.get(int(dyn[idx]), "unclassified")
        if p > 0:
            label[idx] = (p, int(impacts[idx]))
        elif p < 0:
            label[idx] = "invalid start"
        elif m in ("chaotic", "quasi-periodic", "not converged"):
            label[idx] = m
        elif m == "periodic":  # no period but labelled periodic cannot happen; shown as undecided
            label[idx] = "not converged"
        else:
            label[idx] = "no period (no exponents)"
    order: list[Any] = list(pairs) + [n for n in NON_PERIODIC_COLOURS if np.any(label == n)]
    colours = periodic_palette(len(pairs)) + [NON_PERIODIC_COLOURS[n] for n in order[len(pairs):]]
    index = {name: i for i, name in enumerate(order)}
    codes = np.vectorize(lambda n: index[n], otypes=[int])(label) if label.size else np.zeros(period.shape, int)
    classes = [PlotClass(impacts_label(*name) if isinstance(name, tuple) else name, colour, int(np.sum(codes == i)))
               for i, (name, colour) in enumerate(zip(order, colours))]
    return codes, classes


def draw_class_map(ax: Any, x: np.ndarray, y: np.ndarray, codes: np.ndarray, classes: Sequence[PlotClass]) -> Any:
    """Draw ``codes`` (shape (len(y), len(x)), indices into ``classes``) cell by cell in the
    classes' colours; returns the QuadMesh."""
    from matplotlib.colors import ListedColormap

    cmap = ListedColormap([c.colour for c in classes] or ["white"])
    return ax.pcolormesh(x, y, np.asarray(codes, dtype=float), cmap=cmap, vmin=-0.5,
                         vmax=max(len(classes), 1) - 0.5, shading="nearest")


def class_legend(ax: Any, classes: Sequence[PlotClass], title: str | None = None, shares: bool = True,
                 **kwargs: Any) -> Any:
    """A legend with one patch per class (with its share of the cells), outside the axes on the
    right unless ``loc``/``bbox_to_anchor`` are given."""
    from matplotlib.patches import Patch

    total = sum(c.count for c in classes) or 1

    def share(count: int) -> str:  # a class that occurs never reads "0%"
        return "<1%" if 0 < count < 0.005 * total else f"{count / total:.0%}"

    handles = [Patch(facecolor=c.colour, edgecolor="black", linewidth=0.6,
                     label=f"{c.label} ({share(c.count)})" if shares else c.label) for c in classes]
    options = dict(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=8, frameon=False, title=title,
                   title_fontsize=8, borderaxespad=0.0)
    options.update(kwargs)
    return ax.legend(handles=handles, **options)


def wrap_title(text: str, width: int = 70) -> str:
    """``text`` wrapped at ``width`` characters, existing line breaks kept (a title is never cut)."""
    return "\n".join(line for part in text.split("\n") for line in (textwrap.wrap(part, width) or [""]))


def axis_positions(values: np.ndarray) -> tuple[np.ndarray, str]:
    """Where to draw the rows of a scan axis: ``(positions, scale)`` with scale "linear" (evenly
    spaced values, drawn at their values), "log" (evenly spaced in log, positive) or "index"
    (anything else, e.g. Gamma = 10, 30, 1000: one row per value, labelled with it)."""
    v = np.asarray(values, dtype=float)
    if v.size < 3:
        return (v, "linear") if v.size == 2 else (np.arange(v.size, dtype=float), "index")
    step = np.diff(v)
    if np.allclose(step, step[0], rtol=1e-6, atol=1e-12 * max(1.0, float(np.max(np.abs(v))))):
        return v, "linear"
    if np.all(v > 0) and np.allclose(np.diff(np.log(v)), np.log(v[1] / v[0]), rtol=1e-6):
        return v, "log"
    return np.arange(v.size, dtype=float), "index"
