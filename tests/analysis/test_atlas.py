"""The atlas (``impact-harness atlas``) against independent truth: random pixels' attractors are
orbits of the exact flow (mapcheck.exact, Newton on its M-period map: the point, the impacts per
period, the multiplier behind the exponent), a chaotic pixel's exponent is the exact flow's
(two nearby orbits), the FMU route with CVODE labels pixels as the kernel does; a rerun resumes
from the finished tiles; the command's files and its one-line errors; the chart's curves are
checked against the pixels (a curve put where no edge is disagrees everywhere)."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from harness.runs.atlas.plane import AtlasPlane, RunLength
from harness.runs.atlas.scan import run_atlas_plane
from harness.runs.atlas.tiles import APERIODIC, CHAOTIC, PERIODIC, STICKING, start_kinds
from mapcheck.exact import ExactOscillator
from tests.support.cli import run_main
from tests.support.edges import ExactFlow

#: Figure 9's strongly damped oscillator on its compliant wall (harness/experiments/fig9.toml).
FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112, r=0.9, Gamma=10.0, wall=1)
FIG9_CLI = ["atlas", "--config", "harness/experiments/fig9.toml", "--solver", "closed-form", "--no-progress"]


@pytest.fixture(scope="module")
def fig9_atlas():
    plane = AtlasPlane(FIG9, "Gamma", np.geomspace(10, 400, 4), np.array([0.2, 0.23, 0.45, 0.7, 0.95, 1.1]), starts=4,
                       theta=0.0)
    return plane, run_atlas_plane(plane, progress=False, tile_pixels=8)


def test_pixels_are_orbits_of_the_exact_flow(fig9_atlas) -> None:
    plane, a = fig9_atlas
    d = a.data
    per = np.argwhere(d["kind"] == PERIODIC)
    assert len({(int(d["period"][tuple(i)]), int(d["impacts"][tuple(i)])) for i in per}) >= 3  # P1, P2, P3 windows
    rng = np.random.default_rng(1)
    for i, j, s in per[rng.choice(len(per), 5, replace=False)]:
        M, imp = int(d["period"][i, j, s]), int(d["impacts"][i, j, s])
        z = np.array([d["u"][i, j, s], d["v"][i, j, s]])
        flow = ExactFlow(FIG9["nu"], FIG9["Omega"], FIG9["r"], float(plane.p2[i]), "compliant", theta=0.0)
        orb = flow.orbit(float(plane.sigma[j]), M, z)
        assert orb.converged and int(orb.contacts.sum()) == imp
        assert np.min(np.max(np.abs(orb.z - z), axis=1)) < 1e-6  # the atlas's point is on the exact orbit
        mu = np.max(np.abs(flow.multipliers(float(plane.sigma[j]), z, M)))
        assert d["lyapunov"][i, j, s] == pytest.approx(math.log(mu) / M, abs=1e-5)


def test_a_chaotic_pixels_exponent_is_the_exact_flows() -> None:
    plane = AtlasPlane(FIG9, "Gamma", np.array([3000.0]), np.array([0.6]), starts=2, theta=0.0)
    d = run_atlas_plane(plane, progress=False).data
    assert np.all(d["kind"] == CHAOTIC)
    lam = float(d["lyapunov"][0, 0, 0])
    ex = ExactOscillator(FIG9["nu"], FIG9["Omega"], 0.6, r=FIG9["r"], Gamma=3000.0, wall="compliant")
    z = np.array([d["u"][0, 0, 0], d["v"][0, 0, 0]])
    w, h, total, n = np.array([1.0, 1.0]) / math.sqrt(2), 1e-7, 0.0, 100
    for k in range(n):  # two orbits h apart, renormalised each period: the largest exponent
        a = ex.state_at(z[0], z[1], k, k + 1.0)
        b = ex.state_at(z[0] + h * w[0], z[1] + h * w[1], k, k + 1.0)
        dz = (np.array(b[:2]) - np.array(a[:2])) / h
        total += math.log(np.linalg.norm(dz))
        w, z = dz / np.linalg.norm(dz), np.array(a[:2])
    assert total / n > 0.05 and lam > 0.05 and lam == pytest.approx(total / n, abs=0.1)


@pytest.mark.slow  # CVODE through the FMU, a few hundred periods per start
def test_the_fmu_route_with_cvode_labels_pixels_as_the_kernel(model) -> None:
    params = {**FIG9, "solver": 0}
    plane = AtlasPlane(params, "Gamma", np.array([10.0, 100.0]), np.array([0.22, 0.5, 1.0]), starts=2, theta=0.0,
                       run=RunLength(n_max=300, n_lyap=100))
    fmu = run_atlas_plane(plane, "fmu", model, backend="serial", progress=False).data
    ker = run_atlas_plane(plane, progress=False).data
    np.testing.assert_array_equal(fmu["kind"], ker["kind"])
    np.testing.assert_array_equal(fmu["period"], ker["period"])
    np.testing.assert_array_equal(fmu["impacts"], ker["impacts"])
    ok = fmu["kind"] == PERIODIC
    np.testing.assert_allclose(fmu["lyapunov"][ok], ker["lyapunov"][ok], atol=1e-3)


def test_a_rerun_computes_only_the_missing_tiles(tmp_path) -> None:
    plane = AtlasPlane(FIG9, "Gamma", np.geomspace(10, 400, 5), np.linspace(0.15, 1.1, 4), starts=3, theta=0.0)
    ckpt = tmp_path / "ckpt"
    first = run_atlas_plane(plane, progress=False, checkpoint=str(ckpt), tile_pixels=4)
    tiles = sorted(ckpt.glob("tile-*.npz"))
    assert len(tiles) == first.tiles == 5
    for p in tiles[1:3]:
        p.unlink()  # as if interrupted before these two finished
    again = run_atlas_plane(plane, progress=False, checkpoint=str(ckpt), tile_pixels=4)
    assert again.resumed == 3
    for k in first.data:
        np.testing.assert_array_equal(again.data[k], first.data[k])
    other = AtlasPlane(FIG9, "Gamma", np.geomspace(10, 400, 5), np.linspace(0.15, 1.1, 4), starts=2, theta=0.0)
    with pytest.raises(Exception, match="another atlas"):
        run_atlas_plane(other, progress=False, checkpoint=str(ckpt), tile_pixels=4)


@pytest.mark.slow  # real processes interrupted and rerun
def test_cli_interrupted_at_a_tile_keeps_the_finished_ones_and_resumes(tmp_path) -> None:
    import os
    import subprocess
    import sys
    from pathlib import Path

    import xarray as xr

    from harness.runs.tasks import TEST_HOOK_ENV

    root = Path(__file__).resolve().parents[2]
    out = tmp_path / "a"
    # 8 x 1024 pixels: two tiles of 4 rows (4096 pixels each)
    cmd = [sys.executable, "-m", "harness", *FIG9_CLI, "--param2", "Gamma", "--range", "10:100", "--sigma-range",
           "0.2:1", "--grid", "8x1024", "--starts", "1", "--no-plot"]
    first = subprocess.run([*cmd, "--out", str(out)], cwd=root, capture_output=True, text=True, timeout=600,
                           env={**os.environ, TEST_HOOK_ENV: "atlas-tile-00001:0:interrupt"})
    assert first.returncode == 130 and "interrupted" in first.stderr, first.stderr
    assert sorted(p.name for p in (out / "atlas.partial").glob("tile-*.npz")) == ["tile-00000.npz"]
    second = subprocess.run([*cmd, "--out", str(out)], cwd=root, capture_output=True, text=True, timeout=600)
    assert second.returncode == 0, second.stderr
    resumed = xr.open_dataset(out / "atlas.nc")
    assert resumed.attrs["atlas.tiles_resumed"] == 1 and resumed.attrs["atlas.tiles"] == 2
    fresh = subprocess.run([*cmd, "--out", str(tmp_path / "fresh")], cwd=root, capture_output=True, text=True,
                           timeout=600)
    assert fresh.returncode == 0, fresh.stderr
    for name in ("attractor", "kind", "period", "impacts", "lyapunov"):
        np.testing.assert_array_equal(resumed[name].values, xr.open_dataset(tmp_path / "fresh" / "atlas.nc")[name].values)


def _chart_json(path, curves: list[tuple[int, str, list[float], list[float]]], closes=None) -> None:
    windows = {}
    for M, side, p2, sigma in curves:
        w = windows.setdefault(M, {"M": M, "curves": {}, "closing": {"closes": closes}})
        w["curves"][side] = {"kind": "flip", "p2": p2, "sigma": sigma}
    path.write_text(json.dumps({"windows": list(windows.values())}))


def test_cli_files_classes_and_curves(tmp_path, capsys) -> None:
    import xarray as xr

    chart = tmp_path / "chart.json"
    # a "lower edge" of the period-2 window through the middle of the window: wrong everywhere
    _chart_json(chart, [(2, "lower", [10.0, 100.0], [0.6, 0.6])])
    out = tmp_path / "atlas"
    code, stdout, err = run_main([*FIG9_CLI, "--param2", "Gamma", "--range", "10:100", "--log", "--sigma-range",
                                  "0.15:1.1", "--grid", "4x20", "--starts", "3", "--curves", str(chart), "--out",
                                  str(out)], capsys)
    assert code == 0, err
    res = json.loads((out / "atlas.json").read_text())
    by = {(c["M"], c["impacts"]): c for c in res["classes"] if c["kind"] == "periodic"}
    assert {(1, 1), (2, 1), (3, 1)} <= set(by)
    for c in by.values():
        assert set(c) >= {"M", "impacts", "pixels", "p2_range", "sigma_range"} and c["pixels"] > 0
        assert 10 <= c["p2_range"][0] <= c["p2_range"][1] <= 100 and 0.15 <= c["sigma_range"][0] <= 1.1
    # Figure 9's windows, period adding as sigma decreases (Gamma = 10: P1 above ~0.8, P2, P3 below ~0.3)
    assert by[(1, 1)]["sigma_range"][0] > by[(2, 1)]["sigma_range"][0] > by[(3, 1)]["sigma_range"][0]
    cv = res["curves"]
    assert cv["checked"] > 0 and cv["disagree"] == cv["checked"] and set(cv["by_reason"]) == {"both sides"}
    ds = xr.open_dataset(out / "atlas.nc")
    assert ds["attractor"].shape == (4, 20, 3) and ds.attrs["atlas.param2"] == "Gamma" and "fmu_sha256" in ds.attrs
    assert (out / "atlas.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "probes disagree" in (out / "report.md").read_text() and "P2, 1 impact" in stdout
    assert not (out / "atlas.partial").exists()


def test_curves_past_their_windows_closing_are_not_probed(tmp_path, capsys) -> None:
    chart = tmp_path / "chart.json"
    _chart_json(chart, [(2, "lower", [10.0, 100.0], [0.6, 0.6])], closes=5.0)
    out = tmp_path / "atlas"
    code, _, err = run_main([*FIG9_CLI, "--param2", "Gamma", "--range", "10:100", "--sigma-range", "0.3:0.9",
                             "--grid", "4x12", "--starts", "2", "--curves", str(chart), "--out", str(out),
                             "--no-plot"], capsys)
    assert code == 0, err
    cv = json.loads((out / "atlas.json").read_text())["curves"]
    assert cv["checked"] == 0 and cv["past_closing"] > 0


@pytest.mark.parametrize("bad, flag, what", [
    (["--grid", "0x5"], "--grid", ">= 1"),
    (["--grid", "abc"], "--grid", "NP2xNSIGMA"),
    (["--range", "5"], "--range", "LO:HI"),
    (["--range", "100:10"], "--range", "LO < HI"),
    (["--range=-5:10", "--log"], "--range", "LO > 0"),
    (["--range=-5:10"], "--range", "> 0"),
    (["--sigma-range=-2:1"], "--sigma-range", "LO > -1"),
    (["--starts", "0"], "--starts", "1..256"),
    (["--M-max", "0"], "--M-max", "1..64"),
    (["--max-periods", "10"], "--max-periods", "twice"),
    (["--tol", "0"], "--tol", "(0, 0.1)"),
    (["--wall", "rigid"], "--param2", "compliant"),
    (["--kernel", "batch", "--solver", "cvode"], "--kernel", "closed form"),
    (["--grid", "100000x100000"], "--grid", "memory"),
    (["--curves", "/nonexistent/chart.json"], "--curves", "cannot read"),
])
def test_cli_bad_input_is_one_line(tmp_path, capsys, bad: list[str], flag: str, what: str) -> None:
    argv = [*FIG9_CLI, "--param2", "Gamma", "--range", "10:100", "--grid", "3x3", "--starts", "2", "--out",
            str(tmp_path / "a"), "--no-plot"]
    for i, a in enumerate(bad):  # a flag given again overrides the default above
        if a.startswith("--") and a.split("=")[0] in argv and "=" not in a:
            j = argv.index(a)
            del argv[j: j + 2]
    code, _, err = run_main([*argv, *bad], capsys)
    assert code == 2, err
    assert flag in err and what in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_a_start_recurring_on_an_orbit_that_is_not_stable_has_not_settled() -> None:
    """A class is stable at a pixel only where a start reached an attractor of it: a start the kernel
    found recurring on a period-2 orbit with a non-negative exponent (a saddle next to a flip, +0.002
    at Gamma 122.15 on nu = 4, Omega = 1, r = 0.7) counts as aperiodic, not as that orbit; a stable
    orbit, a sticking one (its exponent is that of the sliding) and a chaotic start keep their kinds."""
    from harness.fmu import atlas_kernel as ak

    n = 5
    status = np.array([[ak.PERIODIC, ak.PERIODIC, ak.PERIODIC, ak.PERIODIC, ak.APERIODIC]])
    lyap = np.array([[-0.3, 0.002, 0.0, 0.5, 0.4]])
    sticks = np.array([[False, False, False, True, False]])
    b = ak.AtlasBatch(np.ones(1, bool), status, np.full((1, n), 2), np.ones((1, n), int), np.full((1, n), 100),
                      sticks, lyap, np.zeros((1, n, 2, 2)), "")
    assert start_kinds(b).tolist() == [[PERIODIC, APERIODIC, APERIODIC, STICKING, CHAOTIC]]
