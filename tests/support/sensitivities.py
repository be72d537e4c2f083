"""One FMU instance, FMI 2.0 or 3.0 Co-Simulation, for the sensitivity and closed-form tests.

Drives fmpy's FMU2Slave / FMU3Slave by hand (not through the harness), so that the FMU is
tested on its own: parameters by name with their FMI type from modelDescription.xml, one period
per doStep, the outputs J_uu ... S_v.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave

from mapcheck.exact import ExactOscillator
from tests.support.fmu import FMU3_PATH, FMU_PATH, WALLS

SENS = ("J_uu", "J_uv", "J_vu", "J_vv", "S_u", "S_v")
FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112, sigma=0.5, r=0.9, Gamma=10.0)
UNDERDAMPED = dict(nu=0.196, Omega=7.368, sigma=0.01, r=0.9, Gamma=1000.0)
_UNZIPPED: dict[Path, str] = {}


class Fmu:
    """A started FMU instance (FMI version 2 or 3) with typed access by variable name."""

    def __init__(self, version: int = 2):
        path = FMU_PATH if version == 2 else FMU3_PATH
        self.version = version
        self.md = read_model_description(str(path))
        if path not in _UNZIPPED:
            _UNZIPPED[path] = extract(str(path))
        cls = FMU2Slave if version == 2 else FMU3Slave
        self.slave = cls(guid=self.md.guid, unzipDirectory=_UNZIPPED[path],
                         modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName="sens")
        self.slave.instantiate()
        self.var = {v.name: v for v in self.md.modelVariables}
        self.t = 0.0
        self.started = False

    def _set(self, name: str, x) -> None:  # noqa: ANN001
        v, s = self.var[name], self.slave
        if name == "wall" and isinstance(x, str):
            x = WALLS[x]
        if v.type == "Boolean":
            s.setBoolean([v.valueReference], [bool(x)])
        elif v.type in ("Integer", "Int32"):
            (s.setInteger if self.version == 2 else s.setInt32)([v.valueReference], [int(x)])
        else:
            (s.setReal if self.version == 2 else s.setFloat64)([v.valueReference], [float(x)])

    def start(self, t0: float = 0.0, **params) -> None:  # noqa: ANN003
        """(Re)initialise at t0 with the given parameters (the others at their defaults)."""
        s = self.slave
        if self.started:
            s.reset()
        if self.version == 2:
            s.setupExperiment(startTime=t0)
            s.enterInitializationMode()
        else:
            s.enterInitializationMode(startTime=t0)
        for k, x in params.items():
            self._set(k, x)
        s.exitInitializationMode()
        self.t, self.started = t0, True

    def step(self, t1: float) -> None:
        self.slave.doStep(self.t, t1 - self.t)
        self.t = t1

    def get(self, *names: str) -> np.ndarray:
        vrs = [self.var[n].valueReference for n in names]
        get = self.slave.getReal if self.version == 2 else self.slave.getFloat64
        return np.array(get(vrs))

    def state(self) -> np.ndarray:
        return self.get("u", "v")

    def jac(self) -> tuple[np.ndarray, np.ndarray]:
        """(J, S) of the last doStep: J = d(u, v)(end)/d(u, v)(start), S = d(u, v)(end)/d sigma."""
        x = self.get(*SENS)
        return x[:4].reshape(2, 2), x[4:]

    def impacts(self) -> int:
        vr = [self.var["impacts"].valueReference]
        return int((self.slave.getInteger if self.version == 2 else self.slave.getInt32)(vr)[0])

    def close(self) -> None:
        self.slave.terminate()
        self.slave.freeInstance()


def one_period(f: Fmu, params: dict, x0, t0: float, sens: bool = True, solver: int = 0,
               dt: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """State, J, S after one doStep of dt from (u, v) = x0 at t0."""
    f.start(t0, **params, u0=float(x0[0]), v0=float(x0[1]), sensitivities=sens, solver=solver)
    f.step(t0 + dt)
    J, S = f.jac()
    return f.state(), J, S


def oracle(params: dict, sigma: float | None = None) -> ExactOscillator:
    p = dict(params)
    wall = p.pop("wall", "compliant")
    wall = {v: k for k, v in WALLS.items()}[wall] if isinstance(wall, int) else wall
    if sigma is not None:
        p["sigma"] = sigma
    return ExactOscillator(p["nu"], p["Omega"], p["sigma"], p.get("r", 0.9), p.get("Gamma", 10.0), wall)


def exact_derivatives(params: dict, x0, t0: float, dt: float = 1.0,
                      h: float = 1e-5) -> tuple[np.ndarray, np.ndarray]:
    """J and S from central differences of the closed form (mapcheck.exact), Richardson
    extrapolated (steps h and 2h: error O(h^4) plus rounding ~1e-13/h)."""
    osc = oracle(params)

    def f(u, v, o=osc):  # noqa: ANN001
        return np.array(o.state_at(u, v, t0, t0 + dt)[:2])

    def rich(g):  # noqa: ANN001
        d1 = (g(h) - g(-h)) / (2 * h)
        d2 = (g(2 * h) - g(-2 * h)) / (4 * h)
        return (4 * d1 - d2) / 3

    u0, v0 = float(x0[0]), float(x0[1])
    J = np.column_stack([rich(lambda e: f(u0 + e, v0)), rich(lambda e: f(u0, v0 + e))])
    S = rich(lambda e: f(u0, v0, oracle(params, params["sigma"] + e)))
    return J, S
