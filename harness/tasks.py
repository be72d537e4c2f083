"""Sweep tasks and their execution on a worker.

Kept apart from :mod:`harness.sweeps` so that a worker process imports only what it needs
to run a task (numpy, the FMI layer), not xarray, matplotlib or Dask: worker start-up is
paid once per worker and per sweep.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from .classify import classify_dynamics, classify_orbit, still_settling
from .config import SamplingSpec
from .fmi import INITIAL_STATE, FmuSource
from .sampling import sample_periods
from .simulator import has_derivatives, simulator_for

RESULT_FIELDS = ("u", "v", "impacts", "t", "period", "orbit_impacts", "dynamics", "lyapunov", "lyapunov_err")


@dataclass(frozen=True)
class SweepTask:
    """One unit of work: a fresh point or a continuation chain.

    Attributes
    ----------
    key : str
        Stable identifier (checkpoint file name, ordering).
    mode : str
        ``"fresh"``, ``"up"`` or ``"down"``.
    param : str
        Swept parameter.
    values : tuple of float
        One value (fresh) or the chain in the order it is run (continuation).
    params : dict
        All other FMU parameters (including the fixed second-axis value of a 2D scan).
    state0 : (float, float)
        Initial state at the first section time.
    sampling : SamplingSpec
    """

    key: str
    mode: str
    param: str
    values: tuple[float, ...]
    params: dict[str, Any] = field(hash=False)
    state0: tuple[float, float]
    sampling: SamplingSpec


def execute(task: SweepTask, sim: Any, report: Callable[[str, int], None] | None = None) -> dict[str, np.ndarray]:
    """Run ``task`` on simulator ``sim``; arrays indexed (point in ``task.values``, sample).

    ``report(key, points_done)`` is called after each point, so that a long continuation
    chain moves the progress bar while it runs.
    """
    cpu_start = time.process_time()
    s = task.sampling
    k, n = len(task.values), s.n_samples
    out = {
        "u": np.empty((k, n)),
        "v": np.empty((k, n)),
        "impacts": np.empty((k, n), dtype=np.int64),
        "t": np.empty((k, n)),
        "period": np.empty(k, dtype=np.int64),
        "orbit_impacts": np.empty(k, dtype=np.int64),
        "dynamics": np.empty(k, dtype=np.int64),
        "lyapunov": np.full((k, 2), np.nan),
        "lyapunov_err": np.full((k, 2), np.nan),
    }
    params = dict(task.params)
    state0 = task.state0
    exact = bool(s.lyapunov) and has_derivatives(sim)
    tracked_before = bool(getattr(sim, "tracking", False))
    if exact:
        sim.track_derivatives(True)  # the variational equations from the first start on
    try:
        _run_points(task, sim, params, state0, exact, out, report)
    finally:
        if has_derivatives(sim):  # the simulator is reused by the next task on this worker
            sim.track_derivatives(tracked_before)
    # CPU seconds of this task on its worker: with the wall time this tells how much of
    # the machine a sweep really got (shared machines, oversubscribed clusters)
    out["cpu_s"] = np.array(time.process_time() - cpu_start)
    return out


def _lyapunov_here(sim: Any, params: dict[str, Any], n_periods: int, exact: bool) -> Any:
    """Lyapunov exponents over the next ``n_periods`` periods from where ``sim`` stands; the
    run goes on from their end (a continuation carries that state)."""
    from .lyapunov import lyapunov_from_jacobians, orbit_jacobians, period_jacobians

    n0 = sim.read()[2]
    if exact:
        Js, _ = period_jacobians(sim, n_periods)
        return lyapunov_from_jacobians(Js, method="exact", impacts=sim.read()[2] - n0)
    # differences: the orbit first, then the Jacobians at its points by restarts, then a
    # restart at its end (equivalent: the state at a section time fixes the future)
    t0 = sim.time
    u0, v0, _ = sim.read()
    r = sample_periods(sim, 0, n_periods)
    impacts = int(r.impacts.sum())
    t = np.concatenate(([t0], r.t[:-1]))
    Js = orbit_jacobians(sim, params, t, np.concatenate(([u0], r.u[:-1])), np.concatenate(([v0], r.v[:-1])))
    sim.start(params, float(r.t[-1]), r.final_state)
    return lyapunov_from_jacobians(Js, method="fd", impacts=impacts)


def _run_points(task: SweepTask, sim: Any, params: dict[str, Any], state0: tuple[float, float], exact: bool,
                out: dict[str, np.ndarray], report: Callable[[str, int], None] | None) -> None:
    s = task.sampling
    k = len(task.values)
    for i, value in enumerate(task.values):
        if i == 0:
            if task.param in INITIAL_STATE:  # sweeping the initial state (basin scans)
                state0 = (value, state0[1]) if task.param == INITIAL_STATE[0] else (state0[0], value)
            else:
                params[task.param] = value
            sim.start(params, s.theta, state0)
        else:
            sim.set_parameter(task.param, value)
        r = sample_periods(sim, s.n_transient, s.n_samples)
        orbit = classify_orbit(r.u, r.v, r.impacts, s.tol, s.max_period)
        extra = 0
        # Near window edges orbits converge slowly (a multiplier near +-1): keep going, a
        # window of samples at a time, while allowed and not yet periodic, or periodic only
        # in appearance (an alternation still shrinking towards a shorter period).
        while (extra + s.n_samples <= s.extend
               and (not orbit.periodic or still_settling(r.u, r.v, orbit.period, s.tol))):
            r = sample_periods(sim, 0, s.n_samples)
            extra += s.n_samples
            orbit = classify_orbit(r.u, r.v, r.impacts, s.tol, s.max_period)
        out["u"][i], out["v"][i], out["impacts"][i], out["t"][i] = r.u, r.v, r.impacts, r.t
        out["period"][i], out["orbit_impacts"][i] = orbit.period, orbit.impacts
        settling = orbit.periodic and still_settling(r.u, r.v, orbit.period, s.tol)
        lam = err = float("nan")
        if s.lyapunov:
            now = dict(params) if task.param in INITIAL_STATE else {**params, task.param: value}
            ly = _lyapunov_here(sim, now, s.lyapunov, exact)
            out["lyapunov"][i], out["lyapunov_err"][i] = ly.exponents, ly.uncertainty
            lam, err = ly.largest, ly.largest_uncertainty
        out["dynamics"][i] = classify_dynamics(orbit.period, settling, lam, err)
        if report is not None and i + 1 < k:  # the last point arrives with the result
            report(task.key, i + 1)


# Progress channel of a process-pool worker, set by the pool's initializer.
_POOL_PROGRESS_QUEUE: Any = None


def init_pool_worker(progress_queue: Any) -> None:
    """Process-pool initializer: Ctrl-C is left to the parent (which stops the pool and keeps
    the checkpoint), and per-point progress goes to ``progress_queue``."""
    import signal

    global _POOL_PROGRESS_QUEUE
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _POOL_PROGRESS_QUEUE = progress_queue


def _reporter(progress: Any) -> Callable[[str, int], None] | None:
    if progress is None:
        return None
    if callable(progress):  # in-process
        return progress
    if progress == "pool":
        queue = _POOL_PROGRESS_QUEUE
        return None if queue is None else (lambda key, n: queue.put((key, n)))
    if isinstance(progress, str) and progress.startswith("dask:"):
        from distributed import get_worker

        worker, topic = get_worker(), progress[len("dask:"):]
        return lambda key, n: worker.log_event(topic, (key, n))
    return None


def run_task(task: SweepTask, source: Any, progress: Any = None) -> dict[str, np.ndarray]:
    """Worker entry point: this thread's FMU instance (or a user simulator) runs ``task``.

    ``progress`` selects the channel for per-point progress: a callable (in-process),
    ``"pool"`` (the process pool's queue) or ``"dask:<topic>"`` (a Dask event topic).
    """
    sim = simulator_for(source) if isinstance(source, FmuSource) else source
    return execute(task, sim, _reporter(progress))
