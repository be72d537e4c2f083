"""Monolithic reference of the AFM loop: the oscillator in closed form plus the controller's law.

The coupled system (``examples/afm``): the ImpactOscillator (a cantilever, compliant wall = the
sample surface at ``u_wall``) and the AmplitudeController (``controller/controller.c``), which
samples u at the communication points t_k, takes max - min over windows
[theta + j T, theta + (j+1) T), and moves the wall by a PI law at each window end, holding it in
between.  The wall is therefore piecewise constant in time, and between its jumps the oscillator
is the paper's piecewise-linear ODE with the wall at u = w:

    u'' + nu u' + Omega^2 (u + 1) [+ kappa^2 (u - w) while u > w] = (1 + sigma) F_g cos(2 pi t + phi)

In y = u - w this is the wall-at-0 model with the constant term Omega^2 (1 + w) instead of
Omega^2, which ``mapcheck.exact`` solves in closed form once its modes' constant term is
shifted (``shifted_oscillator``).  So the reference is exact up to rounding: the closed form
from each sample to the next, and the controller's arithmetic repeated in Python double
precision, in the C code's order, so that the wall positions are the same numbers.

The schedule is the Jacobi one that ecos, fmpy's SSP loop and fmpy's Container FMU all use:
over [t_k, t_{k+1}] the oscillator sees the wall the controller output at t_k, and the
controller's step from t_k sees u(t_k).  Only the compliant wall is handled (a rigid wall's
sticking test in ``mapcheck.exact`` does not know about the shift).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mapcheck.exact import ExactOscillator


@dataclass
class Oscillator:
    """Parameters of the ImpactOscillator in the loop (compliant wall)."""

    nu: float = 0.5
    Omega: float = 7.368
    sigma: float = 0.5
    r: float = 0.9
    Gamma: float = 10.0


@dataclass
class Controller:
    """The AmplitudeController's parameters (names as in its modelDescription.xml)."""

    A_set: float = 2.5
    Kp: float = 0.1
    Ki: float = 0.3
    T: float = 1.0
    theta: float = 0.4
    u_wall_start: float = 0.0


@dataclass
class ControllerState:
    """The controller's memory, updated exactly as ``fmi2DoStep`` in controller.c does."""

    p: Controller
    t_start: float
    u_wall: float = 0.0
    amplitude: float = 0.0
    integral: float = 0.0
    windows: int = 0
    have_window: bool = False
    hi: float = -math.inf
    lo: float = math.inf

    def __post_init__(self) -> None:
        self.u_wall = self.p.u_wall_start

    def window_index(self, t: float) -> float:
        # the same expression as controller.c's window_index (floor((t - theta)/T + 1e-9))
        return math.floor((t - self.p.theta) / self.p.T + 1e-9)

    def step(self, t: float, h: float, u: float) -> bool:
        """One fmi2DoStep(t, h) with input u = u(t); True when the wall moved."""
        p = self.p
        k0, k1 = self.window_index(t), self.window_index(t + h)
        win_start = p.theta + k0 * p.T
        if not self.have_window and win_start >= self.t_start - 1e-9 * p.T:
            self.have_window, self.hi, self.lo = True, -math.inf, math.inf
        if self.have_window:
            self.hi, self.lo = max(self.hi, u), min(self.lo, u)
        if k1 > k0:
            moved = self.have_window
            if self.have_window:
                A = self.hi - self.lo
                e = A - p.A_set
                self.integral += e * p.T
                self.amplitude = A
                self.u_wall = p.u_wall_start - (p.Kp * e + p.Ki * self.integral)
                self.windows += 1
            self.have_window, self.hi, self.lo = True, -math.inf, math.inf
            return moved
        return False


def shifted_oscillator(osc: Oscillator, w: float) -> ExactOscillator:
    """Closed form of the oscillator with a fixed wall at u = w, in y = u - w.

    ``mapcheck.exact`` writes each mode's constant term as ``Om2`` (acceleration -Om2 at rest
    on the wall) and its static offset as ``c0 = -Om2/k2``; with the wall at w the constant
    term is Omega^2 (1 + w) in both modes (free and in contact), the stiffnesses unchanged.
    """
    ex = ExactOscillator(osc.nu, osc.Omega, osc.sigma, r=osc.r, Gamma=osc.Gamma, wall="compliant")
    const = osc.Omega ** 2 * (1.0 + w)
    for mode in (ex._free, ex._wall):
        mode.Om2 = const
        mode.c0 = -const / mode.k2
    return ex


