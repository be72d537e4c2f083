"""A Model Exchange importer written here: scikit-sundae's CVODE (BDF, dense Newton) integrating
the FMU through fmpy, with the FMU's event indicator as CVODE's root function and the FMU's event
iteration at each root -- once with the Jacobian from the FMU's directional derivatives (one
call per state, as fmusim and PyFMI build it), once with CVODE's own difference quotients.

What it counts is what it can measure: the FMU's right-hand-side evaluations (every
fmi2GetDerivatives / fmi3GetContinuousStateDerivatives call, the difference quotients' included),
the directional-derivative calls, and CVODE's own counters as scikit-sundae 1.2 exposes them
(nfev: CVodeGetNumRhsEvals, without the difference quotients' evaluations; njev:
CVodeGetNumJacEvals). scikit-sundae exposes no count of Newton (nonlinear solver) convergence
failures, so none is reported.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from sksundae.cvode import CVODE

from tests.support.derivatives import Instance

CV_ROOT_RETURN = 2


@dataclass
class MeRun:
    """The samples at the output times and the counts of one run."""

    times: list[float] = field(default_factory=list)
    states: list[tuple[float, float]] = field(default_factory=list)
    impacts: list[int] = field(default_factory=list)
    fmu_rhs: int = 0
    fmu_jacobians: int = 0
    cvode_nfev: int = 0
    cvode_njev: int = 0
    events: int = 0


class _Driver:
    """The FMU as CVODE's right-hand side, root function and Jacobian."""

    def __init__(self, x: Instance, run: MeRun) -> None:
        self.x, self.run = x, run

    def _at(self, t: float, y) -> None:
        self.x.fmu.setTime(float(t))
        self.x.set_states(float(y[0]), float(y[1]))

    def rhs(self, t, y, yp) -> None:
        self._at(t, y)
        yp[:] = self.x.derivatives()
        self.run.fmu_rhs += 1

    def roots(self, t, y, g) -> None:
        self._at(t, y)
        g[0] = self.x.get("wall_indicator")[0] if self.x.fmi3 else self._indicator()

    def _indicator(self) -> float:
        import ctypes
        z = (ctypes.c_double * 1)()
        self.x.fmu.getEventIndicators(z, 1)
        return z[0]

    def jacobian(self, t, y, yp, JJ) -> None:
        self._at(t, y)
        JJ[:, :] = self.x.jacobian(("der(u)", "der(v)"), ("u", "v"))
        self.run.fmu_jacobians += 1


def run_me(interface: str, params: dict, t0: float, times, rtol: float,
           fmu_jacobian: bool) -> MeRun:
    """Integrate from t0 through `times` (increasing), sampling (u, v) and impacts at each."""
    run = MeRun()
    x = Instance(interface, t0=t0, **params)
    d = _Driver(x, run)

    def roots(t, y, g) -> None:
        d.roots(t, y, g)
    roots.terminal = [True]
    opts = dict(rtol=rtol, atol=rtol, method="BDF", eventsfn=roots, num_events=1,
                max_num_steps=100000, jacfn=d.jacobian if fmu_jacobian else None)
    try:
        t, y = t0, x.states()
        solver = CVODE(d.rhs, **opts)
        solver.init_step(t, y)
        for target in times:
            while True:
                r = solver.step(float(target), tstop=float(target))
                assert r.success, r.message
                t, y = float(np.ravel(r.t)[-1]), np.array(r.y).reshape(-1, 2)[-1]
                if r.status != CV_ROOT_RETURN:
                    break
                run.cvode_nfev += r.nfev
                run.cvode_njev += r.njev
                d._at(t, y)  # the FMU's event iteration at CVODE's root
                x.enter_event_mode()
                x.event_update()
                x.fmu.enterContinuousTimeMode()
                y = x.states()
                run.events += 1
                solver = CVODE(d.rhs, **opts)  # restart after the jump
                solver.init_step(t, y)
            run.times.append(t)
            run.states.append((float(y[0]), float(y[1])))
            d._at(t, y)
            run.impacts.append(x.integer("impacts"))
        run.cvode_nfev += r.nfev
        run.cvode_njev += r.njev
    finally:
        x.close()
    return run
