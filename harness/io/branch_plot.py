"""Figure of a continued branch in the convention of the field: stable solid, unstable dashed,
located events marked and labelled, parameters in the (wrapped) title."""
from __future__ import annotations

import textwrap
from pathlib import Path
from typing import Any, Sequence

import numpy as np


#: Marker of each event kind.
MARKERS = {"flip": ("s", "tab:red"), "fold": ("o", "tab:green"), "ns": ("D", "tab:purple"),
           "graze": ("^", "tab:orange"), "stick": ("v", "tab:brown"), "end": ("x", "grey")}


def branch_figure(branches: Sequence[Any], path: str | Path, title: str) -> Path:
    """Draw u at the section of every branch (:class:`harness.dynamics.branch.Branch`) against its
    parameter, and max |multiplier| below; write ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax, axm) = plt.subplots(2, 1, figsize=(8, 6.5), sharex=True, gridspec_kw={"height_ratios": [3, 1.3]})
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    seen: set[str] = set()
    for b_i, br in enumerate(branches):
        c = colors[b_i % len(colors)]
        x, stable = br.values, br.stable
        mu = np.abs(br.multipliers).max(axis=1)
        for k in range(br.M):
            y = br.points[:, k, 0]
            for i in range(len(x) - 1):
                style = "-" if (stable[i] and stable[i + 1]) else "--"
                ax.plot(x[i:i + 2], y[i:i + 2], style, color=c, lw=1.4,
                        label=f"period {br.M}" if (k == 0 and i == 0) else None)
        for i in range(len(x) - 1):
            axm.plot(x[i:i + 2], mu[i:i + 2], "-" if (stable[i] and stable[i + 1]) else "--", color=c, lw=1.2)
        for e in br.events:
            m, ec = MARKERS.get(e.kind, ("*", "k"))
            lab = e.kind if e.kind not in seen else None
            seen.add(e.kind)
            ax.plot([e.value], [e.point[0]], m, color=ec, ms=7, mfc="none", mew=1.6, label=lab)
            if e.kind != "end":
                ax.annotate(f"{e.kind} {e.value:.6g}", (e.value, e.point[0]), textcoords="offset points",
                            xytext=(4, 6), fontsize=7, color=ec)
    axm.axhline(1.0, color="k", lw=0.6, ls=":")
    ax.set_ylabel("u at t = theta + k")
    axm.set_ylabel("max |multiplier|")
    axm.set_yscale("log")
    axm.set_xlabel(branches[0].param if branches else "parameter")
    ax.legend(fontsize=7, loc="best")
    ax.set_title("\n".join(textwrap.wrap(title, 90)), fontsize=8)
    fig.tight_layout()
    from .plots import _save

    return _save(fig, path)
