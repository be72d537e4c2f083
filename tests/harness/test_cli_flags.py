"""The library names Python arguments in its errors; the CLI prints the flag that set each one
(harness/cli/flags.py), so a Python caller and a CLI user each read their own names."""
from __future__ import annotations

import pytest

from harness.cli.flags import flag_for, with_flags
from harness.cli.main import build_parser
from harness.dynamics.continuation.continue_orbit import continue_orbit
from harness.errors import HarnessInputError, SettingsErrors
from harness.runs.backends import make_backend
from harness.runs.checkpoint import CheckpointMismatch


@pytest.fixture(scope="module")
def parser():
    return build_parser()


def test_the_library_names_its_python_arguments() -> None:
    with pytest.raises(HarnessInputError) as bad_m:
        continue_orbit(None, {}, 0, 0.5, (0.0, 0.0))
    with pytest.raises(HarnessInputError) as bad_range:
        continue_orbit(None, {}, 1, 0.5, (0.0, 0.0), p_range=(1.0, 1.0))
    with pytest.raises(HarnessInputError) as bad_backend:
        make_backend("nonsense", None, None)
    assert (bad_m.value.argument, bad_range.value.argument, bad_backend.value.argument) == ("M", "p_range", "backend")
    assert str(bad_m.value) == "argument M: the period must be >= 1, got 0"


@pytest.mark.parametrize("command,name,flag", [
    ("continue", "M", "-M"),              # its first spelling, as argparse lists it (-M/--period)
    ("continue", "p_range", "--range"),   # dest p_range
    ("continue", "p0", "--start"),        # an alias: the dest is start
    ("continue", "z0", "--start"),
    ("sweep", "scheduler", "--scheduler"),  # dest run__scheduler: a section of the experiment file
    ("sweep", "spec.modes", "--mode"),
    ("sweep", "checkpoint", "--checkpoint"),
    ("basins", "match_tol", "--match-tol"),
    ("jacobian", "measure_theta", "--measure-theta"),
    ("jacobian", "theta", "--theta"),     # not --measure-theta: the dest ends in __theta
    ("chart", "M_max", "--M-max"),
    ("continue", "nonsense", None),       # no option sets it: the name stays
    ("continue", "--start", None),        # already a flag
    ("no-such-command", "M", None),
])
def test_flag_for(parser, command: str, name: str, flag: str | None) -> None:
    assert flag_for(parser, command, name) == flag


def test_with_flags_keeps_the_error_type_and_its_fields(parser) -> None:
    one = with_flags(HarnessInputError("p_range", "needs two different finite values"), parser, "continue")
    assert str(one) == "argument --range: needs two different finite values"
    many = with_flags(SettingsErrors([HarnessInputError("M", "bad"), HarnessInputError("sampling.theta", "bad")]),
                      parser, "continue")
    assert isinstance(many, SettingsErrors) and [e.argument for e in many.errors] == ["-M", "sampling.theta"]
    mismatch = with_flags(CheckpointMismatch("checkpoint", "a different run", ["fmu: changed"]), parser, "sweep")
    assert isinstance(mismatch, CheckpointMismatch) and mismatch.argument == "--checkpoint"
    assert mismatch.changes == ["fmu: changed"]
    untouched = HarnessInputError("nonsense", "why")
    assert with_flags(untouched, parser, "continue") is untouched
