"""The built-in defaults of every setting, the CLI flag of each (for error messages), and where
the package finds its FMU and how many cores it may use."""
from __future__ import annotations

import os
from pathlib import Path
from typing import Any

__all__ = ["SWEEP_MODES", "BACKENDS", "DEFAULTS", "CLI_FLAGS", "SECTION_PHASE", "DEFAULT_SOLVER", "SOLVERS",
           "MODEL_SHORTCUTS", "WALLS", "wall_name", "solver_name", "project_root", "default_fmu_path",
           "default_workers"]

SWEEP_MODES = ("fresh", "up", "down", "both")
BACKENDS = ("serial", "processes", "dask")


def project_root() -> Path:
    """The checkout the package lives in (an editable install points here)."""
    return Path(__file__).resolve().parents[2]  # harness/config/defaults.py -> the checkout


def default_fmu_path() -> str:
    """``$IMPACT_HARNESS_FMU`` or ``build/fmu/ImpactOscillator.fmu`` in the checkout."""
    env = os.environ.get("IMPACT_HARNESS_FMU")
    if env:
        return env
    return str(project_root() / "build" / "fmu" / "ImpactOscillator.fmu")


def default_workers() -> int:
    """Cores this process may use (respects CPU affinity and container limits)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


#: The section phase of every command (sweep, strobe, basins, continue, windows, chart, the
#: paper's figures unless their experiment file says otherwise): samples at t = n + 1/2.  The
#: near-grazing orbits hit the wall near t = n (the wall-free orbit (1 + sigma) cos(2 pi t) - 1
#: is highest there), so a section at phase 0 would sit on the impacts, where the stroboscopic
#: map is not smooth and Newton shooting stalls; half a period away it is smooth.
SECTION_PHASE = 0.5

#: The FMU's integrators: the CLI name of each value of the FMU's Integer parameter ``solver`` (the
#: one solver table: every command, check and report reads it by name).
SOLVERS: dict[str, int] = {"cvode": 0, "closed-form": 1}
#: The one default of every command: CVODE, the FMU's own default, which every FMU and every
#: contact law has (the closed form is exact and ~30x faster, for the linear contact law:
#: ``--solver closed-form``).
DEFAULT_SOLVER = "cvode"

#: The oscillator's parameters every command takes as flags (shortcuts for ``--set NAME=VALUE``),
#: with their meaning for ``--help``.
MODEL_SHORTCUTS: dict[str, str] = {
    "nu": "damping nu (the FMU parameter)",
    "Omega": "natural frequency Omega over the forcing frequency",
    "r": "coefficient of restitution r in (0, 1]",
    "Gamma": "compliant wall stiffness ratio Gamma = kappa^2/Omega^2",
}
#: The wall models: the name of each value of the FMU's Integer parameter ``wall`` (the one wall
#: table: every command, check and report reads it by name).
WALLS: dict[str, int] = {"none": 0, "compliant": 1, "rigid": 2}


def wall_name(code: object) -> str:
    """The name of a ``wall`` code (``1`` -> ``"compliant"``); a name is returned as it is."""
    return _name_of(WALLS, code)


def solver_name(code: object) -> str:
    """The name of a ``solver`` code (``1`` -> ``"closed-form"``); a name is returned as it is."""
    return _name_of(SOLVERS, code)


def _name_of(table: dict[str, int], code: object) -> str:
    if isinstance(code, str):
        return code
    by_code = {v: k for k, v in table.items()}
    return by_code.get(int(code), str(code))  # type: ignore[call-overload]

#: Built-in defaults of every section (``[model]``: the FMU's start values, except the solver).
DEFAULTS: dict[str, dict[str, Any]] = {
    "fmu": {"path": None},
    # the FMU's own start values, and the one default solver of every command
    "model": {"solver": DEFAULT_SOLVER},
    "initial": {"u0": None, "v0": None},
    # 300 transient periods: the slow free-flight mode decays like 0.98^n at Figure 9's
    # parameters, and orbits near window edges converge slowly.
    "sampling": {"theta": SECTION_PHASE, "transient": 300, "samples": 40, "tol": 1e-5, "max_period": None, "extend": 0,
                 "lyapunov": 0},
    # Default sweep: Figure 9 from period 1 (sigma > ~0.85) down through period 2 and 3.
    "sweep": {
        "param": "sigma",
        "start": 1.0,
        "stop": 0.1,
        "num": 91,
        "values": None,
        "mode": "both",
        "scan_param": None,
        "scan_values": None,
    },
    "jacobian": {
        "theta": 0.0,
        "measure_theta": 0.5,
        "x_start": 1e-6,
        "x_stop": 1e-2,
        "x_num": 25,
        "state": None,
        "method": "auto",  # exact (the FMU's derivatives), fd (differences), auto (exact when available)
        "rtol": None,  # None: the FMU's own (tight) default tolerances
        "atol": None,
    },
    "simulate": {"t0": 0.0, "t_end": 10.0, "dt": 0.01},
    "run": {
        "backend": None,
        "workers": None,
        "scheduler": None,
        "out": None,
        "plot": None,
        "checkpoint": None,
        "progress": True,
    },
}

#: The CLI flag of each key, for error messages.
CLI_FLAGS: dict[tuple[str, str], str] = {
    ("fmu", "path"): "--fmu",
    ("initial", "u0"): "--u0",
    ("initial", "v0"): "--v0",
    ("sampling", "theta"): "--theta",
    ("sampling", "transient"): "--transient",
    ("sampling", "samples"): "--samples",
    ("sampling", "tol"): "--tol",
    ("sampling", "max_period"): "--max-period",
    ("sampling", "extend"): "--extend",
    ("sampling", "lyapunov"): "--lyapunov",
    ("sweep", "param"): "--param",
    ("sweep", "start"): "--start",
    ("sweep", "stop"): "--stop",
    ("sweep", "num"): "--num",
    ("sweep", "values"): "--values",
    ("sweep", "mode"): "--mode",
    ("sweep", "scan_param"): "--scan",
    ("sweep", "scan_values"): "--scan",
    ("jacobian", "theta"): "--theta",
    ("jacobian", "measure_theta"): "--measure-theta",
    ("jacobian", "x_start"): "--x-start",
    ("jacobian", "x_stop"): "--x-stop",
    ("jacobian", "x_num"): "--x-num",
    ("jacobian", "state"): "--state",
    ("jacobian", "method"): "--method",
    ("simulate", "t0"): "--t0",
    ("simulate", "t_end"): "--t-end",
    ("simulate", "dt"): "--dt",
    ("run", "backend"): "--backend",
    ("run", "workers"): "--workers",
    ("run", "scheduler"): "--scheduler",
    ("run", "out"): "--out",
    ("run", "plot"): "--plot",
    ("run", "checkpoint"): "--checkpoint",
}
