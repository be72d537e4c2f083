"""One set of defaults: the section phase, the solver and the oscillator's flags are the same in
every command that has them, defined once (harness/config/defaults.py) and stated once in each
command's --help."""
from __future__ import annotations

import argparse

import pytest

from harness.cli.main import build_parser
from harness.config import DEFAULT_SOLVER, DEFAULTS, MODEL_SHORTCUTS, SECTION_PHASE

RUNS_FMU = ("sweep", "basins", "strobe", "continue", "windows", "chart", "atlas")


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


@pytest.mark.parametrize("command", RUNS_FMU)
def test_every_command_takes_the_model_flags_and_the_solver(command) -> None:
    p = _subparsers()[command]
    flags = {s for a in p._actions for s in a.option_strings}
    assert {f"--{k}" for k in MODEL_SHORTCUTS} | {"--wall", "--solver"} <= flags
    solver = next(a for a in p._actions if "--solver" in a.option_strings)
    assert solver.help.count("default") == 1 and f"{DEFAULT_SOLVER} (default" in solver.help


@pytest.mark.parametrize("command", ("sweep", "basins", "strobe", "continue", "windows", "atlas"))
def test_the_section_phase_is_one_default(command) -> None:
    p = _subparsers()[command]
    theta = next(a for a in p._actions if "--theta" in a.option_strings)
    assert theta.help.count("default") == 1 and f"default {SECTION_PHASE:g}" in theta.help
    # what the command runs with when --theta is not given: the same constant
    value = theta.default if theta.default is not None else DEFAULTS["sampling"]["theta"]
    assert value == SECTION_PHASE


def test_model_flags_reach_the_fmu_parameters(tmp_path) -> None:
    """--nu/--Omega on sweep set the FMU's parameters exactly like --set (the recorded settings)."""
    from harness.cli.experiment_args import experiment_of

    args = build_parser().parse_args(["sweep", "--nu", "0.8", "--Omega", "2.5", "--wall", "rigid",
                                      "--out", str(tmp_path / "s.nc")])
    same = build_parser().parse_args(["sweep", "--set", "nu=0.8", "--set", "Omega=2.5", "--set", "wall=rigid",
                                      "--out", str(tmp_path / "s.nc")])
    a, b = experiment_of(args).params, experiment_of(same).params
    assert (a["nu"], a["Omega"], a["wall"]) == (b["nu"], b["Omega"], b["wall"]) == (0.8, 2.5, 2)
