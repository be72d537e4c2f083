"""atlas.png: the plane coloured by each pixel's dominant class (periodic classes in colour, chaos
dark, aperiodic grey, escape white), multistable pixels hatched (/// two attractors, xxx three
or more), the chart's continued edge curves drawn over it, the parameters in the title and the
legend outside the axes."""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .classes import ClassMaps

#: Colours of the classes that are not periodic orbits.
FIXED = {"chaotic": "#1a1a1a", "aperiodic": "#7f7f7f", "escaped": "#ffffff"}
#: Line styles of the chart's edge kinds.
LINESTYLES = {"flip": "-", "fold": "--", "graze": ":", "torus": "-."}


#: Distinct colours for the periodic classes that fill the most pixels (tab20 without its greys,
#: which would read as aperiodic); the others share :data:`OTHER` and one legend entry.
PALETTE = [i for i in range(20) if i not in (14, 15)]
OTHER = "#f2c6de"


def class_colours(maps: ClassMaps) -> list[Any]:
    """One colour per class: the periodic ones by the pixels where they dominate (most first),
    distinct for the first len(PALETTE), :data:`OTHER` beyond; the others fixed."""
    import matplotlib

    cmap = matplotlib.colormaps["tab20"]
    counts = np.bincount(maps.dominant[maps.dominant >= 0].ravel(), minlength=len(maps.classes))
    periodic = [c for c, cl in enumerate(maps.classes) if cl.kind not in FIXED]
    rank = {c: k for k, c in enumerate(sorted(periodic, key=lambda c: (-counts[c], c)))}
    return [FIXED[cl.kind] if cl.kind in FIXED else (cmap(PALETTE[rank[c]]) if rank[c] < len(PALETTE) else OTHER)
            for c, cl in enumerate(maps.classes)]


def legend_patches(maps: ClassMaps, cols: list[Any]) -> list[Any]:
    """One patch per class with its own colour (periodic ones in the order of their pixels), one for
    the classes sharing :data:`OTHER`, and the hatches."""
    from matplotlib.patches import Patch

    counts = np.bincount(maps.dominant[maps.dominant >= 0].ravel(), minlength=len(maps.classes))
    own = [c for c, col in enumerate(cols) if not (isinstance(col, str) and col == OTHER)]
    own.sort(key=lambda c: (maps.classes[c].kind in FIXED, -counts[c] if maps.classes[c].kind not in FIXED else c))
    out = [Patch(facecolor=cols[c], edgecolor="0.5", label=maps.classes[c].name) for c in own]
    shared = [maps.classes[c].name for c, col in enumerate(cols) if isinstance(col, str) and col == OTHER]
    if shared:
        out.append(Patch(facecolor=OTHER, edgecolor="0.5", label=f"{len(shared)} other periodic classes"))
    return out + [Patch(facecolor="white", edgecolor="0.3", hatch="///", label="2 attractors"),
                  Patch(facecolor="white", edgecolor="0.3", hatch="xxx", label="3 or more attractors")]


def _edges(x: np.ndarray, log: bool) -> np.ndarray:
    """Cell edges around the pixel centres x."""
    if x.size == 1:
        return np.array([x[0] * 0.9, x[0] * 1.1]) if log else np.array([x[0] - 0.5, x[0] + 0.5])
    a = np.log(x) if log else x
    mid = (a[1:] + a[:-1]) / 2
    e = np.concatenate([[2 * a[0] - mid[0]], mid, [2 * a[-1] - mid[-1]]])
    return np.exp(e) if log else e


def atlas_figure(maps: ClassMaps, p2: np.ndarray, sigma: np.ndarray, param2: str, log_p2: bool, log_sigma: bool,
                 title: str, path: str | Path, curves: list[dict[str, Any]] | None = None) -> Path:
    """Draw and write atlas.png (see the module comment); returns its path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import ListedColormap

    cols = class_colours(maps)
    fig, ax = plt.subplots(figsize=(10.5, 6.2))
    X, Y = _edges(p2, log_p2), _edges(sigma, log_sigma)
    img = np.ma.masked_less(maps.dominant.T.astype(float), 0)
    if cols:
        ax.pcolormesh(X, Y, img, cmap=ListedColormap(cols), vmin=-0.5, vmax=len(cols) - 0.5, shading="flat")
    multi = maps.n_attractors.T.astype(float)
    if np.any(multi >= 2):
        ax.contourf(p2, sigma, multi, levels=[1.5, 2.5, 1e9], colors="none", hatches=["///", "xxx"])
    handles = legend_patches(maps, cols)
    for c in curves or []:
        k = next((i for i, cl in enumerate(maps.classes) if cl.kind == "periodic" and cl.M == c["M"]
                  and cl.impacts == c["impacts"]), None)
        col = "k" if k is None else cols[k]
        ax.plot(c["p2"], c["sigma"], LINESTYLES.get(c["kind"], "-"), color="white", lw=3.2, alpha=0.8)
        ax.plot(c["p2"], c["sigma"], LINESTYLES.get(c["kind"], "-"), color=col, lw=1.6)
    for kind in sorted({c["kind"] for c in curves or []}):
        handles.append(matplotlib.lines.Line2D([], [], color="k", ls=LINESTYLES.get(kind, "-"),
                                               label=f"{kind} edge (chart, continued)"))
    if log_p2:
        ax.set_xscale("log")
    if log_sigma:
        ax.set_yscale("log")
    ax.set_xlim(X[0], X[-1])
    ax.set_ylim(Y[0], Y[-1])
    ax.set_xlabel(param2)
    ax.set_ylabel("forcing above grazing, sigma")
    ax.set_title(title, fontsize=8)
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path
