"""Sweep figures for a talk: the Lyapunov panel whenever the data has
exponents, one colour per class with a legend listing exactly the classes that occur, titles
that fit in the figure; and a u0 x v0 scan with starts inside the rigid wall runs to the end,
those starts marked invalid.

Truths: the classes are counted independently from the Dataset's period, orbit_impacts and
dynamics; the panels' drawn data are compared with the Dataset's numbers; the title's drawn
extent with the figure's.
"""
from __future__ import annotations

import numpy as np
import pytest
from matplotlib.colors import to_rgba

from harness import SamplingSpec, SweepSpec, read_netcdf, run_sweep
from harness.dynamics.maps.classify import (CHAOTIC, DYNAMICS_NAMES, NOT_CONVERGED, PERIODIC, QUASI_PERIODIC, SIGMAS,
                                       UNCLASSIFIED)
from harness.io import sweep_plots
from harness.io.class_map import NON_PERIODIC_COLOURS, flag_names, orbit_classes, wrap_title
from tests.support.cli import run_main


def _capture(monkeypatch) -> dict:
    """The figure a sweep plot saves, drawn, with what a reader sees of it."""
    seen: dict = {}
    orig = sweep_plots._save

    def capture(fig, path):
        fig.canvas.draw()
        seen["axes"] = list(fig.axes)
        seen["width"] = fig.bbox.width
        texts = [ax.title for ax in fig.axes if ax.get_title()] + ([fig._suptitle] if fig._suptitle else [])
        seen["extents"] = [t.get_window_extent() for t in texts]
        seen["legends"] = [[t.get_text() for t in ax.get_legend().get_texts()] for ax in fig.axes if ax.get_legend()]
        return orig(fig, path)

    monkeypatch.setattr(sweep_plots, "_save", capture)
    return seen


def _titles_fit(seen: dict) -> None:
    for box in seen["extents"]:
        assert box.x0 >= 0 and box.x1 <= seen["width"], (box, seen["width"])


def test_orbit_classes_one_per_class() -> None:
    period = np.array([[2, 2, 6, 0, 0, 0, 0, -1], [3, 2, 6, 0, 0, 0, 2, -1]])
    impacts = np.array([[1, 1, 2, -1, -1, -1, -1, -1], [1, 2, 2, -1, -1, -1, 1, -1]])
    dyn = np.array([[PERIODIC, PERIODIC, PERIODIC, CHAOTIC, QUASI_PERIODIC, NOT_CONVERGED, UNCLASSIFIED, UNCLASSIFIED],
                    [PERIODIC, PERIODIC, PERIODIC, CHAOTIC, CHAOTIC, NOT_CONVERGED, PERIODIC, UNCLASSIFIED]])
    names = {c: DYNAMICS_NAMES[c].replace(" ", "_").replace("-", "_") for c in DYNAMICS_NAMES}  # as in the NetCDF
    codes, classes = orbit_classes(period, impacts, dyn, names)
    labels = [c.label for c in classes]
    assert labels == ["P2, 1 impact", "P2, 2 impacts", "P3, 1 impact", "P6, 2 impacts", "chaotic", "quasi-periodic",
                      "not converged", "no period (no exponents)", "invalid start"]
    assert [c.count for c in classes] == [3, 1, 1, 2, 3, 1, 2, 1, 2]
    assert sum(c.count for c in classes) == period.size
    assert labels[codes[0, 7]] == "invalid start" and labels[codes[1, 1]] == "P2, 2 impacts"
    assert len({str(c.colour) for c in classes}) == len(classes)  # every class its own colour
    # only what occurs: a map of one periodic class and chaos has two entries
    _, few = orbit_classes(np.array([2, 0]), np.array([1, -1]), np.array([PERIODIC, CHAOTIC]), names)
    assert [c.label for c in few] == ["P2, 1 impact", "chaotic"]
    assert few[1].colour == NON_PERIODIC_COLOURS["chaotic"]


def test_wrapped_titles_keep_every_word() -> None:
    text = "Orbits over (sigma, Gamma): " + ", ".join(f"parameter{i} = {i}.5" for i in range(20)) + "\nsecond"
    wrapped = wrap_title(text, 50)
    assert all(len(line) <= 50 for line in wrapped.split("\n"))
    assert wrapped.split() == text.split()


