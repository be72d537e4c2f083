"""The twin's CVODE driver: :class:`CvodeDriver`, the counterpart of the C FMU's
``fmu_src/solver_cvode.c`` (SUNDIALS CVODE through scikit-sundae), integrating an
:class:`twin_physics.OscillatorModel` between communication points.
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

from twin_physics import OscillatorModel


class SolverError(RuntimeError):
    """CVODE failed, or a doStep would not terminate (message says why and when)."""


class CvodeDriver:
    """Integrates an :class:`OscillatorModel` between communication points with CVODE.

    Mirrors ``fmu_src/solver_cvode.c``: the same re-origin rule, maximum step, root indicators,
    event handling and work bounds, and CVODE steps past the communication points and
    interpolates there (see :meth:`_cvode_step`).  The one difference is how a crossing stepped
    over by the solver is located: CVODE's interpolant (``CVodeGetDky``) is not exposed by
    scikit-sundae, so the twin re-integrates from the last point known to lie on the correct
    side of the wall (a return of CVODE at most one doStep back, in practice the previous
    turning point) up to the turning point that revealed the miss, with CVODE's root finding
    on.  That re-integration ends on the wrong side of the wall, so the sign change of g0 is
    bracketed by some step and CVODE locates it.

    Parameters
    ----------
    model : OscillatorModel
        The model; its ``rtol``/``atol`` are read here, so create the driver after they are
        final (FMI: at the end of initialisation).
    """

    #: Re-origin the local time once it passes this, so that tau stays O(1).
    REORIGIN_AFTER = 64.0
    #: Solver steps must not straddle two turning points of u (then the guard's sign change on
    #: v is lost too); a fifth of the shortest period in the problem (forcing: 1) is safe.
    MAX_STEP = 0.05
    #: Bounds on the work of one doStep per unit of time advanced: errors, never hangs.
    MAX_STEPS_PER_CALL = 200_000
    MAX_EVENTS_PER_UNIT_TIME = 1e5

    def __init__(self, model: OscillatorModel) -> None:
        from sksundae.cvode import CVODE  # imported here: only the FMU process needs it

        self.model = model
        self._indicators = model.make_indicators()
        self._cvode = CVODE(
            model.make_rhs(),
            method="Adams",  # as the C FMU: non-stiff, high order pays at rtol 1e-10
            rtol=model.rtol,
            atol=model.atol,
            max_step=self.MAX_STEP,
            max_num_steps=self.MAX_STEPS_PER_CALL,
            jacfn=model.make_jacobian(),
            eventsfn=self._indicators,
            num_events=2,
        )
        self.origin: float = 0.0
        self.tau: float = 0.0
        # last point where the indicators were known to have their mode's sign
        self.tau_good: float = 0.0
        self.y_good: list[float] = [model.u, model.v]
        self.needs_reinit: bool = True
        self._fresh: bool = True
        self.events: int = 0
        self.guard_hits: int = 0  # crossings stepped over and recovered by the rescue (side check)
        self.first_step_retries: int = 0  # see _cvode_step: a root past the point in step 1

    # -- time ------------------------------------------------------------------------------
    def start(self, t: float) -> None:
        """Put the solver at absolute time ``t`` with the model's state (CVODE restarts)."""
        self.origin = float(math.floor(t))
        self.tau = t - self.origin
        self.needs_reinit = True

    @property
    def time(self) -> float:
        """Absolute time ``origin + tau``."""
        return self.origin + self.tau

    # -- internals -------------------------------------------------------------------------
    def _clear_event_log(self) -> None:
        # scikit-sundae appends every root to lists on the events function and converts the
        # whole lists to arrays on every call: without clearing, a long run goes quadratic.
        ev = self._indicators
        ev._i.clear()  # type: ignore[attr-defined]
        ev._t.clear()  # type: ignore[attr-defined]
        ev._y.clear()  # type: ignore[attr-defined]
        ev._i_cnt[:] = 0  # type: ignore[attr-defined]

    def _reinit(self) -> None:
        """Restart CVODE at (tau, u, v) in the model's current mode, moving the integer time
        origin up to the current period first."""
        m = self.model
        k = math.floor(self.tau)
        self.origin += k
        self.tau -= k
        if m.release_now(self.tau):
            self.events += 1
        res = self._cvode.init_step(self.tau, np.array([m.u, m.v]))
        if not res.success:
            raise SolverError(f"CVODE re-initialisation failed: {res.message}")
        self.tau_good = self.tau
        self.y_good = [m.u, m.v]
        self.needs_reinit = False
        self._fresh = True  # the next CVODE call takes the first step (see _cvode_step)

    def _locate_missed_crossing(self, tau_turn: float) -> Optional[tuple[float, list[float]]]:
        """Re-integrate from the last good point to the turning point ``tau_turn``.

        Returns
        -------
        (tau_c, y_c) or None
            The crossing (state just past it, on the far side of the wall), or ``None`` if
            the re-integrated trajectory does not cross (a contact shallower than the solver's
            own error; the re-integrated state at ``tau_turn`` is then kept, see caller).
        """
        res = self._cvode.init_step(self.tau_good, np.array(self.y_good))
        if not res.success:
            raise SolverError(f"CVODE re-initialisation failed: {res.message}")
        res = self._cvode.step(tau_turn, method="normal", tstop=tau_turn)
        if res.status < 0:
            raise SolverError(
                f"CVODE failed while locating a stepped-over wall crossing before "
                f"t = {self.origin + tau_turn!r}: {res.message}"
            )
        hit = res.status == 2 and res.i_events is not None and res.i_events[-1][0] != 0
        self._clear_event_log()
        if hit:
            return float(res.t), [float(res.y[0]), float(res.y[1])]
        if self.model.missed_crossing(float(res.y[0])):
            # the re-integration ends on the wrong side too, without a located crossing: as the
            # C FMU, fail rather than carry a state inside the wall
            raise SolverError(
                "could not locate a wall crossing stepped over before "
                f"t = {self.origin + tau_turn!r}"
            )
        self.tau = float(res.t)
        self.model.u, self.model.v = float(res.y[0]), float(res.y[1])
        return None

    # -- the communication step ------------------------------------------------------------
    def _cvode_step(self, tau_end: float):
        """One call into CVODE towards ``tau_end``; never a stop time at a communication point.

        The C FMU steps CVODE in one-step mode past the communication points and reads the
        state there from CVODE's interpolant (``CVodeGetDky``).  scikit-sundae exposes neither
        ``CVodeGetDky`` nor a persistent stop time, but ``CVode(tout, CV_NORMAL)`` without a
        stop time is the same thing: CVODE takes its own steps until it passes ``tout`` and
        returns ``CVodeGetDky(tout)``, checking roots only up to ``tout`` (so no event past the
        point is returned).  Setting ``tout`` as a stop time instead (as before) made the result
        depend on the importer's time arithmetic: a point a few ulps past a step end gave a
        ~1e-14 "sliver" step that spoiled the variable-step Adams history (u off by 5e-5 after
        100 periods on the grid t0 + k 0.01, 4e-11 on t += 0.01).  The only stop time is the
        re-origin time, the same for every grid.

        The first step after a restart is taken in one-step mode with ``tout = tau + 1`` (as
        the C FMU), because CVODE's initial step size depends on ``tout``.  If that step ends
        past ``tau_end`` the next (normal-mode) call only interpolates.  If it returns a root
        past ``tau_end`` (a wall crossing or turning point within the first step after a
        restart, some 1e-14 long, with the point in between) CVODE is restarted and the step
        retaken with ``tau_end`` as its stop time, and the caller restarts at the point:
        grid-dependent, in that rare case.
        """
        cvode = self._cvode
        if self._fresh:
            self._fresh = False
            res = cvode.step(self.tau + 1.0, method="onestep", tstop=self.REORIGIN_AFTER)
            if res.status != 2 or float(res.t) <= tau_end:
                return res
            # Restart and take the first step again, stopped at the point (a tout that close
            # would be refused as "too close" in normal mode); the caller restarts there.
            self._clear_event_log()
            self.first_step_retries += 1
            res = cvode.init_step(self.tau, np.array([self.model.u, self.model.v]))
            if not res.success:
                raise SolverError(f"CVODE re-initialisation failed: {res.message}")
            return cvode.step(self.tau + 1.0, method="onestep", tstop=tau_end)
        return cvode.step(tau_end, method="normal", tstop=self.REORIGIN_AFTER)

    def advance(self, t_end: float) -> None:
        """Integrate to absolute time ``t_end``, applying every wall event on the way.

        Raises
        ------
        SolverError
            CVODE failed, the target lies in the past, or the events do not end (chatter that
            does not settle).
        """
        m = self.model
        if self.needs_reinit or self.tau >= self.REORIGIN_AFTER:
            self._reinit()
        tau_end = t_end - self.origin
        if tau_end < self.tau:
            raise SolverError(f"cannot integrate backwards to t = {t_end!r}")
        span = max(1.0, math.ceil(tau_end - self.tau))
        max_events = int(self.MAX_EVENTS_PER_UNIT_TIME * span)
        n_events = 0

        while self.tau < tau_end:
            res = self._cvode_step(tau_end)
            if res.status < 0:
                raise SolverError(
                    f"CVODE failed near t = {self.origin + float(res.t)!r}: {res.message}"
                )
            tret = float(res.t)
            y = [float(res.y[0]), float(res.y[1])]
            if res.status == 0 and tret > tau_end:
                # the first step after a restart ended past the point: interpolate next call
                continue
            self.tau = tret
            m.u, m.v = y
            if res.status == 1:
                # a stop time (CV_TSTOP_RETURN): the re-origin time, the same for every grid,
                # or the point itself in _cvode_step's rare retry; restart there
                self.tau_good, self.y_good = tret, y
                self._reinit()
                tau_end = t_end - self.origin
                continue
            if res.status != 2:  # success: tret == tau_end, or a step end before it
                # A return lies on the mode's side of the wall (else g0 would have changed
                # sign in the last step and been returned as a root first).
                self.tau_good, self.y_good = tret, y
                continue
            info = res.i_events[-1]
            self._clear_event_log()
            if info[0] == 0 and not m.missed_crossing(y[0]):
                # a turning point on the right side of the wall
                self.tau_good, self.y_good = tret, y
                continue
            tc, yc = tret, y
            if info[0] == 0:
                found = self._locate_missed_crossing(tret)
                if found is None:
                    # Re-integration did not cross: keep its state, which is on the mode's
                    # side, and continue from there (CVODE is positioned at that point).
                    self.tau_good, self.y_good = self.tau, [m.u, m.v]
                    continue
                tc, yc = found
                self.guard_hits += 1
            m.event_update(tc, yc)
            self.tau = tc
            m.u, m.v = yc
            self.events += 1
            n_events += 1
            if n_events > max_events:
                raise SolverError(
                    f"more than {max_events} wall events before t = {self.origin + tc!r} "
                    "(chatter that does not end?)"
                )
            self._reinit()
            tau_end = t_end - self.origin  # the origin may have moved
