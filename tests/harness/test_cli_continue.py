"""``impact-harness continue``: the files it writes, its report, and its refusals (one line, exit 2)."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from harness.io.results import read_netcdf
from harness.config import DEFAULT_SOLVER
from harness.config import SOLVERS
from tests.support.cli import run_main

FIG9 = ["--nu", "4.605170185988091", "--Omega", "0.3059238689620112", "--r", "0.9", "--wall", "compliant",
        "--Gamma", "10"]


def test_continue_writes_branch_plot_report(tmp_path: Path, capsys) -> None:
    out = tmp_path / "c.nc"
    # 80 points: the period-2 branch switched onto at the flip climbs to its nonsmooth fold at 0.819
    # (the stable window's graze) in steps that shrink towards the corner, then runs down
    code, stdout, err = run_main(["continue", *FIG9, "--range", "0.7:1.1", "--start", "1.0", "--switch",
                                  "--max-points", "80", "--out", str(out), "--no-progress"], capsys)
    assert code == 0, err
    ds = read_netcdf(out)
    events = json.loads(ds.attrs["continuation.events"])
    flips = [e for e in events if e["kind"] == "flip"]
    # the period-1 flip, located on the down branch (Figure 9's M = 1 lower edge)
    assert flips and abs(flips[0]["value"] - 0.8120764) < 1e-6
    assert set(json.loads(ds.attrs["continuation.branches"])) >= {"down", "up"}
    assert ds.attrs["model.solver"] == SOLVERS[DEFAULT_SOLVER]  # the one default of every command
    assert "fmu.sha256" in ds.attrs or any("sha256" in k for k in ds.attrs)
    assert (tmp_path / "c.png").stat().st_size > 0
    report = (tmp_path / "c.md").read_text()
    assert "| flip | 0.81207" in report and "Stable parts" in report
    assert "| flip |" in stdout


@pytest.mark.parametrize("argv,needle", [
    (["--range", "1:0.5", "--start", "0.7"], "--range"),
    (["--range", "0.5:1", "--start", "2"], "--start"),
    (["--range", "0.5:1", "--start", "0.7", "--param", "nonsense"], "--param"),
    (["--range", "0.5:1", "--start", "0.7", "--state", "1,x", "-M", "1"], "--state"),
    (["--range", "0.5:1", "--start", "0.7", "--state", "-3.4,0.01"], "-M"),
    (["--range", "-0.5:-1", "--start", "-0.7"], "--range"),
])
def test_continue_refuses_bad_input(tmp_path: Path, capsys, argv: list[str], needle: str) -> None:
    code, out, err = run_main(["continue", *FIG9, *argv, "--out", str(tmp_path / "x.nc"), "--no-progress"], capsys)
    assert code == 2
    assert needle in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "x.nc").exists()


def test_a_branch_stopped_by_its_point_budget_says_so_and_exits_3(tmp_path: Path, capsys) -> None:
    """Three points cannot cover [0.7, 1.1] from 1.0: the summary line of each branch names the
    point budget as the reason it ended short of the range, and the exit status is 3 (not 0)."""
    out = tmp_path / "c.nc"
    code, stdout, err = run_main(["continue", *FIG9, "--solver", "closed-form", "--range", "0.7:1.1", "--start",
                                  "1.0", "--max-points", "3", "--out", str(out), "--no-progress", "--no-plot"], capsys)
    assert code == 3, err
    heads = [line for line in stdout.splitlines() if line.startswith("## Branch")]
    assert heads and all("3 steps done" in h and "short of the range" in h for h in heads)
    assert "raise --max-points" in stdout
