"""Messages that cost a user an hour when missing: a discarded checkpoint
says which settings differ, a config file's mistakes come all in one run, and --u0/--v0 say at
which time the state applies."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from harness import SamplingSpec, SweepSpec, run_sweep
from harness.runs.checkpoint import differences
from tests.support.cli import run_main


def test_discarded_checkpoint_names_what_differs(model, tmp_path: Path, capsys) -> None:
    """A real checkpoint of a sweep at r = 0.9 with 20 transient periods, then the CLI at r = 0.8
    and 30 periods to the same file: the note names both changes, the run starts afresh."""
    out = tmp_path / "s.nc"
    ckpt = tmp_path / "s.nc.partial"
    values = np.array([0.4, 0.5])
    run_sweep(model, SweepSpec("sigma", values, ("fresh",)), sampling=SamplingSpec(n_transient=20, n_samples=4),
              backend="serial", checkpoint=str(ckpt), progress=False)
    assert (ckpt / "manifest.json").exists()
    code, stdout, err = run_main(["sweep", "--values", "0.4,0.5", "--mode", "fresh", "--set", "r=0.8", "--transient",
                                  "30", "--samples", "4", "--backend", "serial", "--out", str(out), "--no-plot",
                                  "--no-progress"], capsys)
    assert code == 0, err
    note = [line for line in err.splitlines() if "discarding" in line]
    assert len(note) == 1, err
    assert "params.r: 0.9 -> 0.8" in note[0] and "sampling.n_transient: 20 -> 30" in note[0], note[0]
    assert "0 resumed" in stdout and out.exists()
    # with --checkpoint the same directory is refused, with the same reasons
    run_sweep(model, SweepSpec("sigma", values, ("fresh",)), sampling=SamplingSpec(n_transient=20, n_samples=4),
              backend="serial", checkpoint=str(tmp_path / "mine"), progress=False)
    code, _, err = run_main(["sweep", "--values", "0.4,0.5", "--mode", "fresh", "--transient", "20", "--samples", "4",
                             "--set", "Gamma=20", "--backend", "serial", "--out", str(out), "--no-plot",
                             "--no-progress", "--checkpoint", str(tmp_path / "mine")], capsys)
    assert code == 2 and "params.Gamma: 10.0 -> 20.0" in err and "--checkpoint" in err


def test_differences_of_identities() -> None:
    a = {"fmu": "aa", "params": {"r": 0.9, "nu": 1.0}, "values": [0.1, 0.2, 0.3, 0.4, 0.5], "modes": ["up"]}
    b = {"fmu": "bb", "params": {"r": 0.9, "nu": 2.0}, "values": [0.1, 0.2, 0.3, 0.4, 0.5, 0.6], "modes": ["up"]}
    assert differences(a, b) == ["fmu: another FMU binary (sha256 differs)", "params.nu: 1.0 -> 2.0",
                                 "values: 5 values 0.1..0.5 -> 6 values 0.1..0.6"]
    assert differences(a, a) == []


def test_config_mistakes_reported_at_once(tmp_path: Path, capsys) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text('[model]\nsigma = "lots"\nnonsense = 3\n[sampling]\ntheta = 1.5\nsamples = 1\n'
                   '[run]\nbackend = "threads"\n[sweep]\nmode = "sideways"\n[plotting]\nx = 1\n')
    code, _, err = run_main(["sweep", "-c", str(bad), "--transient", "-3", "--no-progress"], capsys)
    assert code == 2 and "Traceback" not in err
    assert "8 problems in the settings" in err
    for part in ("[plotting]: unknown section", "model.sigma", "model.nonsense", "sampling.theta",
                 "sampling.samples", "run.backend", "sweep.mode", "--transient"):
        assert part in err, part
    # one mistake: one line, as before
    code, _, err = run_main(["strobe", "--theta", "2", "--no-progress"], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "--theta" in err


def test_initial_state_help_says_the_time(capsys) -> None:
    for command in ("strobe", "sweep", "simulate"):
        code, stdout, _ = run_main([command, "--help"], capsys)
        text = " ".join(stdout.split())
        assert code == 0
        assert "initial displacement u at the start time t = theta" in text
        assert "initial velocity v at the start time t = theta" in text
