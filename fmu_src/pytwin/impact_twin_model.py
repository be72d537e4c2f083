"""Physics and CVODE driver of the impact oscillator, in Python (the pythonfmu twin).

This module is the counterpart of the C FMU's ``fmu_src/model.c`` (the physics) and
``fmu_src/solver_cvode.c`` (the CVODE driver): the same specification and the same rules
(thresholds, directions, re-origin), a separate implementation on a separate SUNDIALS build, so
that the two check each other.  The differences, on purpose: how a stepped-over crossing is
located (:class:`CvodeDriver`) and the tail of rigid-wall chatter
(:meth:`OscillatorModel._rigid_impact`).  It is also the place to change the contact law
without touching C: everything that defines what happens at the wall is in
:class:`OscillatorModel` (``make_rhs``, ``make_jacobian``, ``make_indicators``,
``event_update``, ``missed_crossing``, ``release_now``).

The model is the non-dimensional driven oscillator of Molenaar, de Weger & van de Water (2001),
eqs (3), (5), (40), (53) (see ``docs/theory.md``, section 1)::

    u'' + nu u' + Omega^2 (u + 1) [+ kappa^2 u in contact] = (1 + sigma) F_g cos(2 pi t + phi)

Time inside the model is *local*: ``tau = t - origin`` with an integer ``origin``, so the
forcing phase ``cos(2 pi tau + phi)`` keeps full precision after many periods.

The integrator is SUNDIALS CVODE (Adams, dense linear solver, analytic Jacobian) through
scikit-sundae.  Wall crossings are located by CVODE's root finding on two indicators, the wall
(g0) and the velocity (g1, the grazing guard); see :class:`CvodeDriver`.
"""
from __future__ import annotations

import math
from typing import Callable, Optional

import numpy as np

__all__ = [
    "WALL_NONE",
    "WALL_COMPLIANT",
    "WALL_RIGID",
    "MODE_FREE",
    "MODE_CONTACT",
    "MODE_STICK",
    "STICK_VELOCITY",
    "ON_WALL",
    "CHATTER_RESOLVED_ATOL",
    "ModelError",
    "OscillatorModel",
    "SolverError",
    "CvodeDriver",
]

WALL_NONE, WALL_COMPLIANT, WALL_RIGID = 0, 1, 2
#: Discrete state. CONTACT: inside the compliant wall. STICK: resting on the rigid wall after
#: chatter, held there while the net force pushes into it.
MODE_FREE, MODE_CONTACT, MODE_STICK = 0, 1, 2

#: Chatter on the rigid wall: once an impact leaves at most this velocity (relative to the
#: incoming one, floored at 1) and the wall force pushes inwards, the impacts would accumulate in
#: finite time; the mass is taken to stick instead (Zeno truncation).  Same value as model.c.
STICK_VELOCITY = 1e-9

#: Where an event leaves the mass on the wall, u is put a hair on the side of its new mode
#: rather than at 0 (as model.c): CVODE deactivates a root function that is exactly zero at a
#: restart and takes its reference sign only after the first step, so a contact or flight
#: shorter than that first step (chatter, grazing) would be stepped over.
ON_WALL = 1e-300

#: Rigid-wall chatter: a flight that rises less than this many ``atol`` above the wall is not
#: left to CVODE, which cannot resolve it (see ``OscillatorModel._rigid_impact``).
CHATTER_RESOLVED_ATOL = 100.0

_TWO_PI = 2.0 * math.pi
_FOUR_PI2 = 4.0 * math.pi * math.pi


def _fmt(x: object) -> str:
    """A value as C's ``%g`` prints it (messages use the C FMU's wording)."""
    try:
        return f"{float(x):g}"
    except (TypeError, ValueError):
        return repr(x)


class ModelError(ValueError):
    """A parameter value or combination the model rejects (message names the variable)."""


#: Valid ranges (lo, hi, lo excluded) of the Real parameters: the C FMU's (fmu_vars.c, VARS).
RANGES = {
    "nu": (0.0, 1e6, False),
    "Omega": (1e-6, 1e4, False),
    "sigma": (-1.0, 1e6, True),
    "r": (0.0, 1.0, False),
    "Gamma": (0.0, 1e16, False),
    "u0": (-1e6, 1e6, False),
    "v0": (-1e6, 1e6, False),
    "rtol": (1e-15, 0.1, False),
    "atol": (1e-30, 0.01, False),
}