@dataclass
class LoopResult:
    """Samples of the loop at the communication points t_k (after the step that ends there)."""

    t: np.ndarray
    u: np.ndarray
    v: np.ndarray
    u_wall: np.ndarray          # the controller's output at t_k
    amplitude: np.ndarray       # the controller's last measured amplitude at t_k
    updates: list = field(default_factory=list)  # (t, A, u_wall) at each window end


def grid(t0: float, h: float, n: int) -> np.ndarray:
    """Communication points t_k by summing t += h, as ecos and fmpy's SSP loop compute them
    (the Container FMU's t0 + k h differ by ulps, which neither the FMU's results nor the
    controller's window count, floor(... + 1e-9), notice)."""
    t = np.empty(n + 1)
    t[0] = x = t0
    for k in range(1, n + 1):
        x = x + h
        t[k] = x
    return t


def simulate(osc: Oscillator, ctrl: Controller, t0: float, t1: float, h: float,
             u0: float, v0: float, A_set_schedule=None, feedback: bool = True) -> LoopResult:
    """Run the loop exactly from (u0, v0) at t0 to t1 on the grid t += h.

    Parameters
    ----------
    A_set_schedule : callable or None
        ``A_set_schedule(t)`` gives the set-point for the controller step from t (a swept
        set-point); None keeps ``ctrl.A_set``.
    feedback : bool
        False: the controller's output is not fed back, the wall stays at u = 0 (an open loop:
        the controller only measures).

    Raises
    ------
    RuntimeError
        When the wall jumps onto the mass (u > w just before or after a jump): that case is the
        FMU's documented rule, not what this reference checks; windows end at phase theta, where
        the tip is far from the surface.
    """
    n = int(round((t1 - t0) / h))
    times = grid(t0, h, n)
    st = ControllerState(ctrl, t_start=t0)
    u_out, v_out = np.empty(n + 1), np.empty(n + 1)
    w_out, a_out = np.empty(n + 1), np.empty(n + 1)
    u_out[0], v_out[0], w_out[0], a_out[0] = u0, v0, st.u_wall, 0.0
    updates = []
    batch = int(math.ceil(ctrl.T / h)) + 2  # a hold never lasts longer than this many steps
    k = 0
    while k < n:
        # The wall stays at w from t_k until the controller moves it; the closed form gives
        # the oscillator at the next samples in one call, the controller eats them in order.
        w = st.u_wall if feedback else 0.0
        m = min(batch, n - k)
        y, _ = shifted_oscillator(osc, w).strobe(u_out[k] - w, v_out[k], times[k + 1:k + m + 1],
                                                t0=times[k])
        for i in range(m):
            j = k + i
            if A_set_schedule is not None:
                st.p = _with_set_point(st.p, A_set_schedule(times[j]))
            moved = st.step(times[j], h, u_out[j])
            # the oscillator's step [t_j, t_j+1] used w (Jacobi): its result stands
            u_out[j + 1], v_out[j + 1] = y[i, 0] + w, y[i, 1]
            w_out[j + 1], a_out[j + 1] = st.u_wall, st.amplitude
            if moved and feedback:
                if u_out[j + 1] > min(w, st.u_wall):
                    raise RuntimeError(f"the wall moved onto the mass at t = {times[j + 1]}")
                updates.append((times[j + 1], st.amplitude, st.u_wall))
                break
            if moved:
                updates.append((times[j + 1], st.amplitude, st.u_wall))
        k = j + 1
    return LoopResult(times, u_out, v_out, w_out, a_out, updates)


def _with_set_point(p: Controller, A_set: float) -> Controller:
    return Controller(A_set, p.Kp, p.Ki, p.T, p.theta, p.u_wall_start)
