"""Sweep tasks and their execution on a worker.

Kept apart from :mod:`harness.sweeps` so that a worker process imports only what it needs
to run a task (numpy, the FMI layer), not xarray, matplotlib or Dask: worker start-up is
paid once per worker and per sweep.
"""
from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from .classify import classify_orbit, still_settling
from .config import SamplingSpec
from .fmi import INITIAL_STATE, FmuSource
from .sampling import sample_periods
from .simulator import simulator_for

RESULT_FIELDS = ("u", "v", "impacts", "t", "period", "orbit_impacts")


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
    }
    params = dict(task.params)
    state0 = task.state0
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
        if report is not None and i + 1 < k:  # the last point arrives with the result
            report(task.key, i + 1)
    # CPU seconds of this task on its worker: with the wall time this tells how much of
    # the machine a sweep really got (shared machines, oversubscribed clusters)
    out["cpu_s"] = np.array(time.process_time() - cpu_start)
    return out


# Progress channel of a process-pool worker, set by the pool's initializer.
_POOL_PROGRESS_QUEUE: Any = None


def init_pool_worker(progress_queue: Any, parent_pid: int | None = None) -> None:
    """Process-pool initializer: Ctrl-C is left to the parent (which stops the pool and keeps
    the checkpoint), per-point progress goes to ``progress_queue``, SIGTERM removes this
    worker's temporary folder and exits at once, and the worker dies with its parent."""
    import signal

    global _POOL_PROGRESS_QUEUE
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _exit_on_signal)
    _POOL_PROGRESS_QUEUE = progress_queue
    die_with_parent(parent_pid)


def _exit_on_signal(signum: int, frame: Any) -> None:
    # os._exit, not SystemExit: the pool's worker loop catches BaseException from a task and
    # would send it back as a result instead of exiting
    from . import tempdirs

    tempdirs.remove_now()
    os._exit(128 + signum)


def die_with_parent(parent_pid: int | None) -> bool:
    """Ask Linux to send this process SIGTERM when its parent dies, SIGKILL included
    (``prctl(PR_SET_PDEATHSIG)``); without it, workers of a killed sweep wait on their task
    queue as orphans for good.  Returns False where prctl is unavailable (not Linux).

    If the parent died before the request took effect, exit now.
    """
    import ctypes
    import signal

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(1, int(signal.SIGTERM), 0, 0, 0) != 0:  # 1 = PR_SET_PDEATHSIG
            return False
    except (OSError, AttributeError):
        return False
    if parent_pid is not None and os.getppid() != parent_pid:
        _exit_on_signal(int(signal.SIGTERM), None)
    return True


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