@pytest.fixture(scope="module")
def lyapunov_sweep(model):
    # Figure 9's parameters: chaotic at sigma = 0.03 and 0.1, period 2 at 0.5
    return run_sweep(model, SweepSpec("sigma", np.array([0.03, 0.1, 0.5]), ("fresh",)),
                     sampling=SamplingSpec(theta=0.5, n_transient=100, n_samples=12, lyapunov=80),
                     backend="serial", progress=False)


def test_sweep_figure_has_a_lyapunov_panel(lyapunov_sweep, tmp_path, monkeypatch) -> None:
    seen = _capture(monkeypatch)
    sweep_plots.bifurcation_diagram(lyapunov_sweep, tmp_path / "b.png")
    assert len(seen["axes"]) == 3
    axl = seen["axes"][2]
    sel = lyapunov_sweep.sel(direction="fresh")
    lam, err = sel["lyapunov"].values[:, 0], sel["lyapunov_err"].values[:, 0]
    x = sel["sigma"].values
    # the zero line
    assert any(np.allclose(line.get_ydata(), 0.0) and len(line.get_ydata()) == 2 for line in axl.get_lines())
    # lambda_1 drawn at its values, with 3-sigma bars
    container = axl.containers[0]
    np.testing.assert_allclose(container.lines[0].get_ydata(), lam)
    segments = container.lines[2][0].get_segments()
    np.testing.assert_allclose([s[1, 1] - s[0, 1] for s in segments], 2 * SIGMAS * err, rtol=1e-12)
    # chaotic points marked: exactly those the Dataset calls chaotic
    chaotic = sel["dynamics"].values == CHAOTIC
    assert chaotic.sum() >= 1 and (~chaotic).sum() >= 1
    star = to_rgba(sweep_plots.CHAOTIC_COLOUR)
    marked = [line for line in axl.get_lines() if to_rgba(line.get_markerfacecolor()) == star]
    assert len(marked) == 1
    np.testing.assert_allclose(marked[0].get_xdata(), x[chaotic])
    _titles_fit(seen)


def test_u0_v0_scan_marks_starts_inside_the_wall_and_draws_every_class(tmp_path, capsys, monkeypatch) -> None:
    """u0 x v0 with a rigid wall at u = 0: the starts at u0 = 0.2 are inside it.  The scan runs to the
    end, those starts are invalid (period -1, no samples), every other start is computed, and the
    figure's legend lists exactly the classes of the data, "invalid start" among them, without a
    colour bar."""
    seen = _capture(monkeypatch)
    out, png = tmp_path / "uv.nc", tmp_path / "uv.png"
    code, stdout, err = run_main(["sweep", "--set", "wall=rigid", "--set", "sigma=0.5", "--param", "u0",
                                  "--values=-1.5,-0.5,0.2", "--scan", "v0=-1,1", "--mode", "fresh", "--theta", "0.5",
                                  "--transient", "100", "--samples", "12", "--lyapunov", "40", "--workers", "1",
                                  "--out", str(out), "--plot", str(png), "--no-progress"], capsys)
    assert code == 0, err
    ds = read_netcdf(out).sel(direction="fresh")
    inside = ds["u0"].values > 0
    assert (ds["period"].values[inside] == -1).all() and np.isnan(ds["u"].values[inside]).all()
    assert (ds["period"].values[~inside] >= 0).all() and np.isfinite(ds["u"].values[~inside]).all()
    assert "invalid start 2" in stdout
    _, classes = orbit_classes(ds["period"].values, ds["orbit_impacts"].values, ds["dynamics"].values,
                               flag_names(ds["dynamics"]))
    legend = seen["legends"][0]
    assert [t.rsplit(" (", 1)[0] for t in legend] == [c.label for c in classes]
    assert any(t.startswith("invalid start (33%)") for t in legend)
    assert len(seen["axes"]) == 1  # one panel, no colour-bar axes
    assert png.stat().st_size > 0
    _titles_fit(seen)
