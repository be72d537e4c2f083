"""One way in: every command builds its run from the same layers (defaults < --config file <
flags and --set) into one run object (harness.runs.experiment.Experiment), which opens the FMU and
checks the solver once; the library's entry points check their arguments themselves (a Python
caller gets the command's checks, naming its own arguments); the wall and solver codes are
tables of harness/config read by name; TOML is read in one place; the command line is recorded
one way."""
from __future__ import annotations

import argparse
import ast
import re
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from harness.cli.main import COMMANDS, build_parser, main
from harness.config import DEFAULT_SOLVER, SECTION_PHASE, SOLVERS, WALLS
from harness.errors import HarnessInputError
from harness.runs.experiment import Experiment

ROOT = Path(__file__).resolve().parents[2]
FIG9 = str(ROOT / "harness" / "experiments" / "fig9.toml")

#: The least each command needs to parse (nothing here runs: the run object is all we look at).
MINIMAL = {
    "simulate": [], "strobe": [], "sweep": [], "jacobian": [], "continue": ["-M", "1", "--range", "0.2:0.5", "--start", "0.3"],
    "basins": ["--u0-grid=-1:1:2", "--v0-grid=-1:1:2"],
    "reproduce": ["fig9"], "windows": ["--nu", "4.6", "--Omega", "0.3"],
    "chart": ["--nu", "4.6", "--Omega", "0.3", "--r", "0.9", "--param2", "Gamma", "--range", "10:20"],
    "atlas": ["--nu", "4.6", "--Omega", "0.3", "--r", "0.9", "--param2", "Gamma", "--range", "10:20"],
}


class Built(Exception):
    """Raised with the run object a command built, before it runs anything."""


def _built_run(monkeypatch, argv: list[str], tmp_path: Path) -> Experiment:
    """The run object command ``argv`` builds, through its own code (the real builder, stopped
    right after it returns)."""
    real = Experiment.from_sources.__func__

    def stop_after(cls, *args, **kwargs):
        raise Built(real(cls, *args, **kwargs))

    monkeypatch.setattr(Experiment, "from_sources", classmethod(stop_after))
    monkeypatch.chdir(tmp_path)  # outputs a command checks before building land here
    parser = build_parser()
    args = parser.parse_args(argv)
    args.command_line = "impact-harness " + " ".join(argv)
    with pytest.raises(Built) as built:
        args.func(args)
    return built.value.args[0]


def test_every_command_is_listed() -> None:
    names = {c.__name__.rsplit(".", 1)[-1].rstrip("_") for c in COMMANDS}
    assert names == set(MINIMAL)


@pytest.mark.parametrize("command", sorted(MINIMAL))
def test_every_command_runs_with_the_one_default_solver(command, monkeypatch, tmp_path) -> None:
    """Without --solver, each command's run object (built by the command itself) has the solver
    of harness/config/defaults.py: a command that set its own default would fail here."""
    run = _built_run(monkeypatch, [command, *MINIMAL[command]], tmp_path)
    assert run.solver == DEFAULT_SOLVER and run.params["solver"] == SOLVERS[DEFAULT_SOLVER]
    assert not run.given("model", "solver")
    if command == "chart":  # and the chart's parameters, taken from the run object
        from harness.analysis.chart.problem import chart_params

        assert chart_params(run)["solver"] == SOLVERS[DEFAULT_SOLVER]


@pytest.mark.parametrize("command", sorted(MINIMAL))
def test_every_command_takes_the_layers(command, monkeypatch, tmp_path) -> None:
    """--config, --set and --solver reach every command's run object, flags over the file."""
    argv = [command, *MINIMAL[command], "--config", FIG9, "--set", "u_wall=0.25", "--solver", "closed-form"]
    run = _built_run(monkeypatch, argv, tmp_path)
    assert run.params["u_wall"] == 0.25 and run.solver == "closed-form"
    assert run.layers.origin[("model", "Gamma")] == "fig9.toml" and run.params["wall"] == WALLS["compliant"]


@pytest.mark.parametrize("command", ["windows", "chart"])
def test_help_lists_config_and_set(command) -> None:
    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)).choices[command]
    text = sub.format_help()
    assert "--config FILE.toml" in text and "--set NAME=VALUE" in text and "--theta" in text
    theta = next(a for a in sub._actions if "--theta" in a.option_strings)
    assert theta.default == SECTION_PHASE


