"""``chart`` over random oscillators and second parameters ends with its three files, never a traceback.

Each case draws (from a fixed seed, so that a failure can be rerun) a damping nu, a frequency Omega,
a restitution r, a wall (compliant with a stiffness Gamma, or rigid), a second parameter among those
the wall has and a sigma range above or reaching below grazing, and runs ``chart`` in quick mode on
a small grid.  Whatever the chart finds there, it must end with exit status 0, chart.json, chart.png
and report.md written, and every window's account in the report (a failed window is a line, not the
end of the run).
"""
from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pytest

from harness.cli.main import main

pytestmark = pytest.mark.slow


def _case(seed: int) -> list[str]:
    rng = np.random.default_rng(seed)
    nu, Om, r = rng.uniform(0.3, 5.0), rng.uniform(0.3, 1.5), rng.uniform(0.6, 0.95)
    wall = "compliant" if rng.random() < 0.6 else "rigid"
    names = ["Gamma", "nu", "Omega", "r"] if wall == "compliant" else ["nu", "Omega", "r"]
    p2 = names[int(rng.integers(len(names)))]
    base = {"Gamma": rng.uniform(5.0, 200.0), "nu": nu, "Omega": Om, "r": r}[p2]
    hi = min(base * 1.5, 0.97) if p2 == "r" else base * 1.5
    sig = "-0.2:0.6" if rng.random() < 0.5 else "0.05:2"
    args = ["chart", "--nu", f"{nu:.4g}", "--Omega", f"{Om:.4g}", "--r", f"{r:.4g}", "--wall", wall,
            "--param2", p2, f"--range={base:.4g}:{hi:.4g}", "--num", "2", "--M-max", "1", "--quick",
            "--per-decade", "4", f"--sigma-range={sig}", "--solver", "closed-form", "--workers", "1"]
    if wall == "compliant":
        args += ["--Gamma", f"{(base if p2 == 'Gamma' else 30.0):.4g}"]
    return args


@pytest.mark.parametrize("seed", [3])
def test_chart_over_a_random_oscillator_ends_with_its_report(tmp_path, seed: int) -> None:
    args = _case(seed)
    out = tmp_path / "chart"
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = main([*args, "--out", str(out)])
    assert rc == 0, (args, buf.getvalue())
    res = json.loads((out / "chart.json").read_text())
    report = (out / "report.md").read_text()
    assert (out / "chart.png").stat().st_size > 0
    assert "Traceback" not in report and "## Brute-force check" in report
    for M in res["closes"]:  # every window has its row in the closing table
        assert f"| {M} |" in report or f"| {M}, no impact" in report or M == "1/0", (M, args)
