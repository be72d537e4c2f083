"""Sweeps on the real FMU: period adding (Figure 9), hysteresis, 2D scans, resuming, worker loss.

Expected windows come from the paper's 1D theory (docs/theory.md section 6, eq (56) with the
|A~(sigma)| scale of section 7 item 3, and eq (64)), not from the harness's own output.
"""
from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from scipy.optimize import brentq

from harness import FmuModel, HarnessInputError, MappingSimulator, SamplingSpec, SweepSpec, SweepStats, run_sweep
from harness.config import SECTION_PHASE
from harness.runs.backends import ProcessBackend
from harness.runs.tasks import TEST_HOOK_ENV

ROOT = Path(__file__).resolve().parents[2]
FMU = ROOT / "build" / "fmu" / "ImpactOscillator.fmu"
DATA_VARS = ("u", "v", "impacts", "t", "period", "orbit_impacts")


def rho_of_sigma(sigma: float, nu: float, Omega: float, r: float) -> float:
    """Strongly damped 1D map parameter, eq (56) with |A~(sigma)| (docs/theory.md section 7, item 3)."""
    A_tilde = (1 + sigma) * 4 * math.pi**2 - sigma * Omega**2
    return nu * Omega**2 * sigma / (2 * A_tilde * (1 - r) ** 2)


def window_centre_sigma(M: int, nu: float, Omega: float, r: float) -> float:
    """sigma at the middle of the stability interval (64) of the maximal period-M orbit."""
    lo, hi = 1 / (4 * M), (1 / M**2 if M > 1 else 0.4)  # M = 1 has no upper edge: take 0.4
    target = 0.5 * (lo + hi)
    return brentq(lambda s: rho_of_sigma(s, nu, Omega, r) - target, 1e-6, 50.0)


def assert_same_results(a: xr.Dataset, b: xr.Dataset) -> None:
    for name in DATA_VARS:
        xr.testing.assert_equal(a[name], b[name])


def test_period_adding_windows_of_figure_9(model: FmuModel) -> None:
    p = model.defaults()
    centres = [window_centre_sigma(M, p["nu"], p["Omega"], p["r"]) for M in (3, 2, 1)]
    assert centres == sorted(centres)
    spec = SweepSpec("sigma", np.array(centres), ("fresh", "up", "down"))
    ds = run_sweep(model, spec, sampling=SamplingSpec(n_transient=300, n_samples=30), backend="serial", progress=False)
    for direction in ("fresh", "up", "down"):
        sel = ds.sel(direction=direction)
        # decreasing sigma: period 1, 2, 3, each a maximal orbit (one impact per period)
        assert sel["period"].values[::-1].tolist() == [1, 2, 3], direction
        assert sel["orbit_impacts"].values.tolist() == [1, 1, 1], direction
    # the sample of a period-M orbit repeats after M periods, and the impacts with it
    p3 = ds.sel(direction="fresh").isel(sigma=0)
    np.testing.assert_allclose(p3["u"].values[3:], p3["u"].values[:-3], atol=1e-6)
    assert p3["impacts"].values.sum() == 10


def test_up_down_scan_shows_hysteresis_below_grazing(model: FmuModel) -> None:
    """Underdamped, stiff wall (figures 6c/7): scanning up from the non-impacting orbit, impacts
    start only at sigma >= 0; scanning down, the impacting orbit survives below sigma = 0."""
    grid = np.linspace(-0.03, 0.03, 13)
    spec = SweepSpec("sigma", grid, ("up", "down"))
    params = {"nu": 0.196, "Omega": 7.368, "Gamma": 1000.0, "r": 0.9, "wall": 1}
    # start on the wall-free periodic orbit p(t) at t = 0: (sigma, 0), not touching the wall
    ds = run_sweep(model, spec, params=params, state0=(grid[0], 0.0),
                   sampling=SamplingSpec(n_transient=150, n_samples=20), backend="processes", workers=2, progress=False)
    hits = ds["impacts"].sum("sample")
    below = ds["sigma"] < 0
    assert int(hits.sel(direction="up").where(below, 0).sum()) == 0
    assert int(hits.sel(direction="up").where(~below, 0).max()) > 0
    disagree = below & (hits.sel(direction="down") > 0)
    assert int(disagree.sum()) >= 1, "no hysteresis: down scan lost its impacts at sigma = 0"


