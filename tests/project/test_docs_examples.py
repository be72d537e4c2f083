"""The examples a user copies are run: the READMEs' Python blocks and examples/*.py as scripts
(in a fresh process, as a user would save and run them: worker processes re-import the
script, which fails without the ``if __name__ == "__main__":`` guard), and the docstring
examples of the API reference as doctests."""
from __future__ import annotations

import doctest
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow  # runs the README's and the examples' commands

ROOT = Path(__file__).resolve().parents[2]
BLOCK = re.compile(r"```python\n(.*?)```", re.S)


def _readme_blocks() -> list[tuple[str, str]]:
    out = []
    for readme in ("README.md", "harness/README.md"):
        for k, code in enumerate(BLOCK.findall((ROOT / readme).read_text())):
            out.append((f"{readme}#{k}", code))
    return out


def _run_script(path: Path, cwd: Path, *args: str) -> subprocess.CompletedProcess:
    # cwd: a scratch directory with build/ linked in, so that the examples' relative paths
    # (build/fmu/..., results/...) resolve and their outputs stay out of the checkout
    (cwd / "build").symlink_to(ROOT / "build")
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run([sys.executable, str(path), *args], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=600)


def test_every_readme_python_example_has_the_main_guard() -> None:
    """Scripts that start worker processes must guard their top level."""
    blocks = _readme_blocks()
    assert blocks
    for name, code in blocks:
        if re.search(r"run_sweep|compare_windows|workers=", code):
            assert 'if __name__ == "__main__":' in code, name


@pytest.mark.parametrize("name,code", _readme_blocks(), ids=[n for n, _ in _readme_blocks()])
def test_readme_python_examples_run(name: str, code: str, tmp_path: Path) -> None:
    script = tmp_path / "example.py"
    script.write_text(code)
    res = _run_script(script, tmp_path)
    assert res.returncode == 0, res.stderr[-3000:]
    assert "BrokenProcessPool" not in res.stderr
    if "strobe(" in code:
        assert "P2, 1 impact" in res.stdout
    if "compare_windows" in code:
        assert (tmp_path / "results" / "windows-example" / "windows.json").is_file()


def test_examples_sweep_runs(tmp_path: Path) -> None:
    res = _run_script(ROOT / "examples" / "sweep.py", tmp_path)
    assert res.returncode == 0, res.stderr[-3000:]
    assert res.stdout.splitlines()[0] == "P2, 1 impact"


def test_examples_windows_runs(tmp_path: Path) -> None:
    """The windows example: ODE edges for M = 1, 2 at (alpha, gamma) = (0.5, 0.05), r = 0.8."""
    res = _run_script(ROOT / "examples" / "windows.py", tmp_path, str(tmp_path / "w"))
    assert res.returncode == 0, res.stderr[-3000:]
    assert (tmp_path / "w" / "report.md").is_file()
    assert "M = 2: ODE (" in res.stdout and "flip/graze" in res.stdout


@pytest.mark.parametrize("module", ["harness", "mapcheck.windows", "mapcheck.coeffs"])
def test_docstring_examples(module: str, monkeypatch) -> None:
    """The examples in the API reference's docstrings (doctest), run from the repository root."""
    import importlib

    monkeypatch.chdir(ROOT)
    mod = importlib.import_module(module)
    res = doctest.testmod(mod, optionflags=doctest.NORMALIZE_WHITESPACE | doctest.ELLIPSIS)
    assert res.attempted > 0, f"{module} has no examples"
    assert res.failed == 0


SHELL_BLOCK = re.compile(r"```bash\n(.*?)```", re.S)


def _readme_cli_commands() -> list[str]:
    out = []
    for readme in ("README.md", "harness/README.md"):
        for code in SHELL_BLOCK.findall((ROOT / readme).read_text()):
            for line in code.splitlines():
                line = line.split("#", 1)[0].strip()
                if line.startswith(("impact-harness ", "python -m harness ")):
                    out.append(line)
    return out


def test_readme_cli_commands_parse() -> None:
    """Every harness command line shown in the READMEs is accepted by the current CLI parser
    (flags and choices; running them all would take hours)."""
    import shlex

    from harness.cli.main import _join_list_values, build_parser

    commands = _readme_cli_commands()
    assert len(commands) >= 10
    parser = build_parser()
    for line in commands:
        argv = shlex.split(line)
        argv = argv[1:] if argv[0] == "impact-harness" else argv[3:]
        try:
            parser.parse_args(_join_list_values(argv))
        except SystemExit as exc:
            raise AssertionError(f"README command no longer parses: {line}") from exc
