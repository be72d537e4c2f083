"""The oscillator's physics in Python (the pythonfmu twin): :class:`OscillatorModel`, the
counterpart of the C FMU's ``fmu_src/model.c`` -- parameters, derived quantities, the discrete
state and everything that happens at the wall (``make_rhs``, ``make_jacobian``,
``make_indicators``, ``event_update``, ``missed_crossing``, ``release_now``).  See
``impact_twin_model`` for the model's equation and what differs from the C FMU on purpose.
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np

from twin_rules import (_FOUR_PI2, _TWO_PI, CHATTER_RESOLVED_ATOL, MODE_CONTACT, MODE_FREE,
                        MODE_STICK, ON_WALL, STICK_VELOCITY, WALL_COMPLIANT, WALL_NONE,
                        WALL_RIGID, ModelError, _fmt, check_real, check_wall)


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
