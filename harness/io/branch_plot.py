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


def _fmt(value: float, span: float) -> str:
    """A parameter value to 6 digits, round-off below 1e-12 of the axis' span shown as 0 (not
    5.37764e-17)."""
    return "0" if abs(value) < 1e-12 * max(span, 1e-300) else f"{value:.6g}"


def _event_labels(branches: Sequence[Any], span: float) -> list[tuple[float, float, str, str]]:
    """One label per place: events of all branches at the same point (within 1e-9 of the span;
    a flip found from both sides, a fold on a graze) joined into one text."""
    placed: list[list[Any]] = []
    for br in branches:
        for e in br.events:
            if e.kind == "end":
                continue
            text = f"{e.kind} {_fmt(e.value, span)}"
            for p in placed:
                if abs(p[0] - e.value) <= 1e-9 * span and abs(p[1] - e.point[0]) <= 1e-9 * max(1.0, abs(p[1])):
                    if text not in p[2]:
                        p[2].append(text)
                    break
            else:
                placed.append([e.value, float(e.point[0]), [text], MARKERS.get(e.kind, ("*", "k"))[1]])
    return [(x, y, ", ".join(t), c) for x, y, t, c in placed]


def _annotate(ax: Any, labels: list[tuple[float, float, str, str]]) -> None:
    """Write each label, raised in steps of 9 points until its drawn box overlaps no label written
    before it (the boxes measured as rendered: a fold and a graze a few label widths apart on the
    axis, or at other heights, still do not print over each other)."""
    from matplotlib.text import Text

    renderer = ax.figure.canvas.get_renderer()
    boxes: list[Any] = []
    for x, y, text, colour in sorted(labels):
        for level in range(40):
            a = ax.annotate(text, (x, y), textcoords="offset points", xytext=(4, 6 + 9 * level), fontsize=7,
                            color=colour, arrowprops=dict(arrowstyle="-", lw=0.4, color=colour) if level else None)
            # the text's own box (an annotation's extent includes its leader line down to the point)
            box = Text.get_window_extent(a, renderer).expanded(1.05, 1.15)
            if not any(box.overlaps(b) for b in boxes):
                break
            a.remove()
        boxes.append(box)


def _runs(stable: np.ndarray, impacts: np.ndarray) -> list[tuple[int, int]]:
    """(first, last) index of each stretch of a branch drawn in one style and colour: the segment
    i -> i + 1 is stable when both ends are, and takes the contacts of its first end."""
    seg = [(bool(stable[i] and stable[i + 1]), int(impacts[i])) for i in range(len(stable) - 1)]
    runs: list[tuple[int, int]] = []
    for i, s in enumerate(seg):
        if runs and seg[runs[-1][0]] == s:
            runs[-1] = (runs[-1][0], i + 1)
        else:
            runs.append((i, i + 1))
    return runs


def branch_figure(branches: Sequence[Any], path: str | Path, title: str) -> Path:
    """Draw u at the section of every branch (:class:`harness.dynamics.continuation.branch.Branch`) against its
    parameter, and max |multiplier| below; write ``path``.  One colour and one legend entry per
    (period, impacts per period) of the stable parts; solid stable, dashed unstable (in the legend
    too); event labels that do not print over each other."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    fig, (ax, axm) = plt.subplots(2, 1, figsize=(8, 6.5), sharex=True, gridspec_kw={"height_ratios": [3, 1.3]})
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    keys: dict[tuple[int, int], str] = {}  # (period, impacts) -> colour, in order of appearance
    seen: set[str] = set()
    span = max((float(np.ptp(br.values)) for br in branches if len(br)), default=1.0) or 1.0
    for br in branches:
        x, stable, imp = br.values, br.stable, br.impacts
        mu = np.abs(br.multipliers).max(axis=1)
        # one line per stretch of equal style: a dash pattern restarts with every line, so a branch
        # drawn segment by segment in short steps looks solid even where it is dashed
        for i, j in _runs(stable, imp):
            c = keys.setdefault((br.M, int(imp[i])), colors[len(keys) % len(colors)])
            style = "-" if (stable[i] and stable[i + 1]) else "--"
            for k in range(br.M):
                ax.plot(x[i:j + 1], br.points[i:j + 1, k, 0], style, color=c, lw=1.4)
            axm.plot(x[i:j + 1], mu[i:j + 1], style, color=c, lw=1.2)
        for e in br.events:
            m, ec = MARKERS.get(e.kind, ("*", "k"))
            ax.plot([e.value], [e.point[0]], m, color=ec, ms=7, mfc="none", mew=1.6,
                    label=("end of a branch" if e.kind == "end" else e.kind) if e.kind not in seen else None)
            seen.add(e.kind)
    fig.tight_layout()
    _annotate(ax, _event_labels(branches, span))
    handles = [Line2D([], [], color=c, lw=1.4, label=f"period {M}, {n} impact{'s' if n != 1 else ''} per period")
               for (M, n), c in keys.items()]
    handles += [Line2D([], [], color="k", lw=1.2, ls="-", label="stable"),
                Line2D([], [], color="k", lw=1.2, ls="--", label="unstable")]
    axm.axhline(1.0, color="k", lw=0.6, ls=":")
    ax.set_ylabel("u at t = theta + k")
    axm.set_ylabel("max |multiplier|")
    axm.set_yscale("log")
    axm.set_xlabel(branches[0].param if branches else "parameter")
    ax.legend(handles=handles + ax.get_legend_handles_labels()[0], fontsize=7, loc="best")
    ax.set_title("\n".join(textwrap.wrap(title, 90)), fontsize=8)
    fig.tight_layout()
    from .plots import _save

    return _save(fig, path)
