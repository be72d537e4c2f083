"""Experiment settings: defaults < TOML file < CLI flags, and validation with clear errors."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from harness import Experiment, FmuModel, HarnessInputError, SamplingSpec
from harness.config import Layered, parameter_values, parse_modes

FMU = Path(__file__).resolve().parents[2] / "build" / "fmu" / "ImpactOscillator.fmu"


def _toml(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "exp.toml"
    path.write_text(text)
    return path


def test_precedence_defaults_file_flags(tmp_path: Path, model: FmuModel) -> None:
    cfg = _toml(tmp_path, """
[model]
Gamma = 100.0
sigma = 0.3
wall = "rigid"
[initial]
u0 = -0.5
[sampling]
theta = 0.25
samples = 12
[sweep]
values = [0.1, 0.2]
mode = "fresh"
[run]
workers = 3
""")
    exp = Experiment.from_sources(cfg, {"model": {"sigma": "0.7"}, "sampling": {"samples": 20}}, model=model)
    assert exp.params["Gamma"] == 100.0          # file
    assert exp.params["sigma"] == 0.7            # flag beats file
    assert exp.params["wall"] == 2               # symbolic value converted to the FMU's Integer
    assert exp.params["nu"] == model.defaults()["nu"]  # FMU default
    assert exp.state0 == (-0.5, model.defaults()["v0"])
    assert (exp.sampling.theta, exp.sampling.n_samples) == (0.25, 20)
    assert exp.sampling.n_transient == SamplingSpec().n_transient  # built-in default
    assert exp.run.workers == 3 and exp.run.backend == "processes"
    spec = exp.sweep_spec()
    assert spec.modes == ("fresh",) and spec.values.tolist() == [0.1, 0.2]
    attrs = exp.as_attrs()
    assert attrs["model.sigma"] == 0.7 and attrs["sampling.theta"] == 0.25


@pytest.mark.parametrize(
    "text, argument, reason",
    [
        ("[sampling]\ntheta = 1.0\n", "exp.toml: sampling.theta", r"\[0, 1\)"),
        ("[sampling]\ntransient = -5\n", "exp.toml: sampling.transient", "negative count"),
        ("[sampling]\nthetaa = 0.1\n", "exp.toml: sampling.thetaa", "unknown key"),
        ("[sampler]\ntheta = 0.1\n", "exp.toml: [sampler]", "unknown section"),
        ("[model]\nsigmaa = 0.1\n", "exp.toml: model.sigmaa", "unknown FMU variable 'sigmaa'"),
        ("[model]\nkappa = 3.0\n", "exp.toml: model.kappa", "calculatedParameter"),
        ("[sweep]\nnum = 0\n", "exp.toml: sweep.num", "empty range"),
        ("[sweep]\nvalues = []\n", "exp.toml: sweep.values", "empty range"),
        ("[sweep]\nparam = 'nope'\n", "exp.toml: sweep.param", "unknown FMU variable"),
        ("[run]\nbackend = 'gpu'\n", "exp.toml: run.backend", "unknown backend"),
        ("[run]\nscheduler = 'localhost:8786'\n", "exp.toml: run.scheduler", "tcp://HOST:PORT"),
        ("[sampling\n", "--config", "not valid TOML"),
    ],
)
def test_file_errors_name_the_key(tmp_path: Path, model: FmuModel, text: str, argument: str, reason: str) -> None:
    cfg = _toml(tmp_path, text)
    with pytest.raises(HarnessInputError, match=reason) as err:
        Experiment.from_sources(cfg, model=model).sweep_spec()
    assert err.value.argument == argument


def test_flag_errors_name_the_flag(model: FmuModel) -> None:
    with pytest.raises(HarnessInputError) as err:
        Experiment.from_sources(None, {"sampling": {"theta": -0.1}}, model=model)
    assert err.value.argument == "--theta"
    with pytest.raises(HarnessInputError) as err:
        Experiment.from_sources(None, {"model": {"foo": "1"}}, model=model)
    assert err.value.argument == "--set foo"


def test_parameter_values() -> None:
    args = ("--start", "--stop", "--num", "--values")
    np.testing.assert_allclose(parameter_values(0.8, 0.1, 8, None, args), np.linspace(0.8, 0.1, 8))
    assert parameter_values(None, None, None, "0.3, 0.1 0.2", args).tolist() == [0.3, 0.1, 0.2]
    assert parameter_values(0.5, 0.5, 1, None, args).tolist() == [0.5]
    for bad, match in [((0.1, 0.1, 3, None), "start = stop"), ((0, 1, -2, None), "negative"),
                       ((None, None, None, [0.1, 0.1]), "distinct"), ((None, None, None, "a,b"), "list of numbers")]:
        with pytest.raises(HarnessInputError, match=match):
            parameter_values(*bad, args)


def test_parse_modes() -> None:
    assert parse_modes("both", "--mode") == ("both",)  # the hysteresis loop, one task
    assert parse_modes("fresh,both", "--mode") == ("fresh", "both")
    assert parse_modes("up,down", "--mode") == ("up", "down")  # two independent scans
    with pytest.raises(HarnessInputError, match="up-then-down loop already"):
        parse_modes("both,down", "--mode")
    assert parse_modes(["down", "down"], "--mode") == ("down",)
    with pytest.raises(HarnessInputError, match="unknown sweep mode 'sideways'"):
        parse_modes("sideways", "--mode")


def test_layers_keep_lower_values_for_missing_flags() -> None:
    layers = Layered()
    layers.merge({"sampling": {"theta": 0.5}}, "a.toml")
    layers.merge({"sampling": {"theta": None, "samples": 7}}, "cli")
    assert layers.get("sampling", "theta") == 0.5 and layers.arg("sampling", "theta") == "a.toml: sampling.theta"
    assert layers.arg("sampling", "samples") == "--samples"


@pytest.mark.parametrize("name", ["fig9.toml", "fig7-hysteresis.toml"])
def test_shipped_experiment_files_are_valid(model: FmuModel, name: str) -> None:
    path = Path(__file__).resolve().parents[2] / "harness" / "experiments" / name
    exp = Experiment.from_sources(path, model=model)
    spec = exp.sweep_spec()
    assert spec.param == "sigma" and spec.modes == ("both",) and len(spec.values) > 10
    assert exp.run.out and exp.run.plot