def test_two_dimensional_scan(model: FmuModel) -> None:
    spec = SweepSpec("sigma", np.array([0.5, 1.0]), ("fresh", "up"), scan_param="Gamma",
                     scan_values=np.array([10.0, 100.0]))
    ds = run_sweep(model, spec, sampling=SamplingSpec(n_transient=100, n_samples=10), backend="serial", progress=False)
    assert ds["u"].dims == ("direction", "sigma", "Gamma", "sample")
    assert ds["u"].shape == (2, 2, 2, 10)
    assert not np.isnan(ds["u"].values).any()
    # each (sigma, Gamma) of the 2D scan equals a 1D run at that Gamma
    one = run_sweep(model, SweepSpec("sigma", np.array([0.5, 1.0]), ("fresh",)), params={"Gamma": 100.0},
                    sampling=SamplingSpec(n_transient=100, n_samples=10), backend="serial", progress=False)
    np.testing.assert_array_equal(ds["u"].sel(direction="fresh", Gamma=100.0).values, one["u"].sel(direction="fresh").values)
    # different walls give different orbits: the second axis really reaches the FMU
    assert not np.allclose(ds["u"].sel(Gamma=10.0).values, ds["u"].sel(Gamma=100.0).values)


def test_mapping_given_by_the_user_strongly_damped_limit() -> None:
    """The 1D map (54)/(55) through the same sweep and classification: its windows are
    known exactly (64): P1 for rho > 1/4, P2 in [1/8, 1/4], P3 in [1/12, 1/9]."""
    sim = MappingSimulator(_strongly_damped_map)
    spec = SweepSpec("rho", np.array([0.1, 0.2, 0.3]), ("fresh",))
    ds = run_sweep(sim, spec, params={"rho": 0.0}, state0=(0.05, 0.0),
                   sampling=SamplingSpec(n_transient=200, n_samples=24, tol=1e-9), backend="serial", progress=False)
    assert ds["period"].sel(direction="fresh").values.tolist() == [3, 2, 1]


def _strongly_damped_map(u: float, v: float, t: float, params: dict) -> tuple[float, float, int]:
    rho = params["rho"]
    if u < 0:
        return u + rho, 0.0, 0
    return -math.sqrt(u) + u + rho, 0.0, 1


def test_sweep_input_errors(model: FmuModel) -> None:
    with pytest.raises(HarnessInputError, match="unknown FMU variable 'sigmaa'"):
        run_sweep(model, SweepSpec("sigmaa", np.array([0.1]), ("fresh",)), progress=False)
    with pytest.raises(HarnessInputError, match="initial state"):
        run_sweep(model, SweepSpec("u0", np.array([0.1]), ("up",)), progress=False)


@pytest.mark.slow  # a real CLI process interrupted, then resumed
def test_interrupted_cli_sweep_resumes_without_recomputing(tmp_path: Path, model: FmuModel) -> None:
    """Ctrl-C a running CLI sweep, rerun the same command: finished points are not redone and
    the result equals an uninterrupted run.  The interruption lands at a known point (the
    test hook sends SIGINT just before point 2 starts), so exactly 2 points are finished."""
    out = tmp_path / "s.nc"
    ckpt = tmp_path / "s.nc.partial"
    values = "0.3,0.4,0.5,0.6,0.7,0.9"
    cmd = [sys.executable, "-m", "harness", "sweep", "--values", values, "--mode", "fresh", "--transient", "300",
           "--samples", "10", "--backend", "serial", "--out", str(out), "--no-plot", "--no-progress"]
    env = {**os.environ, TEST_HOOK_ENV: "fresh-p00002:0:interrupt"}
    res = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=120, env=env)
    assert res.returncode == 130, res.stderr
    assert "interrupted: 2 of 6 points are kept" in res.stderr and "rerun the same command to resume" in res.stderr
    assert sorted(p.name for p in ckpt.glob("fresh-*.npz")) == ["fresh-p00000.npz", "fresh-p00001.npz"]
    assert not out.exists()

    res = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert "4 tasks computed, 2 resumed" in res.stdout
    assert not ckpt.exists()  # removed once the NetCDF file holds everything
    with xr.open_dataset(out) as resumed:
        assert int(resumed.attrs["tasks_resumed"]) == 2
        reference = run_sweep(model, SweepSpec("sigma", np.array([float(x) for x in values.split(",")]), ("fresh",)),
                              sampling=SamplingSpec(theta=SECTION_PHASE, n_transient=300, n_samples=10),
                              backend="serial", progress=False)  # at the command's section phase
        assert_same_results(resumed, reference)


def test_checkpoint_of_another_run_is_refused(tmp_path: Path, model: FmuModel) -> None:
    spec = SweepSpec("sigma", np.array([0.5]), ("fresh",))
    s = SamplingSpec(n_transient=5, n_samples=3)
    run_sweep(model, spec, sampling=s, backend="serial", checkpoint=str(tmp_path / "c"), progress=False)
    stats = SweepStats()
    run_sweep(model, spec, sampling=s, backend="serial", checkpoint=str(tmp_path / "c"), progress=False, stats=stats)
    assert (stats.computed, stats.resumed) == (0, 1)
    with pytest.raises(HarnessInputError, match="different run"):
        run_sweep(model, spec, params={"Gamma": 20.0}, sampling=s, backend="serial",
                  checkpoint=str(tmp_path / "c"), progress=False)


