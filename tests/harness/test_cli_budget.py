"""Memory and work are estimated before anything is allocated: huge grids,
sample counts and time series are refused in one line with the estimate and the way out."""
from __future__ import annotations

import resource
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from harness.runs.budget import Budget, parse_size, simulate_estimate, sweep_estimate
from tests.support.cli import run_main as _run_main

ROOT = Path(__file__).resolve().parents[2]


# Inputs that once allocated without bound, each with the flag the refusal must name and what it says.
HUGE = [
    (["sweep", "--num", "1e9"], "--num", "memory"),
    (["sweep", "--scan", "Gamma=1:10:1000000"], "--scan", "memory"),
    (["strobe", "--samples", "1e9"], "--samples", "memory"),
    (["sweep", "--transient", "1e12"], "--transient", "FMU periods"),
    (["strobe", "--transient", "1e12"], "--transient", "FMU periods"),
    (["simulate", "--dt", "1e-9"], "--dt", "memory"),
    (["jacobian", "--x-num", "1e12"], "--x-num", "memory"),
]


@pytest.mark.parametrize("argv, flag, kind", HUGE, ids=[" ".join(a) for a, _, _ in HUGE])
def test_huge_runs_are_refused_before_they_start(tmp_path: Path, capsys, argv, flag, kind) -> None:
    code, out, err = _run_main([*argv, "--out", str(tmp_path / "x.nc"), "--no-progress"], capsys)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
    assert f"argument {flag}:" in lines[0] and kind in lines[0], lines[0]
    assert ("--max-memory" in lines[0]) if kind == "memory" else ("--max-work" in lines[0] and "--force" in lines[0])
    assert out == "" and not list(tmp_path.iterdir())


def test_refusal_allocates_nothing_in_a_real_process(tmp_path: Path) -> None:
    """`sweep --num 1e9` grew to 6 GB before it said anything; now the process stays small.  The
    peak is the command's own (read by the process itself as it exits from /proc/self/status),
    not that of earlier children of this test worker."""
    # VmHWM: the peak of this process's own memory (ru_maxrss would keep the forking worker's
    # peak across exec)
    own_peak = ("import runpy, sys\ntry:\n    runpy.run_module('harness', run_name='__main__')\nfinally:\n"
                "    hwm = [l.split()[1] for l in open('/proc/self/status') if l.startswith('VmHWM')][0]\n"
                "    print('MAXRSS', hwm, file=sys.stderr)")
    res = subprocess.run([sys.executable, "-c", own_peak, "sweep", "--num", "1e9", "--out", str(tmp_path / "x.nc")],
                         capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert res.returncode == 2 and "TiB of memory" in res.stderr, res.stderr
    peak_kib = int(res.stderr.rsplit("MAXRSS", 1)[1].split()[0])
    assert 0 < peak_kib < 400 * 1024  # KiB: the interpreter and its imports, no grid


def test_limits_can_be_lowered_and_work_forced(tmp_path: Path, capsys) -> None:
    argv = ["strobe", "--transient", "40", "--samples", "4", "--out", str(tmp_path / "s.nc"), "--no-plot", "--no-progress"]
    code, _, err = _run_main([*argv, "--max-work", "10"], capsys)
    assert code == 2 and "44 FMU periods" in err and "limit 10" in err
    code, out, err = _run_main([*argv, "--max-work", "10", "--force"], capsys)
    assert code == 0 and "wrote" in out, err
    code, _, err = _run_main([*argv, "--max-memory", "100"], capsys)
    assert code == 2 and "limit 100 B" in err
    # memory that is not there cannot be forced
    code, _, err = _run_main([*argv, "--max-memory", "100", "--force"], capsys)
    assert code == 2 and "of memory" in err


def test_sweep_estimate_bounds_the_real_result(tmp_path: Path, capsys) -> None:
    """The memory estimate is an upper bound of the arrays the sweep really stores, and not a
    wild one (within the factor of copies it assumes)."""
    out = tmp_path / "s.nc"
    code, _, err = _run_main(["sweep", "--values", "0.5,0.7,0.9", "--mode", "both", "--scan", "Gamma=10,20",
                              "--transient", "5", "--samples", "6", "--backend", "serial", "--out", str(out),
                              "--no-plot", "--no-progress"], capsys)
    assert code == 0, err
    with xr.open_dataset(out) as ds:
        stored = sum(ds[v].nbytes for v in ("u", "v", "t", "impacts"))
        est = sweep_estimate(3, 2, 2, 5, 6, 0)
        assert stored <= est.memory <= 4 * stored
        assert est.work == 3 * 2 * 2 * (5 + 6)


def test_simulate_estimate_counts_the_points() -> None:
    est = simulate_estimate(0.0, 3.0, 0.05)
    assert est.work == pytest.approx(61 + 3.0)
    assert Budget(max_memory=1 << 30).check(est) is est
    assert simulate_estimate(0.0, 10.0, 1e-9).memory > 1e11


@pytest.mark.parametrize("text, expected", [("512M", 512 << 20), ("8G", 8 << 30), ("1.5GiB", int(1.5 * (1 << 30))),
                                            ("100000", 100000), ("2k", 2048)])
def test_parse_size(text: str, expected: int) -> None:
    assert parse_size(text) == expected


@pytest.mark.parametrize("text", ["", "G", "-1G", "1X", "nan", "inf"])
def test_parse_size_rejects(text: str) -> None:
    with pytest.raises(ValueError):
        parse_size(text)


def test_counts_written_like_floats_are_accepted(tmp_path: Path, capsys) -> None:
    code, out, err = _run_main(["strobe", "--transient", "1e1", "--samples", "4e0", "--out", str(tmp_path / "s.nc"),
                                "--no-plot", "--no-progress"], capsys)
    assert code == 0, err
    with xr.open_dataset(tmp_path / "s.nc") as ds:
        assert ds.sizes["sample"] == 4 and np.isfinite(ds["u"].values).all()
    code, _, err = _run_main(["strobe", "--samples", "2.5"], capsys)
    assert code == 2 and "invalid int value" in err
