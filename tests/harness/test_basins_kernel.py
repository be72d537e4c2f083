"""The batch kernel (fmu_src/batch.c through harness/fmu/batch_kernel.py) against the FMU and the
exact flow: its stroboscopic points are the FMU's closed-form mode's to 1e-12 (bit for bit, the
same C calls), the CVODE mode's to 1e-8, and mapcheck's closed form's (an independent
implementation in Python) to 1e-9, on random starts over rigid and compliant walls, a stick-slip
orbit included; early stopping changes no label."""
from __future__ import annotations

import numpy as np
import pytest

from harness import FmuModel, SamplingSpec
from harness.dynamics.attractors.identity import STICKING
from harness.dynamics.maps.sampling import strobe
from harness.errors import HarnessInputError
from harness.fmu import batch_kernel as bk
from harness.fmu.simulator import FmuSimulator
from harness.runs.basins.kernel_scan import run_basins_kernel
from harness.runs.basins.tiles import label_result
from mapcheck.exact import ExactOscillator

#: name -> FMU parameters, section phase, box of starts (u1, u2, v1, v2)
CASES = {
    # Figure 7's two coexisting period-3 orbits (compliant wall, Gamma = 1000)
    "fig7-compliant": (dict(nu=0.196, Omega=7.368, r=0.9, Gamma=1000.0, wall=1, sigma=0.01), 0.0, (-1.2, 0, -8, 8)),
    # Figure 9's strongly damped oscillator on its compliant wall
    "fig9-compliant": (dict(nu=4.605170185988091, Omega=0.3059238689620112, r=0.9, Gamma=10.0, wall=1, sigma=0.5),
                       0.5, (-2, 0.5, -3, 3)),
    # an underdamped oscillator on a rigid wall: one impact per period
    "underdamped-rigid": (dict(nu=0.8, Omega=2.5, r=0.8, wall=2, sigma=1.7), 0.0, (-2, 0, -3, 3)),
    # a stick-slip orbit: pushed onto the rigid wall by F_ext, released by the forcing, chatter
    # (33 impacts per period) back into sticking; stuck at every sample at theta = 0.25
    "stick-slip-rigid": (dict(nu=0.196, Omega=7.368, r=0.5, wall=2, sigma=2.0, F_ext=80.0), 0.25, (-0.5, 0, -2, 2)),
    # chatter that ends in sticking and a release within each period (about 33 impacts)
    "chatter-rigid": (dict(nu=0.196, Omega=7.368, r=0.5, wall=2, sigma=10.0), 0.0, (-0.5, 0, -2, 2)),
}
PERIODS = 12


@pytest.fixture(scope="module")
def fmu_sim() -> FmuSimulator:
    from pathlib import Path

    model = FmuModel(Path(__file__).resolve().parents[2] / "build" / "fmu" / "ImpactOscillator.fmu")
    with FmuSimulator(model.source()) as sim:
        yield sim