def check_real(name: str, x: float) -> Optional[str]:
    """Check one Real parameter value before it is stored (mirrors ``model_check_real``).

    Parameters
    ----------
    name : str
        Variable name (``nu``, ``Omega``, ``sigma``, ``r``, ``Gamma``, ``u0``, ``v0``, ``rtol``,
        ``atol``).
    x : float
        Proposed value.

    Returns
    -------
    str or None
        ``None`` if the value is acceptable, otherwise why not (without the variable name).
    """
    try:
        x = float(x)
    except (TypeError, ValueError):
        return "must be a real number"
    if not math.isfinite(x):
        return "must be a finite number"
    rng = RANGES.get(name)
    if rng is None:
        return "is not a settable Real variable"
    lo, hi, lo_open = rng
    if (x <= lo if lo_open else x < lo) or not x <= hi:
        return f"must lie in {'(' if lo_open else '['}{lo:g}, {hi:g}]"
    return None


def check_wall(x: int) -> Optional[str]:
    """Check the Integer parameter ``wall`` (mirrors ``model_check_integer``).

    Parameters
    ----------
    x : int
        Proposed wall model.

    Returns
    -------
    str or None
        ``None`` if acceptable, otherwise why not.
    """
    if isinstance(x, bool) or not isinstance(x, (int, np.integer)) or not (
        WALL_NONE <= int(x) <= WALL_RIGID
    ):
        return "must lie in [0, 2]"
    return None


