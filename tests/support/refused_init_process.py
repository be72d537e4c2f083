"""Reproducer of the refused-initialisation segfault, run in a subprocess by the tests.

    python -m tests.support.refused_init_process ROUNDS [old]

Each round: FMI 2.0 instances with loggers of their own are created, used, closed and garbage
collected; then the refused configuration (solver = 1, the closed form, with the Hertz or
Hunt-Crossley law on the compliant wall) is initialised through plain fmpy (FMU2Slave and
FMU2Model with fmpy's default callbacks, FMU3Slave and FMU3Model), with logging on and off,
while another instance is alive, and each is freed. Every refusal is printed by the logger it
went to; the parent test counts them in stdout.

With "old", the short-lived loggers are given to fmpy's proxy the way tests/support/fmu.py did
before harness/fmu/fmi2_logging.py (a ctypes callback per instance): fmpy's process-global logger
then points at a collected callback when the plain instance reports its refusal (segfault,
exit status -11, measured). Without "old" they go through harness.fmu.fmi2_logging.
"""
from __future__ import annotations

import ctypes
import gc
import sys
from pathlib import Path

from fmpy import calloc, extract, free, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (
    FMU2Model,
    FMU2Slave,
    fmi2CallbackAllocateMemoryTYPE,
    fmi2CallbackFreeMemoryTYPE,
    fmi2CallbackFunctions,
    fmi2CallbackLoggerTYPE,
)
from fmpy.fmi3 import FMU3Model, FMU3Slave
from fmpy.logging import addLoggerProxy

from harness.fmu.fmi2_logging import Fmi2Callbacks

FMU_PATH = Path(__file__).resolve().parents[2] / "build" / "fmu" / "ImpactOscillator.fmu"
FMU3_PATH = FMU_PATH.with_name("ImpactOscillator_fmi3.fmu")  # as tests/support/fmu.py, without
# its imports (numpy): this script also runs under valgrind
VR_WALL, VR_CONTACT, VR_SOLVER = 5, 17, 31


def _old_callbacks(sink: list) -> fmi2CallbackFunctions:  # noqa: ANN001
    """A per-instance ctypes logger handed to fmpy's proxy (the pattern that crashed)."""
    cb = fmi2CallbackFunctions()
    cb.logger = fmi2CallbackLoggerTYPE(lambda env, name, status, cat, msg: sink.append(msg))
    cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    addLoggerProxy(ctypes.byref(cb))
    return cb


def short_lived_logged_instance(unzipped: str, guid: str, old: bool) -> None:
    """An FMI 2.0 instance with a logger of its own, run, freed; its callbacks then collected."""
    sink: list = []
    s = FMU2Slave(guid=guid, unzipDirectory=unzipped, modelIdentifier="ImpactOscillator",
                  instanceName="short")
    holder = _old_callbacks(sink) if old else Fmi2Callbacks(lambda *m: sink.append(m))
    s.instantiate(callbacks=holder if old else holder.functions, loggingOn=True)
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    s.doStep(0.0, 0.5)
    s.terminate()
    s.freeInstance()
    if not old:
        holder.release()
    del s, holder, sink
    gc.collect()
    # fresh ctypes callbacks take the freed closure's memory, as other test files' objects did
    filler = [fmi2CallbackAllocateMemoryTYPE(calloc) for _ in range(8)]
    del filler


def refused(kind: str, contact: int, logging: bool, unzipped: dict[int, str],
            guids: dict[int, str]) -> None:
    """Initialises the refused configuration on a plain fmpy instance; the refusal must raise."""
    version = 3 if kind.startswith("3") else 2
    cls = {"2cs": FMU2Slave, "2me": FMU2Model, "3cs": FMU3Slave, "3me": FMU3Model}[kind]
    f = cls(guid=guids[version], unzipDirectory=unzipped[version],
            modelIdentifier="ImpactOscillator", instanceName=f"refused-{kind}")
    f.instantiate(loggingOn=logging)
    if version == 2:
        f.setupExperiment(startTime=0.0)
        f.enterInitializationMode()
        f.setInteger([VR_WALL, VR_CONTACT, VR_SOLVER], [1, contact, 1])
    else:
        f.enterInitializationMode(startTime=0.0)
        f.setInt32([VR_WALL, VR_CONTACT, VR_SOLVER], [1, contact, 1])
    try:
        f.exitInitializationMode()
    except FMICallException:
        pass
    else:
        raise AssertionError(f"{kind}: contact = {contact} with solver = 1 was accepted")
    f.freeInstance()


def main(rounds: int, old: bool) -> None:
    unzipped = {2: extract(str(FMU_PATH)), 3: extract(str(FMU3_PATH))}
    guids = {2: read_model_description(str(FMU_PATH)).guid,
             3: read_model_description(str(FMU3_PATH)).instantiationToken}
    alive = FMU2Slave(guid=guids[2], unzipDirectory=unzipped[2],
                      modelIdentifier="ImpactOscillator", instanceName="alive")
    alive.instantiate()
    alive.setupExperiment(startTime=0.0)
    alive.enterInitializationMode()
    alive.exitInitializationMode()
    t = 0.0
    for k in range(rounds):
        short_lived_logged_instance(unzipped[2], guids[2], old)
        for kind in ("2cs", "2me", "3cs", "3me"):
            refused(kind, 1 + k % 2, logging=k % 3 == 0, unzipped=unzipped, guids=guids)
        alive.doStep(t, 0.5)
        t += 0.5
        print(f"round {k} done", flush=True)
    alive.terminate()
    alive.freeInstance()


if __name__ == "__main__":
    main(int(sys.argv[1]), len(sys.argv) > 2 and sys.argv[2] == "old")