@pytest.mark.slow  # a real pool worker killed
def test_process_pool_loses_no_point_when_a_worker_dies(model: FmuModel, tmp_path: Path,
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    """A worker is SIGKILLed at a known point (the test hook, just before point 5 starts, once):
    the pool is replaced, the lost tasks rerun, and the results equal a serial run."""
    spec = SweepSpec("sigma", np.linspace(0.3, 0.9, 8), ("fresh",))
    sampling = SamplingSpec(n_transient=100, n_samples=10)
    marker = tmp_path / "killed"
    monkeypatch.setenv(TEST_HOOK_ENV, f"fresh-p00005:0:kill:{marker}")  # the spawned workers inherit it
    backend = ProcessBackend(2)
    try:
        ds = run_sweep(model, spec, sampling=sampling, backend=backend, progress=False)
    finally:
        backend.close()
    assert marker.exists() and backend.restarts == 1
    monkeypatch.delenv(TEST_HOOK_ENV)
    reference = run_sweep(model, spec, sampling=sampling, backend="serial", progress=False)
    assert_same_results(ds, reference)


def test_continuation_chain_reports_each_point(model: FmuModel) -> None:
    """A long chain moves the progress bar while it runs: one report per finished point
    (the last one arrives with the result)."""
    from harness import FmuSimulator
    from harness.runs.sweeps import execute, plan_tasks

    base = {k: v for k, v in model.defaults().items() if k not in ("u0", "v0")}
    tasks = plan_tasks(SweepSpec("sigma", np.array([0.5, 0.6, 0.7]), ("down",)), base, (-1.0, 0.0),
                       SamplingSpec(n_transient=5, n_samples=3))
    seen: list[tuple[str, int]] = []
    out = execute(tasks["down"], FmuSimulator(model.source()), lambda key, n, row: seen.append((key, n)))
    assert seen == [("down", 1), ("down", 2)]
    assert out["u"].shape == (3, 3)


def test_sampling_spec_is_checked_on_creation() -> None:
    with pytest.raises(HarnessInputError, match="theta"):
        SamplingSpec(theta=200.0)
    with pytest.raises(HarnessInputError, match="n_transient: negative"):
        SamplingSpec(n_transient=-1)
    with pytest.raises(TypeError):
        SamplingSpec(0.0, 100)  # keyword-only: no silent mix-up of theta and counts


def test_unpicklable_user_mapping_needs_the_serial_backend() -> None:
    sim = MappingSimulator(lambda u, v, t, p: (u, v, 0))
    with pytest.raises(HarnessInputError, match="backend='serial'"):
        run_sweep(sim, SweepSpec("a", np.array([1.0]), ("fresh",)), backend="processes", workers=1, progress=False)


def _broken_map(u: float, v: float, t: float, params: dict) -> tuple[float, float, int]:
    if params["a"] > 0.5:
        raise ZeroDivisionError("model blew up")
    return u, v, 0


@pytest.mark.parametrize("backend", ["serial", "processes"])
def test_a_failing_task_is_named(backend: str) -> None:
    from harness.errors import SweepTaskError

    spec = SweepSpec("a", np.array([0.1, 0.9]), ("fresh",))
    with pytest.raises(SweepTaskError, match=r"task fresh-p00001 failed .*ZeroDivisionError: model blew up"):
        run_sweep(MappingSimulator(_broken_map), spec, params={"a": 0.0}, backend=backend, workers=1,
                  sampling=SamplingSpec(n_transient=1, n_samples=2), progress=False)


def test_extend_lets_slow_points_near_a_window_edge_converge(model: FmuModel) -> None:
    """Just above the period-1 edge (rho = 1/4, eq (64)) the multiplier is close to -1; with
    --extend the point runs on until it is periodic: period 1, one impact."""
    p = model.defaults()
    sigma = 1.02 * brentq(lambda s: rho_of_sigma(s, p["nu"], p["Omega"], p["r"]) - 0.25, 1e-6, 50.0)
    spec = SweepSpec("sigma", np.array([sigma]), ("fresh",))
    ds = run_sweep(model, spec, sampling=SamplingSpec(n_transient=100, n_samples=30, extend=3000),
                   backend="serial", progress=False)
    assert int(ds["period"].item()) == 1 and int(ds["orbit_impacts"].item()) == 1
    assert ds["t"].values[0, 0, -1] > 100 + 30  # it did run on
