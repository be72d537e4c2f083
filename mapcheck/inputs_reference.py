"""An independent event-driven reference for the FMU's *inputs*: ramped F_ext and u_wall, a
rigid wall moving at constant velocity with sticking and release, inputs held between ramps.

``mapcheck.exact`` solves the oscillator in closed form for constant ports; the FMU also takes
input derivatives (FMI 2.0 ``canInterpolateInputs``): within a step F_ext and u_wall are linear
in time, after it they hold their end values.  This module integrates that problem with scipy's
DOP853 at tight tolerances, locating every wall event with scipy's own event search, and applies
the paper's jump laws written out here (not taken from the FMU's model.c):

- compliant wall (spring kappa^2 = Gamma Omega^2 on u - w): entry v - w' -> r (v - w'), exit free;
- rigid wall: impact v - w' -> -r (v - w'), (11) in the wall's frame; with a rebound below
  ``v_stick`` while the net force pushes into the wall the mass *sticks*: u = w(t), v = w', until
  the net force (the wall being unaccelerated, the mass's own acceleration on the wall) falls to
  zero, when it is released with the wall's velocity.

Only r = 0 or impacts well above ``v_stick`` are meant here: chatter is the closed form's job.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

from mapcheck.exact import forcing_amplitude_phase

RTOL, ATOL = 1e-13, 1e-14


@dataclass(frozen=True)
class Piece:
    """Inputs on [t0, t1]: F_ext = F + dF (t - t0), u_wall = w + dw (t - t0)."""

    t0: float
    t1: float
    F: float = 0.0
    dF: float = 0.0
    w: float = 0.0
    dw: float = 0.0

    def wall(self, t: float) -> float:
        return self.w + self.dw * (t - self.t0)

    def force(self, t: float) -> float:
        return self.F + self.dF * (t - self.t0)


@dataclass
class RefState:
    """The reference's state: position, velocity, contact mode ("free", "inside", "stick"), and
    the impact bookkeeping the FMU reports (count, last entry time and relative velocity)."""

    t: float
    u: float
    v: float
    mode: str = "free"
    impacts: int = 0
    t_impact: float = 0.0
    v_impact: float = 0.0
    log: list = field(default_factory=list)


class InputsReference:
    """u'' + nu u' + Omega^2 (u + 1) [+ kappa^2 (u - w)] = (1 + sigma) F_g cos(2 pi t + phi) + F.

    Parameters
    ----------
    nu, Omega, sigma, r, Gamma : float
        The oscillator (as ``mapcheck.exact.ExactOscillator``).
    wall : str
        "none", "compliant" or "rigid".
    v_stick : float
        Rigid wall: a rebound slower than this (relative to the wall) sticks if pushed.
    """

    def __init__(self, nu: float, Omega: float, sigma: float, r: float = 0.9, Gamma: float = 10.0,
                 wall: str = "rigid", v_stick: float = 1e-9):
        self.nu, self.Om2, self.sigma, self.r = nu, Omega * Omega, sigma, r
        self.k2 = Gamma * Omega * Omega
        self.wall, self.v_stick = wall, v_stick
        self.F_g, self.phi = forcing_amplitude_phase(nu, Omega)

    def accel(self, t: float, u: float, v: float, p: Piece, inside: bool) -> float:
        a = ((1.0 + self.sigma) * self.F_g * math.cos(2.0 * math.pi * t + self.phi) - self.nu * v
             - self.Om2 * (u + 1.0) + p.force(t))
        return a - self.k2 * (u - p.wall(t)) if inside else a

    def push(self, t: float, p: Piece) -> float:
        """Net force on a mass riding the (unaccelerated) rigid wall: > 0 holds it there."""
        return self.accel(t, p.wall(t), p.dw, p, False)

    def run(self, st: RefState, p: Piece) -> RefState:
        """Advance ``st`` (at p.t0) over the piece; returns the state at p.t1 (``st`` is updated)."""
        while st.t < p.t1:
            if st.mode == "stick":
                self._stick(st, p)
                continue
            inside = st.mode == "inside"

            def g(t, y):
                return y[0] - p.wall(t)
            g.terminal, g.direction = True, (-1.0 if inside else 1.0)
            if self.wall == "none":
                g.terminal = False
            sol = solve_ivp(lambda t, y: [y[1], self.accel(t, y[0], y[1], p, inside)], (st.t, p.t1),
                            [st.u, st.v], method="DOP853", rtol=RTOL, atol=ATOL, events=g,
                            max_step=0.01)
            te = sol.t_events[0]
            if sol.status == 1 and te.size:
                st.t, (st.u, st.v) = float(te[0]), sol.y_events[0][0]
                self._event(st, p)
            else:
                st.t, (st.u, st.v) = p.t1, sol.y[:, -1]
        return st

    def _stick(self, st: RefState, p: Piece) -> None:
        ts = np.linspace(st.t, p.t1, max(3, int((p.t1 - st.t) * 2000)))
        f = np.array([self.push(t, p) for t in ts])
        below = np.nonzero(f <= 0.0)[0]
        if not below.size:
            st.t, st.u, st.v = p.t1, p.wall(p.t1), p.dw
            return
        k = int(below[0])
        lo, hi = (ts[k - 1], ts[k]) if k else (st.t, st.t)
        for _ in range(200):  # bisection of the release time to rounding
            mid = 0.5 * (lo + hi)
            if mid in (lo, hi):
                break
            lo, hi = (mid, hi) if self.push(mid, p) > 0.0 else (lo, mid)
        st.t, st.u, st.v, st.mode = hi, p.wall(hi), p.dw, "free"
        st.log.append((hi, "release"))
        # no step off the wall is needed: u - w starts at 0 and falls (-|a| t^2 / 2), which an
        # event search for an upward crossing does not stop at

    def _event(self, st: RefState, p: Piece) -> None:
        w, rel = p.wall(st.t), st.v - p.dw
        st.u = w
        if self.wall == "compliant":
            if st.mode == "free":
                st.impacts, st.t_impact, st.v_impact = st.impacts + 1, st.t, rel
                st.v, st.mode = p.dw + self.r * rel, "inside"
            else:
                st.mode = "free"
            st.log.append((st.t, "enter" if st.mode == "inside" else "exit"))
            return
        st.impacts, st.t_impact, st.v_impact = st.impacts + 1, st.t, rel
        st.v = p.dw - self.r * rel
        st.log.append((st.t, "impact"))
        if abs(st.v - p.dw) <= self.v_stick and self.push(st.t, p) > 0.0:
            st.v, st.mode = p.dw, "stick"
            st.log.append((st.t, "stick"))
