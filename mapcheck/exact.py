"""Closed-form (piecewise-linear) solution of the impact oscillator: the independent truth.

Model (non-dimensional, forcing period 1; paper equations (3), (5), (40), (53)):

    u'' + nu u' + Omega^2 (u + 1) [+ kappa^2 u while in contact] = (1 + sigma) F_g cos(2 pi t + phi)

with F_g, phi from (5), so that p(t) = (1 + sigma) cos(2 pi t) - 1 (4) is the wall-free
periodic solution; it grazes u = 0 at t = n when sigma = 0.

Wall models (``wall=``):

``"none"``
    free oscillator (3).
``"compliant"``
    kappa^2 = Gamma Omega^2 acts for u > 0 (40).  On entering (u crossing 0 upward)
    v -> r v (footnote 2); no jump on leaving.  A start with u0 > 0, or u0 == 0 and
    v0 > 0, is taken to be inside the wall already (no jump applied at t0).
``"rigid"``
    at u = 0 with v > 0, v -> -r v (11).  Chatter (impacts accumulating in finite
    time) is ended by *sticking*: if the post-impact speed is below ``v_stick``
    (default 1e-9) and the net force F(t) - Omega^2 at u = v = 0 pushes into the
    wall (> 0), the mass is held at u = v = 0 until that force changes sign, which
    is computed in closed form.  The tiny impacts skipped this way change the state
    by O(v_stick).  A start with u0 > 0 is rejected; u0 == 0, v0 > 0 impacts at t0.

Between wall events the solution is exact: each regime is solved in closed form and its wall
crossings found without missing a contact only 1e-9 deep (:mod:`mapcheck.segments`); this
module strings the segments together across the wall events (impacts, entering and leaving the
compliant wall, sticking and release).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .linear import propagator_k2
from .segments import TWO_PI, Mode, Segment, first_crossing, forcing_amplitude_phase

__all__ = ["ExactOscillator", "forcing_amplitude_phase"]


@dataclass
class _State:
    t: float
    u: float
    v: float
    mode: str  # "out", "in" (compliant wall), "stuck" (rigid wall)
    t_release: float = math.inf


class ExactOscillator:
    """Exact solution of the (piecewise-linear) grazing-impact oscillator.

    Parameters
    ----------
    nu, Omega : float
        Damping and natural frequency of (3).
    sigma : float
        Reduced forcing amplitude (5): F = (1 + sigma) F_g.
    r : float
        Restitution coefficient: rigid wall v -> -r v (11); compliant wall v -> r v on
        entering (footnote 2).
    Gamma : float
        Wall stiffness ratio kappa^2 / Omega^2 (compliant wall only).
    wall : {"none", "compliant", "rigid"}
    v_stick : float
        Rigid wall only: post-impact speed below which, with the net force pushing
        into the wall, chatter is ended by sticking (see module docstring).
    F_ext, u_wall : float
        The FMU's ports, held constant: an external force on the right-hand side and the
        wall's position (contact for u > u_wall, the compliant spring acts on u - u_wall).
        They shift the equilibrium and the wall.  With c = u_wall + 1 - F_ext / Omega^2 > 0,
        u = u_wall + c y maps the problem exactly onto the port-free one in y with
        sigma' = (1 + sigma) / c - 1 (the equation is linear, the wall laws homogeneous), which
        is what is solved.  c <= 0 (the equilibrium at or beyond the wall) is not covered.
    """

    def __init__(self, nu: float, Omega: float, sigma: float, r: float = 0.9,
                 Gamma: float = 10.0, wall: str = "compliant", v_stick: float = 1e-9,
                 F_ext: float = 0.0, u_wall: float = 0.0):
        if wall not in ("none", "compliant", "rigid"):
            raise ValueError(f"wall must be 'none', 'compliant' or 'rigid', not {wall!r}")
        self.F_ext, self.u_wall = float(F_ext), float(u_wall)
        self._inner: ExactOscillator | None = None
        if self.F_ext != 0.0 or self.u_wall != 0.0:
            c = self.u_wall + 1.0 - self.F_ext / float(Omega) ** 2
            if not c > 0.0:
                raise ValueError(f"u_wall + 1 - F_ext/Omega^2 = {c:g}: the equilibrium is at or "
                                 "beyond the wall, not covered by the scaling")
            self._scale = c
            self._inner = ExactOscillator(nu, Omega, (1.0 + float(sigma)) / c - 1.0, r, Gamma,
                                          wall, v_stick / c)
        self.nu, self.Omega, self.sigma = float(nu), float(Omega), float(sigma)
        self.r, self.Gamma, self.wall, self.v_stick = float(r), float(Gamma), wall, float(v_stick)
        self.kappa = math.sqrt(self.Gamma) * self.Omega
        self.F_g, self.phi = forcing_amplitude_phase(self.nu, self.Omega)
        Om2 = self.Omega ** 2
        self._free = Mode(self.nu, self.Omega, self.sigma, Om2)
        self._legs: dict = {}
        self._wall = Mode(self.nu, self.Omega, self.sigma, Om2 * (1.0 + self.Gamma))

    # ------------------------------------------------------------------ helpers
    def wall_free_orbit(self, t) -> tuple[np.ndarray, np.ndarray]:
        """p(t) and p'(t) of (4), the wall-free periodic solution."""
        if self._inner is not None:
            p, dp = self._inner.wall_free_orbit(t)
            return self.u_wall + self._scale * p, self._scale * dp
        th = TWO_PI * np.mod(np.asarray(t, dtype=float), 1.0)
        return (1.0 + self.sigma) * np.cos(th) - 1.0, -TWO_PI * (1.0 + self.sigma) * np.sin(th)

    def net_wall_force(self, t) -> np.ndarray:
        """F(t) - Omega^2: the acceleration at u = v = 0 (> 0 pushes into the wall).

        With ports: F(t) + F_ext - Omega^2 (u_wall + 1), the acceleration on the wall at rest."""
        if self._inner is not None:
            return self._scale * self._inner.net_wall_force(t)
        th = TWO_PI * np.mod(np.asarray(t, dtype=float), 1.0)
        return self._free.force(th) - self.Omega ** 2

    def _release_time(self, t: float) -> float:
        """First time >= t at which F(t) - Omega^2 turns negative (rigid-wall sticking)."""
        c = self.Omega ** 2 / ((1.0 + self.sigma) * self.F_g)
        if c >= 1.0:
            return t  # the force can never push in
        if c <= -1.0:
            return math.inf
        # F - Omega^2 < 0 for phase th + phi in (arccos c, 2 pi - arccos c): release at arccos c
        s = (t - math.floor(t) + self.phi / TWO_PI) % 1.0
        s_r = math.acos(c) / TWO_PI
        dt = (s_r - s) % 1.0
        # at the release point itself rounding may put s just past s_r: release now,
        # not a period later (the force is decreasing through zero there)
        return t if dt > 1.0 - 1e-9 else t + dt

    def _initial_state(self, u0: float, v0: float, t0: float) -> tuple[_State, list]:
        events: list = []
        pushes_in = u0 == 0.0 and v0 == 0.0 and self.net_wall_force(t0) > 0.0
        if self.wall == "compliant" and (u0 > 0.0 or (u0 == 0.0 and v0 > 0.0) or pushes_in):
            return _State(t0, u0, v0, "in"), events
        if self.wall == "rigid":
            if u0 > 0.0:
                raise ValueError("rigid wall: u0 > 0 is inside the wall")
            if u0 == 0.0 and v0 > 0.0:
                st = _State(t0, 0.0, v0, "out")
                return self._impact(st, events), events
            if u0 == 0.0 and abs(v0) < self.v_stick and self.net_wall_force(t0) > 0.0:
                return _State(t0, 0.0, 0.0, "stuck", self._release_time(t0)), events
        return _State(t0, u0, v0, "out"), events

    def _impact(self, st: _State, events: list) -> _State:
        vr = -self.r * st.v
        events.append((st.t, "impact"))
        if abs(vr) < self.v_stick and self.net_wall_force(st.t) > 0.0:
            events.append((st.t, "stick"))
            return _State(st.t, 0.0, 0.0, "stuck", self._release_time(st.t))
        return _State(st.t, 0.0, vr, "out")

    def _advance(self, st: _State, T: float, events: list) -> _State:
        """Integrate from st to time T exactly, appending wall events."""
        while True:
            if st.mode == "stuck":
                if T < st.t_release:
                    return _State(T, 0.0, 0.0, "stuck", st.t_release)
                events.append((st.t_release, "release"))
                st = _State(st.t_release, 0.0, 0.0, "out")
                continue
            mode = self._wall if st.mode == "in" else self._free
            seg = Segment(mode, st.t, st.u, st.v)
            tau_end = T - st.t
            tau = None
            if self.wall != "none" and tau_end > 0.0:
                sgn = -1.0 if st.mode == "in" else 1.0
                tau = first_crossing(seg, sgn, tau_end)
            if tau is None:
                if tau_end <= 0.0:
                    return st
                u, v = seg.point_state(tau_end)
                return _State(T, u, v, st.mode)
            st = self._cross(st, seg, tau, events)

    def _cross(self, st: _State, seg: Segment, tau: float, events: list) -> _State:
        """The state just after the wall event found at st.t + tau on seg (appended to events)."""
        t_c = st.t + tau
        vc = seg.point_state(tau)[1]
        if self.wall == "rigid":
            return self._impact(_State(t_c, 0.0, vc, "out"), events)
        if st.mode == "in":
            events.append((t_c, "exit"))
            return _State(t_c, 0.0, vc, "out")
        events.append((t_c, "enter"))
        if self.r * vc == 0.0 and self.net_wall_force(t_c) <= 0.0:
            # r = 0: the entry leaves the mass on the wall at rest, and the net force pulls it
            # out at once: a contact of zero duration. (Left "in", its exit at tau = 0 would be
            # invisible to first_crossing, which ignores crossings in the first grid step of a
            # start at rest, and the wall's spring would act on u < 0.)
            events.append((t_c, "exit"))
            return _State(t_c, 0.0, 0.0, "out")
        return _State(t_c, 0.0, self.r * vc, "in")

    # ------------------------------------------------------------------ public API
    def _through_scaling(self, method, u0: float, v0: float, times,
                         t0: float) -> tuple[np.ndarray, np.ndarray]:
        """The ports by the exact scaling (see the class): ``method`` (strobe or dense) of the
        port-free oscillator from the scaled start, mapped back by u = u_wall + c y, v = c y'."""
        c = self._scale
        states, counts = method((u0 - self.u_wall) / c, v0 / c, times, t0)
        states = states * c
        states[:, 0] += self.u_wall
        return states, counts

    def strobe(self, u0: float, v0: float, times, t0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Exact states at the requested times.

        Parameters
        ----------
        u0, v0 : float
            State at ``t0``.
        times : array_like
            Sorted times, all >= t0.
        t0 : float

        Returns
        -------
        states : ndarray, shape (len(times), 2)
            Exact (u, v) at each time.
        impacts : ndarray of int, shape (len(times),)
            Cumulative wall entries since t0 (compliant: entries into u > 0; rigid:
            impacts, every chattering impact counted).
        """
        if self._inner is not None:
            return self._through_scaling(self._inner.strobe, u0, v0, times, t0)
        times = np.asarray(times, dtype=float).reshape(-1)
        if times.size and (times[0] < t0 or (times.size > 1 and np.any(np.diff(times) < 0))):
            raise ValueError("times must be sorted and >= t0")
        events: list = []
        st, events = self._initial_state(float(u0), float(v0), float(t0))
        states = np.empty((times.size, 2))
        counts = np.empty(times.size, dtype=int)
        n_seen, count = 0, 0
        for k, T in enumerate(times):
            st = self._advance(st, float(T), events)
            count += sum(1 for _, kind in events[n_seen:] if kind in ("enter", "impact"))
            n_seen = len(events)
            states[k] = st.u, st.v
            counts[k] = count
        return states, counts

    def dense(self, u0: float, v0: float, times, t0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Exact states at many sorted times, as :meth:`strobe`, but fast for dense grids.

        The crossings are searched once over [t0, times[-1]] and each smooth stretch between
        two wall events is evaluated at all of its times at once (the closed form anchored at
        the event, vectorised), so 10^4 communication points cost about one strobe call.
        A time equal to an event time gets the state after the event, as in strobe.

        Returns
        -------
        states : ndarray, shape (len(times), 2)
        impacts : ndarray of int, shape (len(times),)
            Cumulative wall entries/impacts since t0.
        """
        if self._inner is not None:
            return self._through_scaling(self._inner.dense, u0, v0, times, t0)
        times = np.asarray(times, dtype=float).reshape(-1)
        if times.size and (np.any(np.diff(times) < 0) or times[0] < t0):
            raise ValueError("times must be sorted and >= t0")
        events: list = []
        st, events = self._initial_state(float(u0), float(v0), float(t0))
        n = times.size
        states = np.empty((n, 2))
        counts = np.empty(n, dtype=int)
        t_last = float(times[-1]) if n else float(t0)
        i, count, n_seen = 0, 0, 0
        while i < n:
            count += sum(1 for _, kind in events[n_seen:] if kind in ("enter", "impact"))
            n_seen = len(events)
            if st.mode == "stuck":
                j = int(np.searchsorted(times, st.t_release, side="left"))
                states[i:j] = 0.0
                counts[i:j] = count
                i = j
                events.append((st.t_release, "release"))
                st = _State(st.t_release, 0.0, 0.0, "out")
                continue
            seg = Segment(self._wall if st.mode == "in" else self._free, st.t, st.u, st.v)
            tau = None
            if self.wall != "none" and t_last > st.t:
                tau = first_crossing(seg, -1.0 if st.mode == "in" else 1.0, t_last - st.t)
            j = n if tau is None else int(np.searchsorted(times, st.t + tau, side="left"))
            if j > i:
                u, v = seg.state(times[i:j] - st.t)
                states[i:j, 0], states[i:j, 1] = u, v
                counts[i:j] = count
                i = j
            if tau is not None:
                st = self._cross(st, seg, tau, events)
        return states, counts

    def crossings(self, u0: float, v0: float, t0: float, t1: float) -> list[tuple[float, str]]:
        """Wall events in [t0, t1], for diagnostics.

        Returns
        -------
        list of (t, kind)
            kind is "enter"/"exit" (compliant), "impact"/"stick"/"release" (rigid).
        """
        if self._inner is not None:
            return self._inner.crossings((u0 - self.u_wall) / self._scale, v0 / self._scale,
                                         t0, t1)
        st, events = self._initial_state(float(u0), float(v0), float(t0))
        self._advance(st, float(t1), events)
        return [(t, k) for t, k in events if t <= t1]

    def state_at(self, u0: float, v0: float, t0: float, t1: float) -> tuple[float, float, int]:
        """Convenience: exact (u, v) at t1 and the number of wall entries/impacts."""
        s, c = self.strobe(u0, v0, [t1], t0)
        return float(s[0, 0]), float(s[0, 1]), int(c[0])

    def _virtual_legs(self, n: int) -> tuple[np.ndarray, ...]:
        """P(-1/2), P(1/2) and p at n, n - 1/2, n + 1/2, n + 1 for :meth:`pre_impact_map`
        (kept per n: a Newton solve maps many points at one n)."""
        legs = self._legs
        if n not in legs:
            legs[n] = (propagator_k2(-0.5, self.nu, self.Omega ** 2),
                       propagator_k2(0.5, self.nu, self.Omega ** 2),
                       *(np.array(self.wall_free_orbit(t)) for t in (float(n), n - 0.5, n + 0.5, float(n + 1))))
        return legs[n]

    def pre_impact_map(self, u, v, n: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Exact counterpart of the near-grazing maps (31)/(32) (docs/theory.md section 3).

        The map's state is the pre-impact ("virtual") state at t = n: the orbit before
        its impact near n, continued to t = n as if there were no wall (figure 3).  So:
        free-propagate (u, v) back to n - 1/2, integrate exactly with the wall to
        n + 1/2, then free-propagate to n + 1 (8).

        Parameters
        ----------
        u, v : float or array_like
            Virtual states at t = n (looped over; each is independent).
        n : int

        Returns
        -------
        u1, v1 : ndarray
            Virtual state at t = n + 1.
        contacts : ndarray of int
            Wall entries/impacts in (n - 1/2, n + 1/2].
        """
        if self._inner is not None:
            raise NotImplementedError("pre_impact_map: the paper's maps have no ports")
        u, v = np.broadcast_arrays(np.asarray(u, dtype=float), np.asarray(v, dtype=float))
        shape = u.shape
        u, v = u.reshape(-1), v.reshape(-1)
        Pb, Pf, pn, pm, pp, p1 = self._virtual_legs(n)
        out_u, out_v = np.empty(u.size), np.empty(u.size)
        counts = np.empty(u.size, dtype=int)
        for k in range(u.size):
            z_half = Pb @ (np.array([u[k], v[k]]) - pn) + pm
            st, c = self.strobe(float(z_half[0]), float(z_half[1]), [n + 0.5], t0=n - 0.5)
            z1 = Pf @ (st[0] - pp) + p1
            out_u[k], out_v[k], counts[k] = z1[0], z1[1], c[0]
        return out_u.reshape(shape), out_v.reshape(shape), counts.reshape(shape)
