"""Stroboscopic sampling and plain time series.

The forcing is ``cos(2 pi t + phi)`` in absolute time, so the section at phase ``theta``
is the set of times ``t = n + theta``.  Runs start at a theta-aligned time ``t0 = k + theta``
and advance one period per step, so each sample is exactly at ``n + theta``.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from ...config import check_count, check_theta
from ...errors import HarnessInputError
from ...fmu.simulator import Simulator


@dataclass
class StrobeResult:
    """Samples of one run at ``t = n + theta``.

    Attributes
    ----------
    t : ndarray, shape (N,)
        Sample times.
    u, v : ndarray, shape (N,)
        State at the sample times.
    impacts : ndarray of int, shape (N,)
        Wall entries in the period that ends at each sample.
    """

    t: np.ndarray
    u: np.ndarray
    v: np.ndarray
    impacts: np.ndarray

    @property
    def final_state(self) -> tuple[float, float]:
        """(u, v) at the last sample (to carry a state on)."""
        return float(self.u[-1]), float(self.v[-1])


def sample_periods(sim: Simulator, n_transient: int, n_samples: int, progress: Any = None) -> StrobeResult:
    """From the simulator's current (theta-aligned) time: skip ``n_transient`` periods,
    then record ``n_samples`` periods.

    Parameters
    ----------
    sim : Simulator
        Started simulator; its current time is a section time.
    n_transient, n_samples : int
        Periods discarded, then periods sampled.
    progress : tqdm-like, optional
        ``update(1)`` is called once per period.
    """
    t_start = sim.time
    # Absolute times from the start time: no drift from accumulated additions.
    for k in range(1, n_transient + 1):
        sim.advance(t_start + k)
        if progress is not None:
            progress.update(1)
    _, _, n_prev = sim.read()
    t = np.empty(n_samples)
    u = np.empty(n_samples)
    v = np.empty(n_samples)
    imp = np.empty(n_samples, dtype=np.int64)
    for i in range(n_samples):
        t[i] = t_start + (n_transient + i + 1)  # integer first: t is the float nearest n + theta
        sim.advance(t[i])
        u[i], v[i], n = sim.read()
        imp[i] = n - n_prev
        n_prev = n
        if progress is not None:
            progress.update(1)
    return StrobeResult(t=t, u=u, v=v, impacts=imp)


def strobe(
    sim: Simulator,
    params: Mapping[str, Any],
    state0: tuple[float, float],
    theta: float = 0.0,
    n_transient: int = 100,
    n_samples: int = 40,
    start_period: int = 0,
    progress: Any = None,
) -> StrobeResult:
    """Stroboscopic samples at ``t = n + theta`` after a transient, from a fresh start.

    Parameters
    ----------
    sim : Simulator
        E.g. :class:`harness.fmu.simulator.FmuSimulator`; it is (re)started here.
    params : mapping
        FMU parameters (``u0``/``v0`` are taken from ``state0``).
    state0 : (float, float)
        (u, v) at the start time ``start_period + theta``.
    theta : float
        Section phase in [0, 1).
    n_transient, n_samples : int
        Periods discarded, then periods sampled (``n_samples >= 1``).

    Returns
    -------
    StrobeResult
        Samples at ``t = start_period + theta + n_transient + 1, ..., + n_samples``.
    """
    theta = check_theta(theta)
    n_transient = check_count(n_transient, "n_transient")
    n_samples = check_count(n_samples, "n_samples", minimum=1)
    sim.start(params, start_period + theta, state0)
    return sample_periods(sim, n_transient, n_samples, progress)


def simulate(
    sim: Simulator,
    params: Mapping[str, Any],
    state0: tuple[float, float],
    t0: float,
    t_end: float,
    dt: float,
    progress: Any = None,
) -> dict[str, np.ndarray]:
    """A plain time series (u, v, cumulative impacts) on a uniform grid from ``t0`` to ``t_end``."""
    if not dt > 0:
        raise HarnessInputError("dt", f"the output step must be > 0, got {dt}")
    if not t_end > t0:
        raise HarnessInputError("t_end", f"must be greater than the start time {t0}, got {t_end}")
    n = int(np.floor((t_end - t0) / dt + 1e-9))
    times = t0 + dt * np.arange(n + 1)
    sim.start(params, t0, state0)
    out = {k: np.empty(n + 1) for k in ("u", "v")}
    out["impacts"] = np.empty(n + 1, dtype=np.int64)
    for i, t in enumerate(times):
        if i:
            sim.advance(float(t))
            if progress is not None:
                progress.update(1)
        out["u"][i], out["v"][i], out["impacts"][i] = sim.read()
    out["t"] = times
    return out
