"""A script that calls run_sweep with worker processes outside ``if __name__ == "__main__":`` gets one
error that names the line and the fix, before any worker starts; the same
script under the guard runs.  Real scripts in a subprocess, the real pool."""
from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from harness.io.main_guard import guarded_lines

ROOT = Path(__file__).resolve().parents[2]
CALL = """ds = run_sweep({fmu!r}, SweepSpec("sigma", np.linspace(0.3, 0.5, 4), ("fresh",)),
               sampling=SamplingSpec(n_transient=200, n_samples=8), workers=2, progress=False)
print("done", int(ds["period"].max()))"""
HEAD = "import numpy as np\nfrom harness import SamplingSpec, SweepSpec, run_sweep\n"


def _run(tmp_path: Path, body: str) -> subprocess.CompletedProcess:
    script = tmp_path / "my_sweep.py"
    script.write_text(HEAD + body)
    return subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=300)


@pytest.mark.slow  # real scripts started with worker pools
@pytest.mark.parametrize("layout", ["top level", "in a function called at top level"])
def test_unguarded_script_gets_one_line(tmp_path: Path, layout: str) -> None:
    call = CALL.format(fmu=str(ROOT / "build" / "fmu" / "ImpactOscillator.fmu"))
    body = call if layout == "top level" else "def main():\n" + textwrap.indent(call, "    ") + "\n\nmain()\n"
    res = _run(tmp_path, body)
    assert res.returncode != 0
    last = res.stderr.strip().splitlines()[-1]
    line = 3 if layout == "top level" else 3 + call.count("\n") + 3
    assert f"called at the top level of my_sweep.py (line {line})" in last, res.stderr
    assert "if __name__ == \"__main__\":" in last and "backend=\"serial\"" in last
    assert "BrokenProcessPool" not in res.stderr and "bootstrapping" not in res.stderr
    assert res.stderr.count("Traceback") == 1 and "done" not in res.stdout  # no worker ran


@pytest.mark.slow  # a real script with a pool of worker processes
def test_guarded_script_runs(tmp_path: Path) -> None:
    call = CALL.format(fmu=str(ROOT / "build" / "fmu" / "ImpactOscillator.fmu"))
    res = _run(tmp_path, 'if __name__ == "__main__":\n' + textwrap.indent(call, "    ") + "\n")
    assert res.returncode == 0, res.stderr
    assert "done 2" in res.stdout  # sigma 0.3 .. 0.5: period 2 (Figure 9)


def test_guarded_lines() -> None:
    src = "import x\ndef f():\n    pass\n\nif '__main__' == __name__:\n    f()\n    g()\nh()\n"
    assert guarded_lines(src) == [(2, 3), (6, 7)]
