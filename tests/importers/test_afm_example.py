"""examples/afm/run.py, the one-command AFM example, at its --quick horizon (about 6 s)."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("ecospy", reason="ecospy is a dev extra: pip install -e '.[dev]'")

from examples.afm import run  # noqa: E402


def test_example_runs_in_one_command(tmp_path: Path) -> None:
    """The example writes its plots, numbers and report; every master is within the FMU's
    budget of the monolithic reference (1e-8 in u, 1e-7 in v; the goal is 1e-6); the sweep shows the loop holding the free amplitude above
    grazing and losing it (the amplitude jumps away from 3) once the set-point asks for a
    contact with the stiff sample."""
    assert run.main(["--quick", "--out", str(tmp_path)]) == 0
    for f in ("settle.png", "sweep.png", "afm.json", "report.md"):
        assert (tmp_path / f).stat().st_size > 0, f
    data = json.loads((tmp_path / "afm.json").read_text())
    assert set(data["masters"]) == {"ecos", "fmpy SSP", "fmpy Container FMU"}
    for name, e in data["masters"].items():
        assert max(e["u"], e["u_wall"], e["amplitude"]) <= 1e-8 and e["v"] <= 1e-7, (name, e)
    rows = {round(r["A_set"], 2): np.array(r["amplitude"]) for r in data["sweep"]["rows"]}
    # above grazing (A_set >= free amplitude 3 - a little): no contact, amplitude exactly free
    assert np.all(np.abs(rows[3.0] - 3.0) < 1e-6)
    # below: the loop pushes the surface into the orbit and the amplitude jumps by > 0.1
    assert any(np.max(np.abs(rows[a] - 3.0)) > 0.1 for a in rows if a <= 2.92)
    # the open-loop diagram: the free amplitude above grazing, scattered below it
    curve = data["open_loop"]
    w, A = np.array(curve["u_wall"]), np.array(curve["amplitude"])
    assert np.all(np.abs(A[w > 0.51] - 3.0) < 1e-6)
    assert np.ptp(A[w < 0.45]) > 0.1  # below grazing: no longer the free period-1 orbit


def test_example_options_reach_the_fmus(tmp_path: Path) -> None:
    """Set-point, gains, Gamma, h and the master as options: the chosen master, run with them,
    matches the monolithic reference run with the same values (so they reached both FMUs), and
    the report and JSON say which values ran."""
    argv = ["--quick", "--no-sweep", "--out", str(tmp_path), "--master", "ecos", "--A-set", "2.6", "--Kp", "0.15",
            "--Ki", "0.25", "--Gamma", "20", "--h", "0.02"]
    assert run.main(argv) == 0
    data = json.loads((tmp_path / "afm.json").read_text())
    assert set(data["masters"]) == {"ecos"} and "sweep" not in data
    p = data["parameters"]
    assert (p["controller"]["A_set"], p["controller"]["Kp"], p["controller"]["Ki"]) == (2.6, 0.15, 0.25)
    assert p["oscillator"]["Gamma"] == 20.0 and p["h"] == 0.02
    e = data["masters"]["ecos"]
    assert max(e["u"], e["u_wall"], e["amplitude"]) <= 1e-8 and e["v"] <= 1e-7, e
    assert len(data["updates"]) >= 5  # the controller acted (a window per period)
    assert "h = 0.02, Gamma = 20, A_set = 2.6, Kp = 0.15, Ki = 0.25" in (tmp_path / "report.md").read_text()


@pytest.mark.parametrize("bad", [["--h", "0.03"], ["--A-set", "-1"], ["--Kp", "nan"], ["--master", "simulink"]])
def test_example_refuses_bad_options_in_one_line(bad: list[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        run.parse_args(bad)
    assert exc.value.code == 2
