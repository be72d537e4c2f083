"""One FMU instance per interface (FMI 2/3, ME/CS) through fmpy's own calls, for the tests of the
directional and adjoint derivatives and of Model Exchange's events.

Everything goes through fmpy's wrappers of the FMI functions (fmpy.fmi2.FMU2Model/FMU2Slave,
fmpy.fmi3.FMU3Model/FMU3Slave), so that the FMU is seen as any importer sees it.
"""
from __future__ import annotations

import ctypes

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Model, FMU2Slave
from fmpy.fmi3 import FMU3Model, FMU3Slave

from tests.support.fmu import FMU3_PATH, FMU_PATH

KNOWNS = ("u", "v", "F_ext", "u_wall", "v_wall")
INTEGERS = ("wall", "contact", "solver")
INTERFACES = ("fmi2-me", "fmi2-cs", "fmi3-me", "fmi3-cs")
_UNZIPPED: dict[str, str] = {}


def _unzipped(path) -> str:
    key = str(path)
    if key not in _UNZIPPED:
        _UNZIPPED[key] = extract(key)
    return _UNZIPPED[key]


class Instance:
    """An initialised instance of one interface, at start time t0, with parameters `params`.

    Model Exchange instances are left in Continuous-Time Mode (after the event iteration that
    ends initialisation); Co-Simulation instances in Step Mode.
    """

    def __init__(self, interface: str, t0: float = 0.0, **params: float) -> None:
        self.interface = interface
        self.fmi3 = interface.startswith("fmi3")
        self.me = interface.endswith("me")
        path = FMU3_PATH if self.fmi3 else FMU_PATH
        md = read_model_description(str(path))
        self.vrs = {v.name: v.valueReference for v in md.modelVariables}
        cls = {(False, True): FMU2Model, (False, False): FMU2Slave, (True, True): FMU3Model,
               (True, False): FMU3Slave}[(self.fmi3, self.me)]
        ident = (md.modelExchange if self.me else md.coSimulation).modelIdentifier
        self.fmu = cls(guid=md.guid, unzipDirectory=_unzipped(path), modelIdentifier=ident,
                       instanceName=interface)
        self.fmu.instantiate()
        if self.fmi3:
            self._set_params(params)
            self.fmu.enterInitializationMode(startTime=t0)
        else:
            self.fmu.setupExperiment(startTime=t0)
            self._set_params(params)
            self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        self.t = t0
        if self.me:
            self.event_update()
            self.fmu.enterContinuousTimeMode()

    def _set_params(self, params: dict) -> None:
        for name, x in params.items():
            vr = [self.vrs[name]]
            if name in INTEGERS:
                (self.fmu.setInt32 if self.fmi3 else self.fmu.setInteger)(vr, [int(x)])
            else:
                (self.fmu.setFloat64 if self.fmi3 else self.fmu.setReal)(vr, [float(x)])

    # -- Model Exchange ----------------------------------------------------------------------
    def event_update(self) -> bool:
        """The event iteration; returns valuesOfContinuousStatesChanged."""
        changed = False
        while True:
            out = self.fmu.updateDiscreteStates() if self.fmi3 else self.fmu.newDiscreteStates()
            need, values = out[0], out[3]
            changed |= bool(values)
            if not need:
                return changed

    def enter_event_mode(self) -> None:
        self.fmu.enterEventMode()

    def set_states(self, u: float, v: float) -> None:
        x = (ctypes.c_double * 2)(u, v)
        self.fmu.setContinuousStates(x, 2)

    def states(self) -> np.ndarray:
        x = (ctypes.c_double * 2)()
        self.fmu.getContinuousStates(x, 2)
        return np.array(x[:])

    def derivatives(self) -> np.ndarray:
        dx = (ctypes.c_double * 2)()
        if self.fmi3:
            self.fmu.getContinuousStateDerivatives(dx, 2)
        else:
            self.fmu.getDerivatives(dx, 2)
        return np.array(dx[:])

    # -- variables ----------------------------------------------------------------------------
    def get(self, *names: str) -> np.ndarray:
        vr = [self.vrs[n] for n in names]
        return np.array(self.fmu.getFloat64(vr) if self.fmi3 else self.fmu.getReal(vr))

    def set_inputs(self, **values: float) -> None:
        vr = [self.vrs[n] for n in values]
        x = [float(x) for x in values.values()]
        (self.fmu.setFloat64 if self.fmi3 else self.fmu.setReal)(vr, x)

    def integer(self, name: str) -> int:
        vr = [self.vrs[name]]
        if self.fmi3:
            get = self.fmu.getBoolean if name == "in_contact" else self.fmu.getInt32
            return int(get(vr)[0])
        get = self.fmu.getBoolean if name == "in_contact" else self.fmu.getInteger
        return int(get(vr)[0])

    # -- derivatives --------------------------------------------------------------------------
    def directional(self, unknowns, knowns, seed) -> np.ndarray:
        u = [self.vrs[n] for n in unknowns]
        k = [self.vrs[n] for n in knowns]
        return np.array(self.fmu.getDirectionalDerivative(u, k, list(seed)))

    def adjoint(self, unknowns, knowns, seed) -> np.ndarray:
        u = [self.vrs[n] for n in unknowns]
        k = [self.vrs[n] for n in knowns]
        return np.array(self.fmu.getAdjointDerivative(u, k, list(seed), nSensitivity=len(k)))

    def jacobian(self, unknowns, knowns=KNOWNS) -> np.ndarray:
        """The matrix d unknowns / d knowns, one directional derivative per known (as fmusim and
        PyFMI build it)."""
        cols = [self.directional(unknowns, knowns, np.eye(len(knowns))[j])
                for j in range(len(knowns))]
        return np.array(cols).T

    def close(self) -> None:
        self.fmu.terminate()
        self.fmu.freeInstance()
