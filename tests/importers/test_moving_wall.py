"""README example 3, the receding rigid wall, in masters no one here wrote: the master sets the
wall's position u_wall and its velocity v_wall at each communication point (Co-Simulation: FMI
3.0 and FMI 2.0 in fmpy, FMI 2.0 in ecos and fmusim) or continuously (Model Exchange: fmpy and
fmusim, each with its CVODE), and every run is compared once per forcing period with a reference
of the ramp wall computed outside the FMU (``mapcheck.inputs_reference``: DOP853 at rtol 1e-13,
the impacts located by scipy's event search, the impact law on the velocity relative to the
wall): u and v to 1e-7, impact counts exact.  Without v_wall the wall jumps at each
communication point and the same master's result is off by far more (the reference can tell).
"""
from __future__ import annotations

import subprocess
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu

from mapcheck.inputs_reference import InputsReference, Piece, RefState
from tests.support.fmu import FMU3_PATH, FMU_PATH
from tests.support.importers import at_periods, fmusim

#: README example 3
START = {"nu": 0.8, "Omega": 2.5, "r": 0.8, "wall": 2, "sigma": 1.7}
PERIODS, RATE, H = 30, 0.01, 0.01  # the wall recedes by RATE per period; the master's step
H_ME = 0.1  # Model Exchange: the output interval (the importer's CVODE chooses its own steps)
TOL = 1e-7
ME_RTOL = 1e-13  # the importers' CVODE: 1e-12 leaves 5e-7 in v after 29 located impacts


@pytest.fixture(scope="module")
def reference() -> np.ndarray:
    """(u, v, impacts) at t = 1 .. PERIODS of the ramp wall u_wall = RATE t."""
    ref = InputsReference(nu=START["nu"], Omega=START["Omega"], sigma=START["sigma"],
                          r=START["r"], wall="rigid")
    st, rows = RefState(0.0, -1.0, 0.0), []
    for k in range(PERIODS):
        ref.run(st, Piece(float(k), k + 1.0, w=RATE * k, dw=RATE))
        rows.append((st.u, st.v, st.impacts))
    out = np.array(rows)
    assert out[-1, 2] >= 25  # an impact in almost every period
    assert abs(st.v_impact) > 0.1  # far from the sticking threshold: the counts are exact
    return out


def _inputs(with_velocity: bool) -> np.ndarray:
    t = np.array([0.0, float(PERIODS)])
    if with_velocity:
        return np.array([(ti, RATE * ti, RATE) for ti in t],
                        dtype=[("time", float), ("u_wall", float), ("v_wall", float)])
    return np.array([(ti, RATE * ti) for ti in t], dtype=[("time", float), ("u_wall", float)])


def _per_period(t: np.ndarray, u, v, impacts) -> np.ndarray:
    k = at_periods(np.asarray(t), PERIODS)
    return np.column_stack([np.asarray(u)[k], np.asarray(v)[k], np.asarray(impacts)[k]])


def _fmpy(path: Path, fmi_type: str, with_velocity: bool = True) -> np.ndarray:
    me = fmi_type == "ModelExchange"
    res = simulate_fmu(str(path), stop_time=PERIODS, output_interval=H_ME if me else H,
                       fmi_type=fmi_type,
                       input=_inputs(with_velocity), start_values=START,
                       relative_tolerance=ME_RTOL if me else None,
                       output=["u", "v", "impacts"])
    return _per_period(res["time"], res["u"], res["v"], res["impacts"])


def _ecos() -> np.ndarray:
    ecospy = pytest.importorskip("ecospy", reason="ecospy is a dev extra: pip install -e '.[dev]'")
    ecospy.EcosLib.set_log_level("warn")
    rows = []
    with ecospy.EcosSimulationStructure() as ss:
        ss.add_model("osc", str(FMU_PATH))
        ss.add_parameter_set("init", {f"osc::{k}": x for k, x in START.items()})
        with ecospy.EcosSimulation(structure=ss, step_size=H) as sim:
            sim.init(parameter_set="init")
            for _ in range(round(PERIODS / H)):
                sim.set_real("osc::u_wall", RATE * sim.get_time())
                sim.set_real("osc::v_wall", RATE)
                t = sim.step()
                if abs(t - round(t)) < 1e-9:
                    rows.append((sim.get_real("osc::u"), sim.get_real("osc::v"),
                                 sim.get_integer("osc::impacts")))
            sim.terminate()
    return np.array(rows)


def _fmusim(path: Path, interface: str, tmp: Path) -> np.ndarray:
    csv = tmp / "inputs.csv"
    csv.write_text(f"time,u_wall,v_wall\n0,0,{RATE!r}\n{PERIODS},{RATE * PERIODS!r},{RATE!r}\n")
    out = tmp / f"out_{interface}_{path.stem}.csv"
    cmd = [str(fmusim()), "--interface-type", interface, "--stop-time", str(PERIODS),
           "--output-interval", repr(H_ME if interface == "me" else H), "--output-file", str(out), "--input-file", str(csv)]
    if interface == "me":
        cmd += ["--solver", "cvode", "--tolerance", repr(ME_RTOL)]
    for k, x in START.items():
        cmd += ["--start-value", k, repr(x)]
    for name in ("u", "v", "impacts"):
        cmd += ["--output-variable", name]
    run = subprocess.run(cmd + [str(path)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr + run.stdout
    res = np.genfromtxt(out, delimiter=",", names=True)
    return _per_period(res["time"], res["u"], res["v"], res["impacts"])


RUNS = {
    "fmi3-cs-fmpy": lambda tmp: _fmpy(FMU3_PATH, "CoSimulation"),
    "fmi2-cs-fmpy": lambda tmp: _fmpy(FMU_PATH, "CoSimulation"),
    "fmi2-cs-ecos": lambda tmp: _ecos(),
    "fmi2-cs-fmusim": lambda tmp: _fmusim(FMU_PATH, "cs", tmp),
    "fmi2-me-fmpy": lambda tmp: _fmpy(FMU_PATH, "ModelExchange"),
    "fmi3-me-fmusim": lambda tmp: _fmusim(FMU3_PATH, "me", tmp),
}


@pytest.mark.parametrize("run", list(RUNS))
def test_readme_example_3_agrees_with_the_ramp_reference(run, reference, tmp_path):
    got = RUNS[run](tmp_path)
    err = np.abs(got[:, :2] - reference[:, :2]).max(axis=0)
    assert err.max() <= TOL, (run, err)
    np.testing.assert_array_equal(got[:, 2], reference[:, 2])


def test_without_the_velocity_the_wall_jumps(reference):
    """The same master without v_wall: the wall jumps by RATE H at each point with zero velocity
    (the impact law then acts on the absolute velocity), a different run."""
    got = _fmpy(FMU_PATH, "CoSimulation", with_velocity=False)
    assert np.abs(got[:, 0] - reference[:, 0]).max() > 0.1
