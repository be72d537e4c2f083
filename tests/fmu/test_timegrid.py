"""Results independent of the importer's time grid, FMI 2.0 and 3.0 Co-Simulation.

Importers compute communication points differently: fmusim as t0 + k h, others by summing
t += h, some with variable steps; the points land a few ulps off "round" times. Setting every
communication point as CVODE's stop time would make a point a few ulps past an internal step end
give a ~1e-14 "sliver" step that spoils the variable-step Adams history (u off by up to 5e-5
after 100 periods on the grid t0 + k 0.01, 1e-10 on t += 0.01). So CVODE steps on its own sequence and the state at a communication point is read from its interpolant, so the
grid cannot change the integration.

Two kinds of checks, for every wall model:
* the state at every communication point against the closed form (mapcheck.exact, evaluated
  densely), within the FMU's budget of 1e-8;
* the states at the times the grids share (the integers, up to the grid's rounding) against
  a run with one doStep per period: equal up to the rounding of the time itself.
"""
from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave

from mapcheck.exact import ExactOscillator
from tests.support.fmu import FMU3_PATH, FMU_PATH, WALLS

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112)
SIGMA, R, GAMMA = 0.5, 0.9, 10.0  # Figure 9, sigma = 0.5 (period 2)
T0 = 0.5
START = dict(u0=-(1.0 + SIGMA) - 1.0, v0=0.0)  # on the wall-free orbit p(t) at t = 0.5
BUDGET = 1e-8


class Driver:
    """A Co-Simulation instance of either FMI version, stepped on a given grid."""

    def __init__(self, path: Path, version: int) -> None:
        md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        self.version = version
        cls = FMU2Slave if version == 2 else FMU3Slave
        self.fmu = cls(guid=md.guid, unzipDirectory=extract(str(path)),
                       modelIdentifier=md.coSimulation.modelIdentifier, instanceName="grid")
        self.fmu.instantiate()

    def run(self, wall: str, grid: np.ndarray) -> np.ndarray:
        """(u, v) at each point of `grid` (increasing, after T0), one doStep per point."""
        f, vr = self.fmu, self.vr
        reals = dict(sigma=SIGMA, r=R, Gamma=GAMMA, **START, **FIG9)
        f.reset()
        if self.version == 2:
            f.setupExperiment(startTime=T0)
            f.enterInitializationMode()
            f.setReal([vr[k] for k in reals], list(reals.values()))
            f.setInteger([vr["wall"]], [WALLS[wall]])
            get = f.getReal
        else:
            f.enterInitializationMode(startTime=T0)
            f.setFloat64([vr[k] for k in reals], list(reals.values()))
            f.setInt32([vr["wall"]], [WALLS[wall]])
            get = f.getFloat64
        f.exitInitializationMode()
        out = np.empty((len(grid), 2))
        t = T0
        for k, t_next in enumerate(grid):
            f.doStep(t, t_next - t)  # the importer's own arithmetic: h = t_next - t
            t = t_next
            out[k] = get([vr["u"], vr["v"]])
        return out

    def close(self) -> None:
        self.fmu.terminate()
        self.fmu.freeInstance()


def fixed(h: float, periods: float) -> Callable[[], np.ndarray]:
    """fmusim's grid t0 + k h."""
    return lambda: T0 + h * np.arange(1, int(round(periods / h)) + 1)


def summed(h: float, periods: float) -> Callable[[], np.ndarray]:
    """An importer that sums its steps, t += h."""
    def make() -> np.ndarray:
        out, t = [], T0
        for _ in range(int(round(periods / h))):
            t += h
            out.append(t)
        return np.array(out)
    return make


def random_steps(periods: int) -> Callable[[], np.ndarray]:
    """Variable steps from 1e-4 to 0.5 (a master with its own step control) that also stop at
    the integers t0 + n (its output points)."""
    def make() -> np.ndarray:
        steps = np.random.default_rng(14).uniform(1e-4, 0.5, int(4 * periods))
        t = T0 + np.cumsum(steps)
        return np.union1d(t[t <= T0 + periods], T0 + np.arange(1, periods + 1))
    return make


def ulps_off(periods: int) -> Callable[[], np.ndarray]:
    """The integers and points a few ulps either side of them."""
    def make() -> np.ndarray:
        pts = []
        for k in range(1, periods + 1):
            x = T0 + k
            pts += [x - 3 * np.spacing(x), x - np.spacing(x), x, x + 2 * np.spacing(x)]
        return np.unique(pts)
    return make


GRIDS = {
    "t0+k*1e-4": fixed(1e-4, 1),
    "t0+k*1e-3": fixed(1e-3, 3),
    "t0+k*0.01": fixed(0.01, 20),
    "t0+k*0.1": fixed(0.1, 40),
    "t0+k*0.3": fixed(0.3, 39),
    "t0+k*1": fixed(1.0, 40),
    "t0+k*10": fixed(10.0, 40),
    "sum 1e-3": summed(1e-3, 3),
    "sum 0.01": summed(0.01, 20),
    "sum 0.1": summed(0.1, 40),
    "random": random_steps(40),
    "ulps": ulps_off(40),
}
FMI3_GRIDS = ["t0+k*0.01", "sum 0.01", "random", "ulps"]  # the same core: a subset suffices


@pytest.fixture(scope="module")
def drivers():
    d = {2: Driver(FMU_PATH, 2), 3: Driver(FMU3_PATH, 3)}
    yield d
    for x in d.values():
        x.close()


def exact_on(wall: str, grid: np.ndarray) -> np.ndarray:
    osc = ExactOscillator(FIG9["nu"], FIG9["Omega"], SIGMA, r=R, Gamma=GAMMA, wall=wall)
    return osc.dense(START["u0"], START["v0"], grid, t0=T0)[0]


CASES = [(2, g) for g in GRIDS] + [(3, g) for g in FMI3_GRIDS]


@pytest.mark.parametrize("wall", ["none", "compliant", "rigid"])
@pytest.mark.parametrize("version,grid", CASES)
def test_every_communication_point_matches_the_closed_form(drivers, version, grid, wall):
    points = GRIDS[grid]()
    got = drivers[version].run(wall, points)
    err = np.max(np.abs(got - exact_on(wall, points)), axis=0)
    assert np.all(err <= BUDGET), f"max |du|, |dv| = {err}"
    if wall == "rigid":
        assert np.all(got[:, 0] <= 0.0)


@pytest.mark.parametrize("wall", ["none", "compliant", "rigid"])
@pytest.mark.parametrize("version,grid", [c for c in CASES if c[1] not in ("t0+k*1", "t0+k*10")])
def test_the_grid_does_not_change_the_states_it_shares(drivers, version, grid, wall):
    """Where a grid passes the integers t0 + n (up to its rounding, |dt| <= 1e-11 for the
    summed grids), its states equal those of a run with one doStep per period, up to what that
    rounding of t itself makes: |(v, a)| |dt| (|v|, |a| < 100 here) plus 1e-13."""
    ref_points = GRIDS["t0+k*1"]()
    reference = drivers[version].run(wall, ref_points)
    points = GRIDS[grid]()
    got = drivers[version].run(wall, points)
    shared = 0
    for n, t in enumerate(ref_points):
        k = int(np.argmin(np.abs(points - t)))
        dt = abs(points[k] - t)
        if dt <= 1e-11:
            diff = np.max(np.abs(got[k] - reference[n]))
            assert diff <= 1e-13 + 100.0 * dt, (t, dt, got[k], reference[n])
            shared += 1
    assert shared >= 1
