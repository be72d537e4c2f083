"""Basins of attraction: attractors told apart by their stroboscopic orbits,
coexisting attractors of equal period kept apart, starts inside a rigid wall marked invalid,
parallel and resumable like sweeps.  The labels are checked against the closed-form flow of
mapcheck (an independent solver): every attractor is a periodic orbit of the exact flow with
the same wall entries, and starts are followed there to the attractor they were labelled with."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from harness import FmuModel, SamplingSpec, SweepSpec, run_sweep
from harness.dynamics.attractors.identity import INVALID, NOT_PERIODIC, hausdorff, identify_attractors
from harness.runs.basins.scan import run_basins
from harness.runs.tasks import TEST_HOOK_ENV
from mapcheck.exact import ExactOscillator

from tests.support.cli import run_main

ROOT = Path(__file__).resolve().parents[2]

#: Figure 7's hysteresis parameters at sigma = 0.01: the up scan sits on a period-3 orbit with
#: one impact, the down scan on a period-3 orbit with two (tests/harness/test_cli_signals.py's
#: loop): two coexisting attractors of the same period.
COEXIST = {"nu": 0.196, "Omega": 7.368, "r": 0.9, "Gamma": 1000.0, "wall": "compliant", "sigma": 0.01, "solver": 1}
#: An underdamped oscillator (not the paper's) on a rigid wall: one stable one-impact period-1 orbit.
RIGID = {"nu": 0.8, "Omega": 2.5, "r": 0.8, "wall": "rigid", "sigma": 1.7, "solver": 1}


def _exact(params: dict) -> ExactOscillator:
    return ExactOscillator(params["nu"], params["Omega"], params["sigma"], r=params["r"],
                           Gamma=params.get("Gamma", 10.0), wall=params["wall"])


# -- identification on constructed samples -----------------------------------------------------
def _orbit_samples(points: np.ndarray, n: int, shift: int = 0, noise: float = 0.0, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    idx = (np.arange(n) + shift) % len(points)
    return points[idx] + noise * rng.standard_normal((n, 2))


def test_identify_separates_equal_periods_and_merges_phase_shifts() -> None:
    a = np.array([[-0.5, 1.0], [-0.2, -2.0], [-0.9, 0.3]])
    b = a + np.array([0.3, 0.0])  # same period, same impacts, another orbit
    starts = [(a, 3, 1, 0, 0.0), (a, 3, 1, 1, 1e-7), (a, 3, 1, 2, 0.0), (b, 3, 1, 0, 0.0), (b, 3, 1, 2, 1e-7),
              (a, 3, 2, 0, 0.0)]  # the last: the same points with other wall entries is another attractor
    u = np.stack([_orbit_samples(p, 12, s, e, k)[:, 0] for k, (p, _, _, s, e) in enumerate(starts)])
    v = np.stack([_orbit_samples(p, 12, s, e, k)[:, 1] for k, (p, _, _, s, e) in enumerate(starts)])
    period = np.array([m for _, m, _, _, _ in starts])
    impacts = np.array([k for _, _, k, _, _ in starts])
    labels, att = identify_attractors(u, v, period, impacts, match_tol=1e-4)
    assert labels.tolist() == [0, 0, 0, 1, 1, 2]  # ordered by basin size
    assert [(x.period, x.impacts, x.starts) for x in att] == [(3, 1, 3), (3, 1, 2), (3, 2, 1)]
    assert hausdorff(att[0].points, a) == 0.0 and hausdorff(att[1].points, b) == 0.0
    # a tolerance larger than the orbits' distance merges what should stay apart
    merged, _ = identify_attractors(u, v, period, impacts, match_tol=0.5)
    assert merged.tolist() == [0, 0, 0, 0, 0, 1]


def test_hausdorff_distance_is_symmetric_and_sees_extra_points() -> None:
    """The definition: the larger of the two directed distances, so that an orbit whose points
    are a subset of another's (a period-1 orbit at one point of a period-2 orbit) is not the
    same attractor; random point sets check the symmetry and the value by brute force."""
    one = np.array([[0.0, 0.0]])
    two = np.array([[0.0, 0.0], [0.3, -0.1]])
    assert hausdorff(one, two) == hausdorff(two, one) == 0.3  # max norm of the unmatched point
    rng = np.random.default_rng(7)
    for n, m in [(1, 3), (4, 2), (5, 5)]:
        a, b = rng.normal(size=(n, 2)), rng.normal(size=(m, 2))
        def directed(x, y):  # sup over x of the distance to the nearest point of y
            return max(min(max(abs(p[0] - q[0]), abs(p[1] - q[1])) for q in y) for p in x)
        truth = max(directed(a, b), directed(b, a))
        assert hausdorff(a, b) == hausdorff(b, a) == truth


def test_identify_marks_not_periodic_and_invalid() -> None:
    u = np.zeros((2, 2, 4))
    v = np.zeros((2, 2, 4))
    period = np.array([[1, 0], [-1, 1]])
    impacts = np.array([[0, -1], [-1, 0]])
    labels, att = identify_attractors(u, v, period, impacts, 1e-6)
    assert labels.tolist() == [[0, NOT_PERIODIC], [INVALID, 0]] and len(att) == 1 and att[0].starts == 2
    with pytest.raises(ValueError):
        identify_attractors(u, v, period, impacts, float("nan"))


# -- the FMU ---------------------------------------------------------------------------------
def test_second_axis_v0_starts_each_row_from_its_own_v0(model: FmuModel) -> None:
    """A u0 x v0 scan ran every row from the first v0 (the start argument wins over v0 among
    the parameters).  After one period every point equals the exact flow from its own start."""
    u0, v0 = np.array([-1.0, -0.5]), np.array([-2.0, 0.0, 3.0])
    ds = run_sweep(model, SweepSpec("u0", u0, ("fresh",), "v0", v0), RIGID, (u0[0], v0[0]),
                   SamplingSpec(n_transient=0, n_samples=2), backend="serial", progress=False)
    osc = _exact(RIGID)
    for i, a in enumerate(u0):
        for j, b in enumerate(v0):
            states, _ = osc.strobe(a, b, [1.0, 2.0])
            got = np.column_stack([ds["u"].values[0, i, j], ds["v"].values[0, i, j]])
            np.testing.assert_allclose(got, states, rtol=0, atol=1e-9)


@pytest.mark.slow  # a basin scan through the FMU, each attractor shot
def test_coexisting_attractors_of_equal_period(model: FmuModel) -> None:
    s = SamplingSpec(n_transient=300, n_samples=40)
    u0, v0 = np.linspace(-1.2, 0.0, 7), np.linspace(-8.0, 8.0, 7)
    ds = run_basins(model, u0, v0, COEXIST, s, workers=2, progress=False)
    att = {(int(p), int(k)): i for i, (p, k) in enumerate(zip(ds["attractor_period"].values,
                                                                ds["attractor_impacts"].values))}
    assert sorted(att) == [(3, 1), (3, 2)], json.loads(ds.attrs["basins.attractors"])
    osc = _exact(COEXIST)
    tol = ds.attrs["basins.match_tol"]
    for (p, k), i in att.items():
        pts = ds["attractor_points"].values[i, :p]
        # a periodic orbit of the exact flow with k wall entries per orbit period
        states, counts = osc.strobe(pts[0, 0], pts[0, 1], np.arange(1, p + 1, dtype=float))
        assert hausdorff(states, pts) < 1e-6 and counts[-1] == k
    labels = ds["attractor"].values
    assert set(np.unique(labels)) <= {0, 1} and (labels == 1).any()
    # starts followed by the exact flow end on the attractor they were labelled with
    rng = np.random.default_rng(3)
    for i, j in zip(*np.nonzero(labels >= 0)):
        if rng.random() > 0.25:
            continue
        states, _ = osc.strobe(u0[i], v0[j], np.arange(s.n_transient + 1, s.n_transient + 4, dtype=float))
        mine = ds["attractor_points"].values[labels[i, j], :3]
        other = ds["attractor_points"].values[1 - labels[i, j], :3]
        assert hausdorff(states, mine) < tol < hausdorff(states, other)


def test_starts_inside_a_rigid_wall_are_invalid_and_the_rest_runs(model: FmuModel) -> None:
    u0, v0 = np.array([-2.0, -0.5, 0.0, 0.25]), np.array([-1.0, 0.0, 1.0])
    # 400 periods: the orbit's multiplier is ~ -0.92, so the samples sit on it to ~1e-14
    ds = run_basins(model, u0, v0, RIGID, SamplingSpec(n_transient=400, n_samples=20), backend="serial",
                    progress=False)
    labels = ds["attractor"].values
    # inside: u0 > 0 (contact for u > u_wall = 0), or on the wall moving into it
    inside = (u0[:, None] > 0) | ((u0[:, None] == 0) & (v0[None, :] > 0))
    assert ((labels == INVALID) == inside).all()
    assert (labels[~inside] == 0).all() and int(ds["attractor_period"][0]) == 1
    assert int(ds["attractor_impacts"][0]) == 1 and ds.attrs["basins.invalid_starts"] == int(inside.sum())
    pt = ds["attractor_points"].values[0, 0]
    states, counts = _exact(RIGID).strobe(pt[0], pt[1], [1.0])
    np.testing.assert_allclose(states[0], pt, rtol=0, atol=1e-9)
    assert counts[0] == 1


# -- the command ------------------------------------------------------------------------------
ARGS = ["basins", "--set", "nu=0.8", "--set", "Omega=2.5", "--set", "r=0.8", "--set", "wall=rigid",
        "--set", "sigma=1.7", "--solver", "closed-form", "--u0-grid=-2:0.5:4", "--v0-grid=-3:3:3",
        "--transient", "400", "--samples", "20", "--no-progress"]


@pytest.mark.parametrize("kernel", ["fmu", "batch"])
def test_cli_writes_netcdf_figure_and_lists_the_attractors(tmp_path: Path, capsys, kernel: str) -> None:
    out = tmp_path / "b.nc"
    code, stdout, err = run_main([*ARGS, "--workers", "2", "--kernel", kernel, "--out", str(out)], capsys)
    assert code == 0, err
    assert "A0: P1, 1 impact" in stdout and "invalid (refused by the FMU: inside a rigid wall): 3 start(s)" in stdout
    ds = xr.open_dataset(out)
    assert ds["attractor"].dims == ("u0", "v0") and ds.attrs["basins.invalid_starts"] == 3
    png = out.with_suffix(".png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("bad, flag", [("--u0-grid=-1:0", "--u0-grid"), ("--v0-grid=1:1:3", "--v0-grid"),
                                       ("--match-tol=-1", "--match-tol")])
def test_cli_bad_input_is_one_line(tmp_path: Path, capsys, bad: str, flag: str) -> None:
    argv = [a for a in ARGS if not a.startswith(bad.split("=")[0])] + [bad, "--out", str(tmp_path / "b.nc")]
    code, _, err = run_main(argv, capsys)
    assert code == 2 and flag in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


@pytest.mark.slow
def test_cli_interrupted_scan_resumes_with_no_point_missing(tmp_path: Path) -> None:
    out = tmp_path / "b.nc"
    # the FMU path (a sweep of every start, resumed point by point; the batch kernel's tiles:
    # tests/harness/test_basins_kernel.py)
    cmd = [sys.executable, "-m", "harness", *ARGS, "--kernel", "fmu", "--backend", "serial", "--out", str(out),
           "--no-plot"]
    first = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=600,
                           env={**os.environ, TEST_HOOK_ENV: "fresh-s0001-p00002:0:interrupt"})
    assert first.returncode == 130, first.stderr
    assert "points are kept in" in first.stderr and "rerun the same command to resume" in first.stderr
    second = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert second.returncode == 0, second.stderr
    resumed = xr.open_dataset(out)
    fresh = tmp_path / "fresh.nc"
    whole = subprocess.run([*cmd[:-3], "--out", str(fresh), "--no-plot"], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert whole.returncode == 0, whole.stderr
    xr.testing.assert_equal(resumed["attractor"], xr.open_dataset(fresh)["attractor"])
    np.testing.assert_array_equal(resumed["u"].values, xr.open_dataset(fresh)["u"].values)


def test_a_sweep_of_u0_marks_starts_inside_the_wall_and_other_refusals_stay_errors(tmp_path: Path, capsys) -> None:
    """A scan stopped entirely at one start inside the rigid wall; that start is now an invalid
    point.  A refusal that is not about the start (the closed-form solver with the Hertz law)
    still stops the run with the FMU's message."""
    out = tmp_path / "s.nc"
    base = ["sweep", "--param", "u0", "--mode", "fresh", "--set", "wall=rigid", "--transient", "3", "--samples", "4",
            "--workers", "1", "--out", str(out), "--no-plot", "--no-progress"]
    code, _, err = run_main([*base, "--values", "-0.5,0.01,-0.2"], capsys)
    assert code == 0, err
    ds = xr.open_dataset(out)
    assert ds["period"].sel(u0=0.01).item() == -1 and np.isnan(ds["u"].sel(u0=0.01).values).all()
    assert (ds["period"].sel(u0=[-0.5, -0.2]).values >= 0).all() and np.isfinite(ds["u"].sel(u0=-0.2).values).all()
    code, _, err = run_main([*ARGS, "--set", "wall=compliant", "--set", "contact=1",
                             "--out", str(tmp_path / "b.nc")], capsys)
    assert code == 2 and "Hertz" in err and "Traceback" not in err