class OscillatorModel:
    """Parameters, derived quantities and discrete state of the oscillator, and its wall law.

    Attributes mirror ``ModelData`` in ``fmu_src/model.h``.  Defaults are the C FMU's (the
    paper's Figure 9 case, started at rest at u = -1).
    """

    def __init__(self) -> None:
        self.nu: float = 4.605170185988091
        self.Omega: float = 0.3059238689620112
        self.sigma: float = 0.2
        self.r: float = 0.9
        self.Gamma: float = 10.0
        self.wall: int = WALL_COMPLIANT
        self.u0: float = -1.0
        self.v0: float = 0.0
        # Tight by default, as the C FMU: contacts 1e-9 deep are found at every phase.
        self.rtol: float = 1e-12
        self.atol: float = 1e-14
        # continuous state at the current local time, and discrete state
        self.u: float = self.u0
        self.v: float = self.v0
        self.mode: int = MODE_FREE
        self.impacts: int = 0
        self.update_derived()

    # -- parameters ------------------------------------------------------------------------
    def update_derived(self) -> None:
        """Recompute F_g, phi (eq (5)), kappa and the squared stiffnesses from the parameters."""
        self.Omega2 = self.Omega * self.Omega
        # (5): F_g = sqrt((Omega^2 - 4 pi^2)^2 + 4 pi^2 nu^2), phi = arccos((Omega^2-4 pi^2)/F_g)
        self.F_g = math.hypot(self.Omega2 - _FOUR_PI2, _TWO_PI * self.nu)
        self.phi = math.acos((self.Omega2 - _FOUR_PI2) / self.F_g) if self.F_g > 0.0 else 0.0
        self.kappa2 = self.Gamma * self.Omega2
        self.kappa = math.sqrt(abs(self.kappa2))
        # The amplitude is cached: the right-hand side runs thousands of times per period.
        self.amp = (1.0 + self.sigma) * self.F_g

    def set_real(self, name: str, x: float) -> None:
        """Set one Real parameter after checking it.

        Raises
        ------
        ModelError
            If the value is rejected; the message names the variable and the reason.
        """
        why = check_real(name, x)
        if why is not None:
            raise ModelError(f"{name} = {_fmt(x)} rejected: {why}")  # model.c's wording
        setattr(self, name, float(x))
        self.update_derived()

    def set_wall(self, x: int) -> None:
        """Set the wall model after checking it.

        Raises
        ------
        ModelError
            If ``x`` is not 0, 1 or 2.
        """
        why = check_wall(x)
        if why is not None:
            raise ModelError(f"wall = {x!r} rejected: {why}")
        self.wall = int(x)

    def check_all(self) -> None:
        """Check every parameter and their combinations (end of initialisation).

        Raises
        ------
        ModelError
            With the first problem found (mirrors ``model_check_consistency``).
        """
        for name in ("nu", "Omega", "sigma", "r", "Gamma", "u0", "v0", "rtol", "atol"):
            why = check_real(name, getattr(self, name))
            if why is not None:
                raise ModelError(f"{name} = {_fmt(getattr(self, name))} rejected: {why}")
        why = check_wall(self.wall)
        if why is not None:
            raise ModelError(f"wall = {self.wall!r} rejected: {why}")
        if self.wall == WALL_COMPLIANT and not self.Gamma > 0.0:
            raise ModelError(f"Gamma = {self.Gamma:g}: a compliant wall needs Gamma > 0")
        if self.wall == WALL_RIGID and (self.u0 > 0.0 or (self.u0 == 0.0 and self.v0 > 0.0)):
            raise ModelError(
                f"u0 = {self.u0:g}, v0 = {self.v0:g} starts inside the rigid wall at u_wall = 0 "
                "(need u0 < u_wall, or u0 = u_wall moving away from it)"
            )

    # -- physics ---------------------------------------------------------------------------
    def wall_force(self, tau: float) -> float:
        """Net force pushing into the wall at u = v = 0 (positive: pushes into the wall).

        Parameters
        ----------
        tau : float
            Local time (the integer origin drops out of the forcing phase).
        """
        return self.amp * math.cos(_TWO_PI * tau + self.phi) - self.Omega2

    def initialize_state(self, tau0: float) -> None:
        """Set the continuous and discrete state from (u0, v0) at local start time ``tau0``."""
        self.u, self.v = self.u0, self.v0
        self.impacts = 0
        self.mode = MODE_FREE
        if self.wall == WALL_COMPLIANT and (self.u0 > 0.0 or (self.u0 == 0.0 and self.v0 > 0.0)):
            # a start inside the wall is a state, not an entry: no jump
            self.mode = MODE_CONTACT
        elif (
            self.wall == WALL_RIGID
            and self.u0 == 0.0
            and self.v0 == 0.0
            and self.wall_force(tau0) > 0.0
        ):
            self.mode = MODE_STICK

    def make_rhs(self) -> Callable[[float, np.ndarray, np.ndarray], None]:
        """Return the CVODE right-hand side ``f(tau, y, yp)`` for the current parameters.

        The closure reads ``mode`` at every call (the mode changes at events, with a CVODE
        re-initialisation) but binds the parameters, which are fixed during a run except
        ``sigma``; a change of ``sigma`` rebuilds nothing because ``amp`` is read each call.
        """
        m = self
        cos = math.cos
        two_pi = _TWO_PI

        def rhs(tau: float, y: np.ndarray, yp: np.ndarray) -> None:
            mode = m.mode
            if mode == MODE_STICK:
                yp[0] = 0.0
                yp[1] = 0.0
                return
            u = y[0]
            v = y[1]
            k = m.Omega2 * (u + 1.0)
            if mode == MODE_CONTACT:
                k += m.kappa2 * u  # (40): the wall's spring
            yp[0] = v
            yp[1] = m.amp * cos(two_pi * tau + m.phi) - m.nu * v - k

        return rhs

    def make_jacobian(self) -> Callable[[float, np.ndarray, np.ndarray, np.ndarray], None]:
        """Return the analytic Jacobian ``J(tau, y, yp, JJ)`` (as ``model_jacobian``)."""
        m = self

        def jac(tau: float, y: np.ndarray, yp: np.ndarray, JJ: np.ndarray) -> None:
            if m.mode == MODE_STICK:
                JJ[:, :] = 0.0
                return
            JJ[0, 0] = 0.0
            JJ[0, 1] = 1.0
            JJ[1, 0] = -(m.Omega2 + (m.kappa2 if m.mode == MODE_CONTACT else 0.0))
            JJ[1, 1] = -m.nu

        return jac

    def make_indicators(self) -> Callable[[float, np.ndarray, np.ndarray], None]:
        """Return the event indicators ``g(tau, y, g)`` in the twin's sign convention.

        The C FMU changes CVODE's root directions with the mode; scikit-sundae fixes them when
        the solver is created.  So the twin keeps the directions fixed at (+1, -1) and flips
        the indicators' signs instead, which selects exactly the same roots:

        ====== ======================== ============================ =====================
        mode   C: g0 (direction)        twin: g0 (direction +1)      g1: C / twin (dir -1)
        ====== ======================== ============================ =====================
        FREE   u (+1, entering)         u                            v (-1) / v: max of u
        CONTACT u (-1, leaving)         -u                           v (+1) / -v: min of u
        STICK  a(tau) (-1, release)     -a(tau)                      1 / 1 (never)
        ====== ======================== ============================ =====================
        """
        m = self
        cos = math.cos
        two_pi = _TWO_PI

        def indicators(tau: float, y: np.ndarray, g: np.ndarray) -> None:
            if m.wall == WALL_NONE:
                g[0] = 1.0  # never crosses
                g[1] = 1.0
                return
            mode = m.mode
            if mode == MODE_FREE:
                g[0] = y[0]  # the wall u = 0
                # The grazing guard: a contact that enters and leaves within one solver step
                # leaves u < 0 at both step ends, but its turning point (v = 0) is bracketed.
                g[1] = y[1]
            elif mode == MODE_CONTACT:
                g[0] = -y[0]
                g[1] = -y[1]
            else:  # MODE_STICK: release when the wall force stops pushing
                g[0] = m.Omega2 - m.amp * cos(two_pi * tau + m.phi)
                g[1] = 1.0

        indicators.direction = [+1, -1]  # type: ignore[attr-defined]
        indicators.terminal = [True, True]  # type: ignore[attr-defined]
        return indicators

    def missed_crossing(self, u: float) -> bool:
        """True when, at a turning point with displacement ``u``, the wall indicator has the
        sign of the other side: a crossing pair was stepped over and must be located."""
        if self.wall == WALL_NONE:
            return False
        if self.mode == MODE_FREE:
            return u > 0.0
        if self.mode == MODE_CONTACT:
            return u < 0.0
        return False

    def release_now(self, tau: float) -> bool:
        """Leave STICK at once if the holding force has vanished (e.g. after sigma changed).

        Returns
        -------
        bool
            True if the mode changed.
        """
        if self.mode == MODE_STICK and self.wall_force(tau) <= 0.0:
            self.mode = MODE_FREE
            return True
        return False

    def event_update(self, tau: float, y: list[float]) -> None:
        """Apply the wall event (indicator g0) found at ``tau`` with state ``y`` (in place).

        Parameters
        ----------
        tau : float
            Local time of the event.
        y : list of float
            ``[u, v]`` just past the crossing; updated to the state after the event.
        """
        mode = self.mode
        if mode == MODE_FREE:
            # entering the wall at the root u = 0, v > 0
            if self.wall == WALL_COMPLIANT:
                self.impacts += 1
                y[0] = ON_WALL
                y[1] *= self.r  # footnote 2: the wall passes the mass on with v -> r v
                self.mode = MODE_CONTACT
            else:
                self._rigid_impact(tau, y)
        elif mode == MODE_CONTACT:
            y[0] = -ON_WALL  # leaving the compliant wall: no jump in v
            self.mode = MODE_FREE
        else:  # MODE_STICK: released
            y[0] = -ON_WALL
            y[1] = 0.0
            self.mode = MODE_FREE


    def _rigid_impact(self, tau: float, y: list[float]) -> None:
        """Impact on the rigid wall (11), with chatter ended by sticking.

        Differs from the C FMU (model.c) in the tail of chatter, on purpose.  The C FMU lets
        CVODE resolve every chattering impact until the rebound speed falls below
        ``STICK_VELOCITY``.  A flight that leaves the wall with speed s under a net force a
        rises only s^2/(2a) (1e-20 for s = 1e-9), far below CVODE's absolute tolerance: how
        many of those last impacts CVODE sees depends on its step sequence (in the test case
        the oracle counts 27, the C FMU 26, this code with the tail left to CVODE 18; before
        the C FMU restarted "a hair off the wall" it failed there).  The twin hands a flight
        to CVODE only while it rises more than ``CHATTER_RESOLVED_ATOL`` times ``atol``; below
        that it sums the rest of the chatter in closed form (flights under a constant force
        over the remaining ~1e-6 of time: each returns with the speed it left with, each
        impact multiplies it by r) until the rebound speed falls below ``STICK_VELOCITY``,
        every impact counted, and the mass sticks at once.  Its counts match the oracle's.

        Parameters
        ----------
        tau : float
            Local time of the impact.
        y : list of float
            ``[u, v]`` at the crossing; updated to the state after the impact.
        """
        vc = y[1]
        a = self.wall_force(tau)
        y[0] = -ON_WALL
        if vc <= 0.0:
            # A root of u with the mass not moving into the wall: round-off at u = 0 (it
            # should not happen with the closed-form tail below). Not an impact.
            if a > 0.0:
                y[0] = y[1] = 0.0
                self.mode = MODE_STICK
            return
        self.impacts += 1
        y[1] = -self.r * vc  # (11)
        if abs(y[1]) <= STICK_VELOCITY * max(1.0, vc) and a > 0.0:
            y[0] = y[1] = 0.0
            self.mode = MODE_STICK
            return
        s = -y[1]
        if a > 0.0 and self.r < 1.0 and s * s / (2.0 * a) <= CHATTER_RESOLVED_ATOL * self.atol:
            # impacts k = 1, 2, ...: incoming speed r^(k-1) s, rebound r^k s; the last one
            # leaves at most STICK_VELOCITY (s < 1 here, so the threshold is absolute)
            if self.r == 0.0 or self.r * s <= STICK_VELOCITY:
                k = 1
            else:
                k = max(1, math.ceil(math.log(STICK_VELOCITY / s) / math.log(self.r)))
                while k > 1 and self.r ** (k - 1) * s <= STICK_VELOCITY:
                    k -= 1
                while self.r**k * s > STICK_VELOCITY:
                    k += 1
            self.impacts += k
            y[0] = y[1] = 0.0
            self.mode = MODE_STICK


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
