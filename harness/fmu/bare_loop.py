"""The FMU driven by hand, as a user would write it without the harness: one fmpy FMU2Slave,
``doStep(t, 1)`` and a ``getReal``/``getInteger`` of (u, v, impacts) per period.  The baseline
that :mod:`harness.runs.benchmark` measures the harness against (fmpy is known only to this layer).
"""
from __future__ import annotations

import time
from typing import Any

import numpy as np
from fmpy.fmi2 import FMU2Slave

from .fmi import FmuModel, open_source


def bare_loop(model: FmuModel, params: dict[str, Any], state0: tuple[float, float],
              periods: int) -> tuple[float, np.ndarray]:
    """Seconds for ``periods`` periods with fmpy's FMU2Slave driven by hand, and the
    (u, v, impacts) it read after each period."""
    unzipdir, _ = open_source(model.source())
    v = model.variables
    fmu = FMU2Slave(guid=model.guid, unzipDirectory=unzipdir, modelIdentifier=model.model_identifier,
                    instanceName="bare")
    fmu.instantiate()
    try:
        values = {**params, "u0": state0[0], "v0": state0[1]}
        t0 = time.perf_counter()
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        reals = [n for n in values if v[n].type == "Real"]
        ints = [n for n in values if v[n].type == "Integer"]
        fmu.setReal([v[n].value_reference for n in reals], [float(values[n]) for n in reals])
        fmu.setInteger([v[n].value_reference for n in ints], [int(values[n]) for n in ints])
        fmu.exitInitializationMode()
        vr_state = [v["u"].value_reference, v["v"].value_reference]
        vr_imp = [v["impacts"].value_reference]
        out = np.empty((periods, 3))
        for k in range(periods):
            fmu.doStep(currentCommunicationPoint=float(k), communicationStepSize=1.0)
            out[k, :2] = fmu.getReal(vr_state)
            out[k, 2] = fmu.getInteger(vr_imp)[0]
        elapsed = time.perf_counter() - t0
        fmu.terminate()
    finally:
        fmu.freeInstance()
    return elapsed, out
