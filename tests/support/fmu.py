"""Direct fmpy access to a built FMU for the FMU's own tests (independent of the harness).

The harness has its own FMI layer; the FMU's tests drive fmpy's FMU2Slave by hand so that a bug
in the harness cannot hide one in the FMU, and they capture the FMU's log messages.
"""
from __future__ import annotations

import re
import weakref
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave

from harness.fmu.fmi2_logging import Fmi2Callbacks

ROOT = Path(__file__).resolve().parents[2]
FMU_PATH = ROOT / "build" / "fmu" / "ImpactOscillator.fmu"

WALLS = {"none": 0, "compliant": 1, "rigid": 2}
# the per-doStep line the FMU logs under logEvents (fmu_cs.c, core_do_step)
EVENTS_LOG = re.compile(r"(\d+) wall events in .*, (\d+) of them recovered by the rescue of a stepped-over crossing")


@dataclass
class LoggedSlave:
    """An FMU2Slave whose log messages are collected in `messages` as (status, category, text)."""

    path: Path = FMU_PATH
    name: str = "test"
    logging: bool = False
    messages: list[tuple[int, str, str]] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.md = read_model_description(str(self.path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.types = {v.name: v.type for v in self.md.modelVariables}
        self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=extract(str(self.path)),
                               modelIdentifier=self.md.coSimulation.modelIdentifier,
                               instanceName=self.name)

        # fmpy's logger proxy keeps ONE process-wide logger: a per-instance ctypes callback
        # given to it dangled once collected (harness/fmu/fmi2_logging.py), so the messages go
        # through the project's immortal dispatcher to this instance's list.
        messages = self.messages  # not self: the handler must not keep the slave alive
        self._callbacks = Fmi2Callbacks(lambda _name, status, category, text:
                                        messages.append((status, category, text)))
        weakref.finalize(self, self._callbacks.release)
        self.slave.instantiate(callbacks=self._callbacks.functions, loggingOn=self.logging)
        self.t = 0.0

    # -- set-up ---------------------------------------------------------------------------------
    def set(self, **values: float) -> None:
        for k, x in values.items():
            if k == "wall" and isinstance(x, str):
                x = WALLS[x]
            if self.types[k] == "Integer":
                self.slave.setInteger([self.vr[k]], [int(x)])
            elif self.types[k] == "Boolean":
                self.slave.setBoolean([self.vr[k]], [bool(x)])
            else:
                self.slave.setReal([self.vr[k]], [float(x)])

    def start(self, t0: float = 0.0, tolerance: float | None = None, **params: float) -> None:
        """Reset, set the parameters, initialise at t0 (with the importer's tolerance, if any)."""
        self.slave.reset()
        self.slave.setupExperiment(startTime=t0, tolerance=tolerance)
        self.slave.enterInitializationMode()
        self.set(**params)
        self.slave.exitInitializationMode()
        self.t = t0

    # -- stepping -------------------------------------------------------------------------------
    def step_to(self, t: float) -> None:
        self.slave.doStep(self.t, t - self.t)
        self.t = t

    def state(self) -> np.ndarray:
        return np.array(self.slave.getReal([self.vr["u"], self.vr["v"]]))

    def impacts(self) -> int:
        return int(self.slave.getInteger([self.vr["impacts"]])[0])

    def in_contact(self) -> bool:
        return bool(self.slave.getBoolean([self.vr["in_contact"]])[0])

    def get(self, name: str) -> float:
        return float(self.slave.getReal([self.vr[name]])[0])

    def errors(self) -> list[str]:
        return [m for s, _, m in self.messages if s >= 3]

    def close(self) -> None:
        self.slave.freeInstance()


def harness_params(model, **overrides: float) -> dict:  # noqa: ANN001 (harness.FmuModel)
    """The FMU's default parameters for the harness, without the start state (u0, v0), which
    the harness passes separately, updated with `overrides`."""
    p = model.defaults()
    for k in ("u0", "v0"):
        p.pop(k)
    p.update(overrides)
    return p


def on_orbit(sigma: float, t0: float) -> dict[str, float]:
    """u0, v0 on the wall-free periodic orbit p(t) = (1+sigma) cos(2 pi t) - 1 (eq (4)) at t0.

    At Figure 9's parameters the slow eigenvalue is 0.98 per period, so a start at rest takes
    hundreds of periods to reach the wall; a start on p(t0) hits it in the first period.
    """
    w = 2 * np.pi
    return dict(u0=(1 + sigma) * np.cos(w * t0) - 1, v0=-(1 + sigma) * w * np.sin(w * t0))


def expect_error(call, *args) -> None:  # noqa: ANN001
    """Assert that an FMI call returns fmi2Error (fmpy raises FMICallException with status 3)."""
    try:
        call(*args)
    except FMICallException as e:
        assert e.status == 3, f"expected fmi2Error, got status {e.status}"
        return
    raise AssertionError(f"{call.__name__}{args} did not fail")


def refused_and_restored(fmu: LoggedSlave, call, *args) -> None:  # noqa: ANN001
    """Assert that `call` returns fmi2Error, that the instance is then in the Error state, and
    recover it the way FMI 2.0.4 (section 2.1.3) documents: restore a state saved before.

    After fmi2Error "the simulation cannot be continued" with the instance; fmi2SetFMUstate of an
    earlier state (or fmi2Reset) is the way back. Error-state check: fmi2Terminate, allowed in
    every running state but not in Error, is refused.
    """
    saved = fmu.slave.getFMUstate()
    try:
        expect_error(call, *args)
        message = fmu.errors()[-1]
        expect_error(fmu.slave.terminate)
        fmu.messages.append((3, "logStatusError", message))  # the call's message stays last
        fmu.slave.setFMUstate(saved)
    finally:
        fmu.slave.freeFMUstate(saved)


# -- FMI 3.0, Model Exchange and contact-law helpers -----------------------------------------
FMU3_PATH = ROOT / "build" / "fmu" / "ImpactOscillator_fmi3.fmu"


def at_times(result, times) -> tuple[np.ndarray, np.ndarray]:
    """(u, v) and impacts at each of `times` from an fmpy result that also holds event rows
    (the last row at each time: after any event there)."""
    t = result["time"]
    rows = [int(np.flatnonzero(np.isclose(t, x, rtol=0, atol=1e-12))[-1]) for x in times]
    return (np.c_[result["u"][rows], result["v"][rows]],
            np.asarray(result["impacts"][rows], dtype=int))


def simulate(path, fmi_type: str, t0: float, t1: float, dt: float, rtol: float = 1e-10,
             **start_values):
    """fmpy.simulate_fmu with this FMU's outputs; extra keyword arguments go to simulate_fmu
    when they are among its own options, else they are start values."""
    from fmpy import simulate_fmu
    options = {k: start_values.pop(k) for k in ("use_event_mode", "early_return_allowed",
                                                "step_finished", "solver") if k in start_values}
    for k, x in list(start_values.items()):
        if k == "wall" and isinstance(x, str):
            start_values[k] = WALLS[x]
    return simulate_fmu(str(path), fmi_type=fmi_type, start_time=t0, stop_time=t1,
                        output_interval=dt, relative_tolerance=rtol, start_values=start_values,
                        output=["u", "v", "impacts", "in_contact"], **options)
