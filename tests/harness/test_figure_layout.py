"""Figures that show what they claim: `continue`'s unstable stretches dashed however short its steps,
its event labels apart, and overlapping windows of one row of windows_windows.png both visible."""
from __future__ import annotations

import numpy as np

from harness.analysis.windows.plots import bar_lanes
from harness.io.branch_plot import _annotate, _runs, branch_figure


def test_a_branch_is_drawn_in_one_line_per_stretch_of_one_style(tmp_path) -> None:
    """A branch of 40 short steps, stable, then unstable, then stable again with another contact
    count: three lines, not 39 segments (a dash pattern restarts with every line, so an unstable
    branch drawn step by step looked solid)."""
    stable = np.array([True] * 10 + [False] * 20 + [True] * 10)
    impacts = np.array([1] * 30 + [2] * 10)
    runs = _runs(stable, impacts)
    assert runs == [(0, 9), (9, 30), (29, 39)] or len(runs) == 3
    # every point covered, consecutive stretches sharing their end point (the line is unbroken)
    assert runs[0][0] == 0 and runs[-1][1] == len(stable) - 1
    assert all(a[1] == b[0] for a, b in zip(runs, runs[1:]))


def test_the_dashed_stretch_is_one_dashed_line(tmp_path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from harness.dynamics.continuation.branch import Branch

    n = 40
    x = np.linspace(0.0, 0.01, n)  # short steps: each segment shorter than one dash
    mult = np.where(np.arange(n)[:, None] < 20, 0.5, 1.5) * np.ones((n, 2))
    br = Branch("sigma", 1, {}, 0.5, x, np.stack([x, x], axis=1)[:, None, :], np.ones((n, 1), dtype=int),
                mult.astype(complex), np.full(n, np.inf), [""] * n)
    captured = {}
    orig = plt.Figure.savefig

    def grab(fig, *a, **k):
        captured["lines"] = [(ln.get_linestyle(), len(ln.get_xdata())) for ln in fig.axes[0].lines]
        return orig(fig, *a, **k)

    plt.Figure.savefig = grab
    try:
        branch_figure([br], tmp_path / "b.png", "test")
    finally:
        plt.Figure.savefig = orig
    dashed = [k for s, k in captured["lines"] if s == "--"]
    assert dashed == [21]  # the unstable stretch: one line through its 21 points
    assert (tmp_path / "b.png").stat().st_size > 0


def test_event_labels_do_not_overlap() -> None:
    """A fold and a graze a fraction of a label's width apart in x, at the same height, and a third
    one just beyond the old 0.1-of-the-axis rule: every drawn label box is clear of the others."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4))
    ax.set_xlim(0.0, 1.0)
    ax.set_ylim(-1.0, 1.0)
    labels = [(0.50, 0.0, "fold 0.500123", "g"), (0.51, 0.0, "graze 0.510456", "orange"),
              (0.62, 0.02, "graze 0.620789", "orange")]
    _annotate(ax, labels)
    from matplotlib.text import Text

    r = fig.canvas.get_renderer()
    boxes = [Text.get_window_extent(t, r) for t in ax.texts]
    assert len(boxes) == 3
    assert not any(boxes[i].overlaps(boxes[j]) for i in range(3) for j in range(i + 1, 3))
    plt.close(fig)


def test_overlapping_windows_of_one_row_get_lanes_of_their_own() -> None:
    """A map's period-1 window [0.2, 1.0] overlapping its period-2 window [0.1, 0.3]: two lanes; a
    third window apart from both shares the first lane free."""
    lane, n = bar_lanes([(0.2, 1.0), (0.1, 0.3), (1.5, 2.0)])
    assert n == 2
    assert lane[0] != lane[1]
    assert lane[2] in (0, 1)
    lane, n = bar_lanes([(0.0, 0.1), (0.2, 0.3)])
    assert n == 1 and lane == [0, 0]
