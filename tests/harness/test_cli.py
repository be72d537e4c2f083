"""The command line on the real FMU: bad input (exit 2, one line), outputs and provenance."""
from __future__ import annotations

import hashlib
import re
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
import xarray as xr

from tests.support.cli import run_main as _run_main

ROOT = Path(__file__).resolve().parents[2]
FMU = ROOT / "build" / "fmu" / "ImpactOscillator.fmu"
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def me_fmu(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The real FMU with its CoSimulation element replaced by ModelExchange."""
    assert FMU.is_file(), f"build the FMU first ({FMU} missing)"
    out = tmp_path_factory.mktemp("me") / "me.fmu"
    with zipfile.ZipFile(FMU) as src, zipfile.ZipFile(out, "w") as dst:
        for item in src.infolist():
            data = src.read(item.filename)
            if item.filename == "modelDescription.xml":
                data = re.sub(rb"<CoSimulation[^>]*?(/>|>.*?</CoSimulation>)",  # empty, or with <SourceFiles>
                              b'<ModelExchange modelIdentifier="ImpactOscillator"/>', data, flags=re.S)
            dst.writestr(item, data)
    return out


BAD_INPUT = [
    (["strobe", "--theta", "1.5"], "--theta", r"\[0, 1\)"),
    (["strobe", "--theta", "-0.2"], "--theta", r"\[0, 1\)"),
    (["strobe", "--samples", "-3"], "--samples", "negative count"),
    (["strobe", "--transient", "-1"], "--transient", "negative count"),
    (["sweep", "--num", "0"], "--num", "empty range"),
    (["sweep", "--start", "0.3", "--stop", "0.3", "--num", "5"], "--stop", "empty range"),
    (["sweep", "--values", ""], "--values", "empty range"),
    (["sweep", "--param", "sigmaa"], "--param", "unknown FMU variable 'sigmaa'"),
    (["strobe", "--set", "foo=1"], "--set foo", "unknown FMU variable 'foo'"),
    (["strobe", "--set", "wall=soft"], "--set wall", "not a valid Integer"),
    (["strobe", "--set", "sigma"], "--set", "NAME=VALUE"),
    (["strobe", "--fmu", "/nonexistent/x.fmu"], "--fmu", "no such file"),
    (["sweep", "--mode", "sideways"], "--mode", "unknown sweep mode"),
    (["sweep", "--scheduler", "localhost:8786"], "--scheduler", "tcp://HOST:PORT"),
    (["sweep", "--workers", "0"], "--workers", "must be >= 1"),
    (["sweep", "--scan", "Gamma"], "--scan", "NAME=V1,V2"),
    (["jacobian", "--x-start", "-1"], "--x-start", "must be > 0"),
    (["jacobian", "--theta", "2"], "--theta", r"\[0, 1\)"),
    (["sweep", "--transient", "abc"], "--transient", "invalid int value"),
    (["simulate", "--dt", "0"], "--dt", "must be > 0"),
    (["simulate", "--t0", "nan"], "--t0", "must be finite"),
    (["simulate", "--t-end", "inf"], "--t-end", "must be finite"),
    (["simulate", "--t0", "5", "--t-end", "1"], "--t-end", "greater than the start time"),
    (["sweep", "--values", "0.5", "--checkpoint", "/proc/no/such"], "--checkpoint", "cannot create the checkpoint"),
    (["sweep", "--mode", "both,up"], "--mode", "up-then-down loop already"),
    (["sweep", "--max-work", "nan"], "--max-work", "invalid positive number"),
    (["sweep", "--max-memory", "lots"], "--max-memory", "invalid size"),
    (["strobe", "--fmu", "/"], "--fmu", "is a directory"),
    # found by the FMU itself, quoted from its log
    (["strobe", "--set", "wall=rigid", "--u0", "0.01"], None, "rejected the settings.*inside the rigid wall"),
]


@pytest.mark.parametrize("argv, argument, reason", BAD_INPUT, ids=[" ".join(a) for a, _, _ in BAD_INPUT])
def test_bad_input_exits_2_with_one_line(tmp_path: Path, capsys, argv, argument, reason) -> None:
    code, out, err = _run_main([*argv, "--out", str(tmp_path / "x.nc"), "--no-progress"], capsys)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    assert argument is None or f"argument {argument}" in lines[0], lines[0]
    assert re.search(reason, lines[0]), lines[0]
    assert not (tmp_path / "x.nc").exists()


def test_model_exchange_fmu_is_refused(me_fmu: Path, capsys) -> None:
    code, _, err = _run_main(["strobe", "--fmu", str(me_fmu), "--no-progress"], capsys)
    assert code == 2
    assert err.count("\n") == 1 and "argument --fmu" in err and "not a Co-Simulation FMU" in err


@pytest.mark.slow  # two real CLI processes
@pytest.mark.parametrize("launcher", [[sys.executable, "-m", "harness"], [str(Path(sys.executable).with_name("impact-harness"))]],
                         ids=["python -m harness", "impact-harness"])
def test_real_processes_exit_2_without_traceback(launcher: list[str], tmp_path: Path) -> None:
    res = subprocess.run([*launcher, "strobe", "--theta", "1", "--out", str(tmp_path / "x.nc")],
                         capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert res.returncode == 2
    assert res.stderr.strip().count("\n") == 0 and "argument --theta" in res.stderr and "Traceback" not in res.stderr


@pytest.mark.parametrize("command", ["simulate", "strobe", "sweep", "jacobian"])
def test_help_of_each_subcommand(command: str, capsys) -> None:
    code, out, _ = _run_main([command, "--help"], capsys)
    assert code == 0
    assert "--config" in out and "--fmu" in out and "--out" in out


def test_sweep_from_toml_with_flag_override_writes_results_with_provenance(tmp_path: Path, capsys) -> None:
    cfg = tmp_path / "exp.toml"
    cfg.write_text(f"""
[fmu]
path = "{FMU}"
[model]
Gamma = 10.0
[sampling]
transient = 300
samples = 8
[sweep]
values = [0.25, 0.55, 1.0]
mode = "both"
[run]
backend = "serial"
""")
    out = tmp_path / "res" / "fig9.nc"
    code, stdout, err = _run_main(["sweep", "--config", str(cfg), "--samples", "12", "--out", str(out), "--no-progress"], capsys)
    assert code == 0, err
    assert "windows of maximal orbits" in stdout
    png = out.with_suffix(".png")
    assert png.read_bytes()[:8] == PNG_MAGIC and png.stat().st_size > 10_000
    with xr.open_dataset(out) as ds:
        assert ds["u"].dims == ("direction", "sigma", "sample")
        assert list(ds["direction"].values) == ["up", "down"] and ds.sizes["sample"] == 12  # flag beats file
        assert ds["sigma"].values.tolist() == [0.25, 0.55, 1.0]
        a = ds.attrs
        assert a["fmu_sha256"] == hashlib.sha256(FMU.read_bytes()).hexdigest()
        assert a["fmi_version"] == "2.0" and a["backend"].startswith("serial")
        assert a["model.Gamma"] == 10.0 and a["sampling.samples"] == 12 and a["sampling.transient"] == 300
        for lib in ("impact-grazing", "fmpy", "numpy", "xarray", "dask"):
            assert a[f"version.{lib}"] not in ("", "not installed")
        # the command line recorded with the file written out as flags (the file may change later)
        assert a["wall_time_s"] > 0 and a["command"].startswith("impact-harness sweep ")
        assert "--config" not in a["command"] and "--values 0.25,0.55,1.0" in a["command"]
        assert "--samples 12" in a["command"] and "--samples 8" not in a["command"]  # typed over the file
        # P2 at sigma = 0.55 in both directions (inside the eq (64) window, see the sweep tests)
        assert ds["period"].sel(sigma=0.55).values.tolist() == [2, 2]


def test_strobe_simulate_jacobian_write_files(tmp_path: Path, capsys) -> None:
    code, out, err = _run_main(["strobe", "--set", "sigma=1.0", "--transient", "300", "--samples", "10",
                                "--out", str(tmp_path / "s.nc"), "--no-progress"], capsys)
    assert code == 0, err
    assert "P1, 1 impact" in out
    with xr.open_dataset(tmp_path / "s.nc") as ds:
        assert int(ds["period"]) == 1 and ds.attrs["classification"] == "P1, 1 impact"
        assert ds.attrs["model.sigma"] == 1.0
    assert (tmp_path / "s.png").read_bytes()[:8] == PNG_MAGIC

    code, out, err = _run_main(["simulate", "--t-end", "3", "--dt", "0.05", "--out", str(tmp_path / "t.nc"),
                                "--no-progress"], capsys)
    assert code == 0, err
    with xr.open_dataset(tmp_path / "t.nc") as ds:
        assert ds.sizes["t"] == 61 and ds["t"].values[-1] == pytest.approx(3.0)

    code, out, err = _run_main(["jacobian", "--set", "sigma=0", "--x-start", "1e-4", "--x-stop", "1e-2", "--x-num", "3",
                                "--out", str(tmp_path / "j.nc"), "--no-progress"], capsys)
    assert code == 0, err
    assert "exponent q of |J11 - P11| ~ x^q" in out and "+-" in out
    with xr.open_dataset(tmp_path / "j.nc") as ds:
        assert ds["J"].shape == (3, 2, 2)
    assert (tmp_path / "j.png").read_bytes()[:8] == PNG_MAGIC


def test_stale_default_checkpoint_is_discarded_explicit_one_refused(tmp_path: Path, capsys) -> None:
    out = tmp_path / "s.nc"
    stale = tmp_path / "s.nc.partial"
    stale.mkdir()
    (stale / "manifest.json").write_text('{"fingerprint": "another sweep"}')
    argv = ["sweep", "--values", "0.5", "--mode", "fresh", "--transient", "5", "--samples", "3", "--backend", "serial",
            "--out", str(out), "--no-plot", "--no-progress"]
    code, _, err = _run_main(argv, capsys)
    assert code == 0 and "discarding" in err and out.exists() and not stale.exists()

    explicit = tmp_path / "mine"
    explicit.mkdir()
    (explicit / "manifest.json").write_text('{"fingerprint": "another sweep"}')
    code, _, err = _run_main([*argv, "--checkpoint", str(explicit)], capsys)
    assert code == 2 and "argument --checkpoint" in err and "different run" in err


@pytest.mark.slow  # the default sweep, in full
def test_default_sweep_shows_the_period_adding_windows(tmp_path: Path, capsys) -> None:
    """The default `impact-harness sweep` (Figure 9, up and down), on a coarser grid: in both
    directions the maximal orbits come as period 1, 2, 3 with decreasing sigma."""
    from harness.dynamics.maps.classify import windows

    out = tmp_path / "default.nc"
    code, stdout, err = _run_main(["sweep", "--num", "19", "--workers", "2", "--out", str(out), "--no-progress"], capsys)
    assert code == 0, err
    assert out.with_suffix(".png").read_bytes()[:8] == PNG_MAGIC
    with xr.open_dataset(out) as ds:
        assert list(ds["direction"].values) == ["up", "down"]
        assert ds.attrs["model.Gamma"] == 10.0 and ds.attrs["model.wall"] == 1  # the FMU's defaults
        for direction in ("up", "down"):
            sel = ds.sel(direction=direction)
            found = windows(ds["sigma"].values, sel["period"].values, sel["orbit_impacts"].values)
            by_decreasing_sigma = [m for m, lo, hi in sorted(found, key=lambda w: -w[2]) if m <= 3]
            assert by_decreasing_sigma == [1, 2, 3], (direction, found)


def test_fmu_refusal_inside_a_worker_process_is_still_bad_input(tmp_path: Path, capsys) -> None:
    """Sweeping the contact law into one the closed-form solver does not have: the FMU refuses
    one point in a pool worker; the error crosses the process boundary intact and exits with
    status 2.  (A start inside a rigid wall is an invalid point of the scan, not a refusal of
    the run: tests/harness/test_basins.py.)"""
    code, _, err = _run_main(["sweep", "--param", "contact", "--values", "0,1", "--mode", "fresh", "--solver",
                              "closed-form", "--transient", "2", "--samples", "2", "--workers", "1",
                              "--out", str(tmp_path / "x.nc"), "--no-progress"], capsys)
    assert code == 2, err
    assert err.strip().count("\n") == 0 and "Hertz" in err and "Traceback" not in err


def test_input_errors_survive_pickling() -> None:
    import pickle

    from harness import HarnessInputError

    e = pickle.loads(pickle.dumps(HarnessInputError("--theta", "must lie in [0, 1)")))
    assert (e.argument, e.reason, str(e)) == ("--theta", "must lie in [0, 1)", "argument --theta: must lie in [0, 1)")
