"""The pythonfmu twin's tests (tests/twin/test_twin_*.py) share these: where the twin and the C
FMU are built, the parameter sets, an fmpy slave on either FMU, the wall-free orbit, and a run of
either FMU through the harness's simulator strobed once per period."""
from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from harness.fmu.fmi import FmuModel
from harness.fmu.simulator import FmuSimulator
from tests.support.fmu import LoggedSlave

ROOT = Path(__file__).resolve().parents[2]
TWIN_SRC = ROOT / "fmu_src" / "pytwin"
TWIN_FMU = ROOT / "build" / "fmu" / "ImpactOscillatorPy.fmu"
C_FMU = ROOT / "build" / "fmu" / "ImpactOscillator.fmu"

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112)  # overdamped, the paper's Fig. 9
UNDERDAMPED = dict(nu=0.196, Omega=7.368)
THETA = 0.5  # strobe half a period away from the grazing phase t = n


def Slave(path: Path, logging: bool = False) -> LoggedSlave:
    """fmpy's FMU2Slave on one FMU, collecting log messages (status, category, text).

    The tests of the twin alone use this (not the harness) so that they also see the FMI
    status codes and the log; the cross-check uses the harness.
    """
    return LoggedSlave(path=path, name="twin-test", logging=logging)


def on_orbit(t0: float, sigma: float) -> tuple[float, float]:
    """The wall-free periodic orbit p(t) = (1+sigma) cos(2 pi t) - 1 of eq (4) at t0."""
    w = 2.0 * math.pi
    return (1 + sigma) * math.cos(w * t0) - 1, -(1 + sigma) * w * math.sin(w * t0)


def harness_strobe(path: Path, params: dict, t0: float, state: tuple[float, float],
                   periods: int, tune: dict[int, float] | None = None
                   ) -> tuple[np.ndarray, np.ndarray, float]:
    """Drive one FMU through the harness's simulator and strobe it once per period.

    Parameters
    ----------
    path : Path
        The FMU.
    params : dict
        Parameters (by name) for ``FmuSimulator.start``.
    t0, state : float, (float, float)
        Start time and (u, v) there.
    periods : int
        Number of periods; the strobe times are t0 + 1, ..., t0 + periods.
    tune : dict, optional
        {period index k: sigma}: set sigma (tunable) after the k-th strobe.

    Returns
    -------
    states : ndarray (periods, 2)
    impacts : ndarray (periods,)
    seconds_per_period : float
        Wall-clock cost of the stepping (initialisation excluded).
    """
    sim = FmuSimulator(FmuModel(path).source(), instance_name="twin-xcheck")
    try:
        sim.start(params, t0, state)
        states, counts = np.empty((periods, 2)), np.empty(periods, dtype=int)
        tic = time.perf_counter()
        for k in range(periods):
            sim.advance(t0 + k + 1)
            u, v, n = sim.read()
            states[k] = u, v
            counts[k] = n
            if tune and k in tune:
                sim.set_parameter("sigma", tune[k])
        return states, counts, (time.perf_counter() - tic) / periods
    finally:
        sim.close()