def _starts(box: tuple[float, float, float, float], n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return rng.uniform(box[0], box[1], n), rng.uniform(box[2], box[3], n)


@pytest.mark.parametrize("case", sorted(CASES))
def test_kernel_is_the_fmus_closed_form_and_agrees_with_cvode(case: str, fmu_sim: FmuSimulator) -> None:
    params, theta, box = CASES[case]
    u0, v0 = _starts(box, 10, seed=len(case))
    res = bk.run_batch({**params, "solver": 1}, u0, v0, theta, 0, PERIODS, threads=2)
    assert not res.error and np.all(res.status == bk.RAN)
    for i in range(u0.size):
        cf = strobe(fmu_sim, {**params, "solver": 1}, (u0[i], v0[i]), theta, 0, PERIODS)
        assert np.max(np.abs(cf.u - res.u[i])) <= 1e-12 and np.max(np.abs(cf.v - res.v[i])) <= 1e-12
        np.testing.assert_array_equal(cf.impacts, res.impacts[i])
        cv = strobe(fmu_sim, {**params, "solver": 0}, (u0[i], v0[i]), theta, 0, PERIODS)
        scale = max(1.0, float(np.max(np.abs(cv.v))))
        assert np.max(np.abs(cv.u - res.u[i])) <= 1e-8 * scale and np.max(np.abs(cv.v - res.v[i])) <= 1e-8 * scale
        # chatter's impacts accumulate geometrically before sticking: its last few, each shallower
        # than CVODE's tolerance, fall on either side of where each solver declares sticking
        # (the states after it agree to 1e-8 all the same)
        chatter = res.impacts[i] >= 8
        np.testing.assert_array_equal(cv.impacts[~chatter], res.impacts[i][~chatter])
        assert np.all(np.abs(cv.impacts[chatter] - res.impacts[i][chatter]) <= 0.1 * res.impacts[i][chatter])
    if case.startswith("stick-slip"):
        assert res.stuck.all() and res.impacts.max() > 20  # the sticking and the chatter are really there


@pytest.mark.parametrize("case", ["fig7-compliant", "underdamped-rigid", "chatter-rigid"])
def test_kernel_agrees_with_the_exact_flow_of_mapcheck(case: str) -> None:
    params, theta, box = CASES[case]
    u0, v0 = _starts(box, 4, seed=7)
    res = bk.run_batch({**params, "solver": 1}, u0, v0, theta, 0, 6)
    p = params
    wall = {1: "compliant", 2: "rigid"}[p["wall"]]
    osc = ExactOscillator(p["nu"], p["Omega"], p["sigma"], r=p["r"], Gamma=p.get("Gamma", 10.0), wall=wall,
                          **({"F_ext": p["F_ext"]} if "F_ext" in p else {}))
    times = theta + np.arange(1, 7)
    for i in range(u0.size):
        exact, _ = osc.strobe(u0[i], v0[i], times, t0=theta)
        scale = max(1.0, float(np.max(np.abs(exact))))
        assert np.max(np.abs(exact[:, 0] - res.u[i])) <= 1e-9 * scale
        assert np.max(np.abs(exact[:, 1] - res.v[i])) <= 1e-9 * scale


@pytest.mark.parametrize("match_tol", [None, 0.3, 1.0])
def test_early_stopping_changes_no_label(match_tol: float | None) -> None:
    """Also with a coarse matching tolerance (up to the distance between the two attractors'
    nearest points, 1.2), where a single passage near an attractor's point would mislabel
    hundreds of starts: there the tolerance balls reach other basins (harness/runs/basins/ball.py)
    and the orbit must come round twice; at the scan's own tolerance one attractor's balls pass
    and one period labels its starts."""
    params, theta, box = CASES["fig7-compliant"]
    s = SamplingSpec(theta=theta, n_transient=150, n_samples=30)
    u0, v0 = np.linspace(box[0], box[1], 36), np.linspace(box[2], box[3], 36)
    fast = run_basins_kernel(None, u0, v0, {**params, "solver": 1}, s, match_tol, progress=False, tile_size=400)
    # the same grid with every start run in full: the seed is the whole grid, no tile stops early
    us, vs = (x.ravel() for x in np.meshgrid(u0, v0, indexing="ij"))
    full = bk.run_batch({**params, "solver": 1}, us, vs, theta, s.n_transient, s.n_samples)
    lab = label_result(full, s, bk.KnownAttractors.none(fast.attrs["basins.match_tol"]))
    assert fast.attrs["basins.periods_run_mean"] < 0.5 * (s.n_transient + s.n_samples)  # it did stop early
    one_period = fast["attractor_confirm_periods"].values == 1
    assert one_period.any() if match_tol is None else not one_period.any()
    np.testing.assert_array_equal(one_period, fast["attractor_ball_inside"].values)
    assert len(lab["candidates"]) == fast.sizes["attractor_index"] == 2
    # the full run's classes, named by the fast scan's attractors
    names = {}
    for k, c in enumerate(lab["candidates"]):
        for a in range(fast.sizes["attractor_index"]):
            p = int(fast["attractor_period"].values[a])
            if p == c.period and np.max(np.abs(np.sort(c.points, axis=0) - np.sort(
                    fast["attractor_points"].values[a, :p], axis=0))) < fast.attrs["basins.match_tol"]:
                names[-100 - k] = a
    mapped = np.array([names.get(int(x), int(x)) for x in lab["label"]]).reshape(fast["attractor"].shape)
    np.testing.assert_array_equal(mapped, fast["attractor"].values)


@pytest.mark.parametrize("case", ["fig7-compliant", "fig9-compliant", "underdamped-rigid"])
def test_the_recurrence_stop_ends_a_start_on_its_orbit(case: str) -> None:
    """A start stopped once its samples repeat (1e-9 of the orbit's size; the global search's seed
    asks 1e-12) is classified as the same orbit as the same start run in full (period, impacts,
    points within 1e-6), after fewer periods, and its points are a periodic orbit of mapcheck's
    exact flow (M periods from its last point return there to 1e-6); a start that does not repeat
    runs in full."""
    from harness.dynamics.attractors.identity import hausdorff
    from harness.dynamics.maps.classify import classify_orbit

    params, theta, box = CASES[case]
    u0, v0 = _starts(box, 24, seed=11)
    full = bk.run_batch({**params, "solver": 1}, u0, v0, theta, 200, 24)
    stop = bk.run_batch({**params, "solver": 1}, u0, v0, theta, 200, 24, recur_tol=1e-9)
    wall = {1: "compliant", 2: "rigid"}[params["wall"]]
    osc = ExactOscillator(params["nu"], params["Omega"], params["sigma"], r=params["r"],
                          Gamma=params.get("Gamma", 10.0), wall=wall)
    early = 0
    for i in range(u0.size):
        a = classify_orbit(full.u[i], full.v[i], full.impacts[i], 1e-6)
        b = classify_orbit(stop.u[i], stop.v[i], stop.impacts[i], 1e-6)
        if stop.periods[i] < 224:
            early += 1
            assert b.periodic
        if not a.periodic:
            continue
        assert (b.period, b.impacts) == (a.period, a.impacts)
        M = a.period
        pa = np.column_stack([full.u[i, -M:], full.v[i, -M:]])
        pb = np.column_stack([stop.u[i, -M:], stop.v[i, -M:]])
        scale = max(1.0, float(np.max(np.abs(pa))))
        assert hausdorff(pa, pb) <= 1e-6 * scale
        exact, _ = osc.strobe(pb[-1, 0], pb[-1, 1], theta + np.arange(1, M + 1), t0=theta)
        assert np.max(np.abs(exact[-1] - pb[-1])) <= 1e-6 * scale
    assert early > 0 and np.all(stop.periods <= full.periods)


#: the lightly damped oscillator of bench/global_search_bench.py: most starts converge slowly onto a
#: period-8 orbit, a quarter are still settling after 74 periods
LIGHTLY_DAMPED = (dict(nu=0.1, Omega=2.25, r=0.8, Gamma=100.0, wall=1, sigma=-0.005), 0.5, (-2.5, 0.5, -9, 9))


@pytest.mark.parametrize("case, sigma", [("fig9-compliant", 0.05), ("lightly-damped", None), ("fig7-compliant", None),
                                         ("chatter-rigid", None)])
def test_the_aperiodic_stop_changes_no_label(case: str, sigma: float | None) -> None:
    """A start stopped once its samples rule out every period, with no attractor able to recognise
    it any more (the global search's margin: the tolerance times 1 + ten times the starts' spread),
    is one that the same run in full leaves unmatched and not periodic: every label, with the
    attractors of a seed known (the strict rule), is the full run's; the stopped starts' samples so
    far are the full run's bit for bit, the others' whole results too.  Figure 9's chaos at
    sigma = 0.05 stops most starts at their 13th sample."""
    from dataclasses import replace

    from harness.runs.basins.registry import Registry

    params, theta, box = LIGHTLY_DAMPED if case == "lightly-damped" else CASES[case]
    params = {**params, "solver": 1, **({} if sigma is None else {"sigma": sigma})}
    u0, v0 = _starts(box, 160, seed=5)
    s, seed_s = (SamplingSpec(theta=theta, n_transient=n, n_samples=24, tol=1e-6) for n in (50, 200))
    seed = bk.run_batch(params, u0[:16], v0[:16], theta, 200, 24)
    reg = Registry(1e-2 * max(1.0, float(np.nanmax(np.abs(np.concatenate([seed.u.ravel(), seed.v.ravel()]))))))
    reg.merge(label_result(seed, seed_s, reg.known()))
    known = reg.known(strict=True)
    known = replace(known, confirm=np.maximum(4, 2 * known.period).astype(np.int32))
    full = bk.run_batch(params, u0, v0, theta, 50, 24, known)
    spread = max(float(np.ptp(u0)), float(np.ptp(v0)))
    stop = bk.run_batch(params, u0, v0, theta, 50, 24, known, aperiodic_tol=1e-6 * (1.0 + 10.0 * spread))
    a, b = label_result(full, s, known), label_result(stop, s, known)
    assert np.array_equal(a["label"], b["label"])
    assert [(c.period, c.impacts) for c in a["candidates"]] == [(c.period, c.impacts) for c in b["candidates"]]
    ap = stop.status == bk.APERIODIC
    assert np.all(full.status[ap] == bk.RAN) and np.all(stop.periods[ap] < 74)
    for i in np.flatnonzero(ap):
        k = stop.periods[i] - 50
        assert np.array_equal(stop.u[i, :k], full.u[i, :k]) and np.array_equal(stop.v[i, :k], full.v[i, :k])
        assert np.all(np.isnan(stop.u[i, k:]))
    rest = ~ap
    for name in ("label", "periods", "status", "u", "v", "impacts", "stuck"):
        x, y = getattr(full, name)[rest], getattr(stop, name)[rest]
        assert np.array_equal(x, y, equal_nan=name in ("u", "v")), name
    if (case, sigma) == ("fig9-compliant", 0.05):
        assert ap.mean() > 0.5 and np.min(stop.periods[ap]) == 63


@pytest.mark.parametrize("case, sigma, tol, max_period", [
    ("fig9-compliant", 0.3, 1e-6, None), ("fig9-compliant", 0.05, 1e-3, 5), ("chatter-rigid", None, 1e-6, None)])
def test_orbit_periods_are_classify_orbits(case: str, sigma: float | None, tol: float, max_period: int | None) -> None:
    """All starts' periods at once (:func:`harness.runs.basins.tiles.orbit_periods`) are
    :func:`harness.dynamics.maps.classify.classify_orbit`'s, row by row, periodic or not."""
    from harness.dynamics.maps.classify import classify_orbit
    from harness.runs.basins.tiles import orbit_periods

    params, theta, box = CASES[case]
    params = {**params, "solver": 1, **({} if sigma is None else {"sigma": sigma})}
    u0, v0 = _starts(box, 120, seed=9)
    res = bk.run_batch(params, u0, v0, theta, 40, 24)
    period, entries = orbit_periods(res.u, res.v, res.impacts, SamplingSpec(theta=theta, n_transient=40, n_samples=24,
                                                                            tol=tol, max_period=max_period))
    got = [classify_orbit(res.u[i], res.v[i], res.impacts[i], tol, max_period) for i in range(u0.size)]
    want = [(c.period, c.impacts) if c.periodic else (0, -1) for c in got]
    assert want == list(zip(period.tolist(), entries.tolist()))
    assert case == "chatter-rigid" or 0 < np.sum(period > 0) < period.size  # periodic rows and not


def test_a_start_still_chattering_at_its_samples_is_sticking_not_an_attractor() -> None:
    p, theta, box = CASES["chatter-rigid"]
    s = SamplingSpec(theta=0.0, n_transient=0, n_samples=4)  # no transient: not yet periodic
    u0, v0 = _starts(box, 30, seed=3)
    res = bk.run_batch({**p, "solver": 1}, u0, v0, 0.0, 0, 4)
    lab = label_result(res, s, bk.KnownAttractors.none())
    chatter = res.impacts.max(axis=1) >= 8
    assert chatter.any() and np.all(lab["label"][chatter] == STICKING)
    # stopped as soon as its samples rule out a period: sticking all the same, from the samples it has
    stop = bk.run_batch({**p, "solver": 1}, u0, v0, 0.0, 0, 4, aperiodic_tol=1e-6)
    assert np.any(stop.status == bk.APERIODIC)
    assert np.array_equal(label_result(stop, s, bk.KnownAttractors.none())["label"], lab["label"])


def test_the_kernel_refuses_what_it_cannot_run() -> None:
    with pytest.raises(HarnessInputError, match="Hertz|linear contact"):
        bk.run_batch({"wall": 1, "contact": 1}, np.zeros(1), np.zeros(1), 0.0, 0, 2)
    with pytest.raises(HarnessInputError, match="does not know the parameter nonsense"):
        bk.run_batch({"nonsense": 1.0}, np.zeros(1), np.zeros(1), 0.0, 0, 2)


# -- tiles, resumption, Dask, the command ---------------------------------------------------------
FIG7 = ["basins", "--config", "harness/experiments/fig7-hysteresis.toml", "--set", "sigma=0.01", "--solver",
        "closed-form", "--no-progress"]


def test_a_rerun_computes_only_the_missing_tiles(tmp_path) -> None:
    from harness.runs.sweep_collect import SweepStats

    params, theta, box = CASES["fig7-compliant"]
    s = SamplingSpec(theta=theta, n_transient=150, n_samples=30)
    u0, v0 = np.linspace(box[0], box[1], 30), np.linspace(box[2], box[3], 24)
    ckpt = tmp_path / "ckpt"
    first = run_basins_kernel(None, u0, v0, {**params, "solver": 1}, s, progress=False, tile_size=100,
                              checkpoint=str(ckpt))
    tiles = sorted(ckpt.glob("tile-*.npz"))
    assert len(tiles) == first.attrs["basins.tiles"] == 8
    for p in tiles[2:5]:
        p.unlink()  # as if interrupted before these three finished
    stats = SweepStats()
    again = run_basins_kernel(None, u0, v0, {**params, "solver": 1}, s, progress=False, tile_size=100,
                              checkpoint=str(ckpt), stats=stats)
    assert (stats.computed, stats.resumed) == (3, 5) and again.attrs["basins.tiles_resumed"] == 5
    np.testing.assert_array_equal(again["attractor"].values, first["attractor"].values)
    np.testing.assert_array_equal(again["periods_run"].values, first["periods_run"].values)


@pytest.mark.slow  # real processes interrupted and rerun
def test_cli_interrupted_at_a_tile_resumes_it_and_keeps_the_rest(tmp_path) -> None:
    import os
    import subprocess
    import sys
    from pathlib import Path

    import xarray as xr

    from harness.runs.tasks import TEST_HOOK_ENV

    root = Path(__file__).resolve().parents[2]
    out = tmp_path / "b.nc"
    cmd = [sys.executable, "-m", "harness", *FIG7, "--u0-grid=-1.2:0:30", "--v0-grid=-8:8:30", "--tile-size", "100",
           "--out", str(out), "--no-plot"]
    first = subprocess.run(cmd, cwd=root, capture_output=True, text=True, timeout=600,
                           env={**os.environ, TEST_HOOK_ENV: "tile-00004:0:interrupt"})
    assert first.returncode == 130, first.stderr
    assert "400 of 900 points are kept" in first.stderr
    second = subprocess.run(cmd, cwd=root, capture_output=True, text=True, timeout=600)
    assert second.returncode == 0, second.stderr
    resumed = xr.open_dataset(out)
    assert resumed.attrs["basins.tiles_resumed"] == 4
    fresh = tmp_path / "fresh.nc"
    whole = subprocess.run([*cmd[:-3], "--out", str(fresh), "--no-plot"], cwd=root, capture_output=True, text=True,
                           timeout=600)
    assert whole.returncode == 0, whole.stderr
    np.testing.assert_array_equal(resumed["attractor"].values, xr.open_dataset(fresh)["attractor"].values)


@pytest.mark.slow  # a CLI basins run with its zoom and its check through the FMU
def test_cli_zoom_check_and_figure(tmp_path, capsys) -> None:
    import xarray as xr

    from tests.support.cli import run_main

    out = tmp_path / "b.nc"
    code, stdout, err = run_main([*FIG7, "--u0-grid=-1.2:0:40", "--v0-grid=-8:8:40", "--zoom=-1:-0.8:-2:2",
                                  "--check-fmu", "40", "--uncertainty-pairs", "300", "--out", str(out)], capsys)
    assert code == 0, err
    ds = xr.open_dataset(out)
    assert ds.attrs["basins.kernel"] == "batch" and ds["attractor_zoom"].shape == (40, 40)
    assert ds.attrs["basins.fmu_check_equal"] == ds.attrs["basins.fmu_check_starts"] == 40
    assert bool(ds["attractor_confirmed"].all()) and np.all(ds["attractor_multiplier"].values < 1.0)
    f = dict(zip(ds["basin_class"].values.tolist(), ds["basin_fraction"].values.tolist()))
    assert sum(f.values()) == pytest.approx(1.0) and set(f) == {0, 1}
    for key in ("basins.entropy", "basins.boundary_entropy", "basins.uncertainty_exponent", "basins_zoom.entropy"):
        assert key in ds.attrs
    assert "basin entropy S_b" in stdout and "uncertainty exponent alpha" in stdout and "40 of 40" in stdout
    assert "from 300 random pairs per eps" in stdout and ds["pairs_uncertain_fraction"].size == 8
    assert out.with_suffix(".png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("bad, flag, what", [
    (["--zoom=-1:-2:0:1"], "--zoom", "U1 < U2"),
    (["--zoom=a:b"], "--zoom", "four numbers"),
    (["--kernel", "batch", "--solver", "cvode"], "--kernel", "closed form"),
    (["--kernel", "batch", "--lyapunov", "50"], "--kernel", "Lyapunov"),
    (["--zoom=-1:-0.8:-2:2", "--kernel", "fmu"], "--zoom", "batch kernel"),
    (["--uncertainty-pairs", "10", "--kernel", "fmu"], "--uncertainty-pairs", "batch kernel"),
])
def test_cli_bad_input_is_one_line(tmp_path, capsys, bad: list[str], flag: str, what: str) -> None:
    from tests.support.cli import run_main

    code, _, err = run_main([*FIG7, "--u0-grid=-1.2:0:4", "--v0-grid=-8:8:4", *bad, "--out", str(tmp_path / "b.nc")],
                            capsys)
    assert code == 2 and flag in err and what in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
