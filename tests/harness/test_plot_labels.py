"""What a sweep's NetCDF and plots tell a reader: no stale attributes, the codes of period and
orbit_impacts explained on the variables, titles with the parameters, natural axis labels,
and the period drawn as a number on a linear axis."""
from __future__ import annotations

import numpy as np
import pytest

from harness import SamplingSpec, SweepSpec, read_netcdf, run_sweep, write_netcdf
from harness.io import plots
from harness.io import sweep_plots
from harness.io.plots import parameter_title, section_label


@pytest.fixture(scope="module")
def sweep(model):
    # Figure 9's defaults: sigma = 0.5 is period 2 with one impact, 0.9 period 1 (docs/theory.md)
    spec = SweepSpec("sigma", np.array([0.5, 0.9]), ("up",), scan_param="Gamma", scan_values=np.array([10.0, 20.0]))
    return run_sweep(model, spec, sampling=SamplingSpec(n_transient=200, n_samples=12), backend="serial")


def test_swept_parameters_are_not_stale_attributes(sweep, tmp_path) -> None:
    path = tmp_path / "s.nc"
    write_netcdf(sweep, path)
    ds = read_netcdf(path)
    assert "model.sigma" not in ds.attrs and "model.Gamma" not in ds.attrs  # coordinates instead
    assert ds.attrs["model.nu"] == pytest.approx(4.605170185988091)
    assert "model.r" in ds.attrs
    for name in ("period", "orbit_impacts"):
        assert "comment" in ds[name].attrs and ds[name].dtype.kind == "i", name
    assert "-1 when period = 0" in ds["orbit_impacts"].attrs["comment"]
    assert "dynamics" in ds["period"].attrs["comment"]
    # the codes agree with the data: orbit_impacts = -1 exactly where no period was found
    p, k = ds["period"].values, ds["orbit_impacts"].values
    assert np.array_equal(p == 0, k == -1)


def test_labels_and_title_text() -> None:
    assert section_label("u", 0.0) == "position u at t = n"
    assert section_label("v", 0.5) == "velocity v at t = n + 1/2"
    attrs = {"model.nu": 4.605170185988091, "model.Omega": 0.3059238689620112, "model.r": 0.9, "model.wall": 1,
             "model.Gamma": 10.0, "model.sigma": 0.2}
    t = parameter_title(attrs, ("sigma",))
    assert "(alpha, gamma) = (0.99, 0.01)" in t and "r = 0.9" in t and "compliant wall Gamma = 10" in t
    assert "sigma" not in t
    assert "rigid wall" in parameter_title({**attrs, "model.wall": 2})


def _capture(monkeypatch) -> dict:
    """The figure a sweep plot is about to save, kept open for inspection."""
    seen: dict = {}
    orig = sweep_plots._save

    def capture(fig, path):
        seen["fig"] = fig
        seen["axes"] = list(fig.axes)
        seen["suptitle"] = fig._suptitle.get_text() if fig._suptitle else ""
        seen["titles"] = [ax.get_title() for ax in fig.axes]
        seen["legends"] = [[t.get_text() for t in ax.get_legend().get_texts()] if ax.get_legend() else []
                           for ax in fig.axes]
        return orig(fig, path)

    monkeypatch.setattr(sweep_plots, "_save", capture)
    return seen


def test_bifurcation_diagram_says_what_it_shows(sweep, tmp_path, monkeypatch) -> None:
    """The drawn figure: parameters in the title, a natural y label, the period as numbers on a
    linear axis (0 = "none"), no Lyapunov panel without exponents."""
    seen = _capture(monkeypatch)
    path = sweep_plots.bifurcation_diagram(sweep, tmp_path / "b.png")
    assert path.stat().st_size > 0
    ax, axp = seen["axes"][:2]
    assert len(seen["axes"]) == 2  # no exponents in this sweep: no Lyapunov panel
    title = seen["titles"][0]
    assert "(alpha, gamma) = (0.99, 0.01)" in title.replace("\n", " ") and "r = 0.9" in title
    assert "Gamma = 10" in title  # the scan value shown
    assert ax.get_ylabel() == "position u at t = n"
    assert axp.get_yscale() == "linear"
    ticks = [float(v) for v in axp.get_yticks() if axp.get_ylim()[0] <= v <= axp.get_ylim()[1]]
    assert ticks == [float(round(v)) for v in ticks] and 1.0 in ticks and 2.0 in ticks  # integers, 1 and 2 drawn
    assert axp.yaxis.get_major_formatter()(0.0, 0) == "none"  # no period found
    assert axp.yaxis.get_major_formatter()(3.0, 0) == "3"