def test_one_wall_table_and_one_solver_table() -> None:
    """The codes of the FMU's ``wall`` and ``solver`` parameters are written once, in
    harness/config/defaults.py; everything else reads them by name."""
    wall_tables, solver_tables = [], []
    for path in sorted((ROOT / "harness").rglob("*.py")):
        text = path.read_text()
        rel = path.relative_to(ROOT).as_posix()
        wall_tables += [rel for _ in re.finditer(r"[\"']compliant[\"']\s*:\s*\(?\s*1\b", text)]
        solver_tables += [rel for _ in re.finditer(r"[\"']closed-form[\"']\s*:\s*1\b", text)]
        # a wall or solver tested against a bare code (== 2, != 1) instead of its name
        assert not re.search(r"get\(\"(wall|solver)\"[^)]*\)\)\s*[!=]=\s*\d", text), rel
        assert not re.search(r"[\"'](wall|solver)[\"']\s*:\s*\d|\b(wall|solver)=\d", text), rel
    assert wall_tables == solver_tables == ["harness/config/defaults.py"]


def test_toml_is_read_in_one_place_with_the_fallback_of_python_3_10() -> None:
    """Only harness/config/layers.py imports a TOML reader, as ``tomllib`` from Python 3.11 and
    ``tomli`` before (pyproject.toml supports 3.10 and requires tomli there)."""
    readers = []
    for path in sorted((ROOT / "harness").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            if any(n.split(".")[0] in ("tomllib", "tomli") for n in names):
                readers.append(path.relative_to(ROOT).as_posix())
    assert sorted(set(readers)) == ["harness/config/layers.py"]
    guard = _toml_import_block()
    assert "sys.version_info >= (3, 11)" in guard and "import tomli as tomllib" in guard
    assert re.search(r"tomli[^\"]*python_version\s*<\s*'3\.11'", (ROOT / "pyproject.toml").read_text())


def _toml_import_block() -> str:
    """The source of the version-guarded import in harness/config/layers.py."""
    source = (ROOT / "harness" / "config" / "layers.py").read_text()
    node = next(n for n in ast.parse(source).body if isinstance(n, ast.If) and "tomllib" in ast.unparse(n))
    return ast.unparse(node)


def _oldest_python() -> str | None:
    """An interpreter of the oldest Python pyproject.toml supports, if one is installed."""
    import shutil

    oldest = re.search(r'requires-python\s*=\s*">=(\d+\.\d+)"', (ROOT / "pyproject.toml").read_text()).group(1)
    candidates = [str(p) for p in sorted(Path.home().glob(f".pyenv/versions/{oldest}.*/bin/python{oldest}"))]
    candidates += [p for p in [shutil.which(f"python{oldest}")] if p]
    for python in candidates:  # the first that runs (a pyenv shim may name a version it does not select)
        ok = subprocess.run([python, "-c", "import sys; print(sys.version_info[:2])"], capture_output=True, text=True,
                            timeout=60)
        if ok.returncode == 0 and ok.stdout.strip() == str(tuple(int(x) for x in oldest.split("."))):
            return python
    return None


def test_the_toml_import_takes_the_fallback_on_the_oldest_python() -> None:
    """Run under the oldest supported Python (where one is installed), the guarded import asks
    for ``tomli`` (not for ``tomllib``, which 3.10 lacks): ``chart --config`` reads its file
    through it, like every command."""
    python = _oldest_python()
    if python is None:
        pytest.skip("no interpreter of the oldest supported Python here (the import path is checked above)")
    code = "import sys\n" + _toml_import_block() + "\nprint(tomllib.__name__)"
    res = subprocess.run([python, "-c", code], capture_output=True, text=True, timeout=60)
    lacks_tomllib = subprocess.run([python, "-c", "import tomllib"], capture_output=True, timeout=60).returncode != 0
    if lacks_tomllib:  # the fallback: tomli, which pyproject.toml installs there
        assert res.stdout.strip() == "tomli" or "No module named 'tomli'" in res.stderr, res.stderr
        assert "tomllib" not in res.stderr
    else:
        assert res.stdout.strip() == "tomllib"


def test_chart_reads_its_config_through_the_one_reader(tmp_path, capsys) -> None:
    """chart --config: a missing file, a broken file and an unknown section are the same one-line
    errors as every command's (exit 2, no traceback)."""
    base = ["chart", "--param2", "Gamma", "--range", "10:20", "--out", str(tmp_path / "c")]
    bad = tmp_path / "bad.toml"
    bad.write_text("[model\nnu = 1\n")
    unknown = tmp_path / "unknown.toml"
    unknown.write_text("[modle]\nnu = 1.0\n")
    for cfg, words in ((tmp_path / "none.toml", "no such file"), (bad, "is not valid TOML"),
                       (unknown, "unknown section")):
        assert main([*base, "--config", str(cfg)]) == 2
        err = capsys.readouterr().err
        assert words in err and "Traceback" not in err and len(err.strip().splitlines()) == 1, err


def test_the_library_checks_what_the_command_checks(tmp_path) -> None:
    """The entry points the commands call check their arguments from Python too, naming them."""
    from harness import compare_windows
    from harness.analysis.chart.chart import chart
    from harness.analysis.chart.problem import chart_problem
    from harness.analysis.chart.run import ChartProblem
    from harness.reproduce import run_target

    params = {"nu": 4.6, "Omega": 0.3, "r": 0.9, "wall": WALLS["compliant"], "Gamma": 10.0}
    grid = np.geomspace(0.1, 1.0, 5)
    cases = [
        (lambda: chart(ChartProblem(params, "Gamma", np.array([10.0, 20.0]), False, 13, grid), tmp_path), "M_max"),
        (lambda: chart(ChartProblem({**params, "wall": WALLS["none"]}, "Gamma", np.array([10.0, 20.0]), False, 2,
                                    grid), tmp_path), "wall"),
        (lambda: chart(ChartProblem(params, "Gamma", np.array([10.0]), False, 2, grid), tmp_path), "values"),
        (lambda: chart(ChartProblem(params, "Gamma", np.array([10.0, 20.0]), False, 2, grid), tmp_path,
                       workers=0), "workers"),
        (lambda: chart(ChartProblem(params, "nope", np.array([10.0, 20.0]), False, 2, grid), tmp_path), "param2"),
        (lambda: chart_problem(params, "Gamma", (0.0, 20.0), log=True), "p_range"),
        (lambda: chart_problem(params, "Gamma", (10.0, 20.0), num=1), "num"),
        (lambda: chart_problem(params, "Gamma", (10.0, 20.0), sigma_range=(-1.0, 1.0)), "sigma_range"),
        (lambda: compare_windows(nu=4.6, Omega=0.3, wall="none", out=tmp_path), "wall"),
        (lambda: compare_windows(nu=4.6, Omega=0.3, M_max=13, out=tmp_path), "M_max"),
        (lambda: compare_windows(nu=4.6, Omega=0.3, solver="rk4", out=tmp_path), "solver"),
        (lambda: compare_windows(nu=4.6, Omega=0.3, fmu_path=tmp_path / "none.fmu", out=tmp_path), "fmu_path"),
        (lambda: run_target("fig9", tmp_path, workers=0), "workers"),
    ]
    for call, argument in cases:
        with pytest.raises(HarnessInputError) as exc:
            call()
        assert exc.value.argument == argument, (argument, str(exc.value))
    assert not (tmp_path / "chart.json").exists()


@pytest.mark.parametrize("argv,flag", [
    (["chart", *MINIMAL["chart"], "--M-max", "13"], "--M-max"),
    (["chart", *MINIMAL["chart"], "--wall", "none"], "--wall"),
    (["chart", "--nu", "4.6", "--Omega", "0.3", "--param2", "Gamma", "--range", "10:20"], "--r"),
    (["chart", *MINIMAL["chart"][:-1], "0:20", "--log"], "--range"),
    (["chart", *MINIMAL["chart"], "--sigma-range=-2:1"], "--sigma-range"),
    (["windows", *MINIMAL["windows"], "--wall", "none"], "--wall"),
    (["windows", *MINIMAL["windows"], "--set", "wall=sideways"], "--set wall"),
    (["reproduce", "fig9", "--workers", "0"], "--workers"),
])
def test_the_command_line_names_the_flag(argv, flag, tmp_path, capsys) -> None:
    assert main([*argv, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert f"argument {flag}:" in err and len(err.strip().splitlines()) == 1, err


def test_the_command_line_is_recorded_one_way(tmp_path) -> None:
    """What was typed, with --config written out as the command's flags: parsed again it gives
    the run object the file gave (the file may change later)."""
    from harness.cli.experiment_args import recorded_command
    from harness.cli.flags import command_parser

    parser = build_parser()
    for argv in (["chart", "--config", FIG9, "--set", "u_wall=0.5", "--param2", "Gamma", "--range", "10:20"],
                 ["windows", "--config", FIG9, "--r", "0.8", "--sigma-range=-0.2:1"],
                 ["strobe", "--config", FIG9, "--samples", "12"]):
        args = parser.parse_args(argv)
        line = recorded_command(command_parser(parser, argv[0]), args, argv)
        assert line.startswith(f"impact-harness {argv[0]} ") and "--config" not in line, line
        again = parser.parse_args(shlex.split(line)[1:])
        from harness.cli.experiment_args import experiment_of

        a, b = experiment_of(args), experiment_of(again)
        assert a.params == b.params and (argv[0] != "strobe" or a.sampling == b.sampling), line
    # a setting with no flag of its own keeps the file in the line
    scan = tmp_path / "scan.toml"
    scan.write_text('[sweep]\nscan_param = "Gamma"\nscan_values = [10.0, 100.0]\n[model]\nr = 0.8\n')
    argv = ["sweep", "--config", str(scan)]
    line = recorded_command(command_parser(parser, "sweep"), parser.parse_args(argv), argv)
    assert f"--config {scan}" in line and "--r 0.8" in line
