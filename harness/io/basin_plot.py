"""The basin figure: one colour per attractor with a legend (period, impacts per period, share
of the starts), grey for starts that reach no periodic orbit, black for invalid starts, and each
attractor's stroboscopic points drawn over its basin."""
from __future__ import annotations

import json
import textwrap
from pathlib import Path
from typing import Any

import numpy as np

from .plots import _save, parameter_title, plt  # plt: the Agg backend, selected once for the package

#: Not periodic, invalid start (labels -1, -2): neutral colours outside the attractors' palette.
NOT_PERIODIC_COLOUR = "#c8c8c8"
INVALID_COLOUR = "#000000"


def basin_figure(ds: Any, path: str | Path) -> str:
    """Draw the basins of a :func:`harness.runs.basin_scan.run_basins` Dataset to ``path`` (PNG).

    Returns the path written.
    """
    from matplotlib.colors import ListedColormap
    from matplotlib.patches import Patch

    labels = ds["attractor"].values  # (u0, v0)
    names = json.loads(ds.attrs["basins.attractors"])
    n = len(names)
    palette = plt.get_cmap("tab10" if n <= 10 else "tab20")
    colours = [INVALID_COLOUR, NOT_PERIODIC_COLOUR] + [palette(i % palette.N) for i in range(n)]
    cmap = ListedColormap(colours)
    u0, v0 = ds["u0"].values, ds["v0"].values
    fig, ax = plt.subplots(figsize=(7.5, 6.0))
    ax.pcolormesh(u0, v0, (labels + 2).T, cmap=cmap, vmin=-0.5, vmax=len(colours) - 0.5, shading="nearest")
    total = labels.size
    handles = []
    for i, name in enumerate(names):
        p = int(ds["attractor_period"].values[i])
        pts = ds["attractor_points"].values[i, :p]
        ax.plot(pts[:, 0], pts[:, 1], linestyle="none", marker="o", markersize=7, markerfacecolor=colours[i + 2],
                markeredgecolor="black", markeredgewidth=1.2)
        share = int(ds["attractor_starts"].values[i]) / total
        handles.append(Patch(facecolor=colours[i + 2], edgecolor="black", label=f"{name} ({share:.0%})"))
    for code, colour, what in ((-1, NOT_PERIODIC_COLOUR, "not periodic"), (-2, INVALID_COLOUR, "invalid start")):
        count = int(np.sum(labels == code))
        if count:
            handles.append(Patch(facecolor=colour, edgecolor="black", label=f"{what} ({count / total:.0%})"))
    ax.set_xlabel("u0 (displacement at t = theta)")
    ax.set_ylabel("v0 (velocity at t = theta)")
    head = f"Basins of attraction at t = n + {float(ds.attrs.get('sampling.theta', 0.0)):g}: "
    ax.set_title("\n".join(textwrap.wrap(head + parameter_title(ds.attrs), 72)), fontsize=10)
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=9, frameon=False,
              title="attractor (share of starts);\ndots: its stroboscopic points", title_fontsize=8)
    fig.tight_layout()
    return str(_save(fig, path))
