"""Sweep tasks and their execution on a worker.

Kept apart from :mod:`harness.runs.sweeps` so that a worker process imports only what it needs
to run a task (numpy, the FMI layer), not xarray, matplotlib or Dask: worker start-up is
paid once per worker and per sweep.
"""
from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ..io.children import _exit_on_signal, die_with_parent
from ..dynamics.maps.classify import classify_orbit, explain_dynamics, still_settling
from ..config import SamplingSpec
from ..config.defaults import WALLS
from ..fmu.fmi import INITIAL_STATE, FmuSource
from ..dynamics.maps.sampling import sample_periods
from ..fmu.simulator import has_derivatives, simulator_for

RESULT_FIELDS = ("u", "v", "impacts", "t", "period", "orbit_impacts", "dynamics", "dynamics_reason", "lyapunov",
                 "lyapunov_err")


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
    resume : (int, float, float, float), optional
        Resume an interrupted chain at this point from state (u, v) at time t.
    """

    key: str
    mode: str
    param: str
    values: tuple[float, ...]
    params: dict[str, Any] = field(hash=False)
    state0: tuple[float, float]
    sampling: SamplingSpec
    #: (first point, t, u, v): go on from a checkpointed chain (None: from the start)
    resume: tuple[int, float, float, float] | None = None


def execute(task: SweepTask, sim: Any, report: Callable[[str, int, dict], None] | None = None) -> dict[str, np.ndarray]:
    """Run ``task`` on simulator ``sim``; arrays indexed (point in ``task.values``, sample).

    ``report(key, points_done, row)`` is called after each point but the last (which
    arrives with the result), ``row`` holding that point's results as lists: a long
    continuation chain moves the progress bar while it runs, and the caller can checkpoint
    the chain point by point.  A task with :attr:`SweepTask.resume` starts at that point
    from the stored state; the rows before it are left for the caller to fill in.
    """
    cpu_start = time.process_time()
    s = task.sampling
    k, n = len(task.values), s.n_samples
    out = {
        "u": np.full((k, n), np.nan),
        "v": np.full((k, n), np.nan),
        "impacts": np.full((k, n), -1, dtype=np.int64),
        "t": np.full((k, n), np.nan),
        "period": np.full(k, -1, dtype=np.int64),
        "orbit_impacts": np.full(k, -1, dtype=np.int64),
        "dynamics": np.full(k, -1, dtype=np.int64),
        "dynamics_reason": np.full(k, -1, dtype=np.int64),
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


def _start_is_swept(task: SweepTask) -> bool:
    """True when the task's start state is one of the scan's axes (a basin scan): then a start
    inside the wall is a point of the grid, not a mistake in the settings."""
    return task.param in INITIAL_STATE or any(name in task.params for name in INITIAL_STATE)


def inside_rigid_wall(params: dict[str, Any], state: tuple[float, float]) -> bool:
    """A start the FMU refuses by its own rule: inside a rigid wall (u0 > u_wall), or on it
    moving into it.  Told apart here, before the FMU is asked, so that any other refusal at
    initialization (a bad setting) stays an error of the whole run."""
    wall = params.get("wall")
    if wall not in (WALLS["rigid"], "rigid"):
        return False
    u_wall = float(params.get("u_wall", 0.0))
    return state[0] > u_wall or (state[0] == u_wall and state[1] > 0.0)


def _run_points(task: SweepTask, sim: Any, params: dict[str, Any], state0: tuple[float, float], exact: bool,
                out: dict[str, np.ndarray], report: Callable[[str, int, dict], None] | None) -> None:
    s = task.sampling
    k = len(task.values)
    first = 0
    if task.resume is not None:
        # an interrupted chain goes on from the state after its last finished point: the
        # next value set at that (theta-aligned) time, as set_parameter would have done
        first, t_resume, u_resume, v_resume = task.resume
        params[task.param] = task.values[first]
        run_test_hook(task.key, first)
        sim.start(params, t_resume, (u_resume, v_resume))
    for i in range(first, k):
        value = task.values[i]
        if i == first and task.resume is None:
            run_test_hook(task.key, i)
            if task.param in INITIAL_STATE:  # sweeping the initial state (basin scans)
                state0 = (value, state0[1]) if task.param == INITIAL_STATE[0] else (state0[0], value)
            else:
                params[task.param] = value
            if _start_is_swept(task) and inside_rigid_wall(params, state0):
                continue  # an invalid point of a basin scan (period -1, the fill value); the scan goes on
            sim.start(params, s.theta, state0)
        elif i > first:
            run_test_hook(task.key, i)
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
            from ..dynamics.maps.lyapunov import lyapunov_continued

            ly = lyapunov_continued(sim, now, s.lyapunov, exact)
            out["lyapunov"][i], out["lyapunov_err"][i] = ly.exponents, ly.uncertainty
            lam, err = ly.largest, ly.largest_uncertainty
        out["dynamics"][i], out["dynamics_reason"][i] = explain_dynamics(orbit.period, settling, lam, err)
        if report is not None and i + 1 < k:  # the last point arrives with the result
            row = {name: out[name][i].tolist() for name in RESULT_FIELDS}
            u_end, v_end, _ = sim.read()
            row["end"] = [float(sim.time), float(u_end), float(v_end)]  # where a resumed chain goes on
            report(task.key, i + 1, row)


#: ``KEY:POINT:ACTION[:FILE]``: tests make an interruption land at a known point of a known
#: task instead of after a sleep (a sleep races the run).  Before point POINT of task KEY starts:
#: ``interrupt`` sends SIGINT to the process running the sweep (the pool's parent, or this
#: process), ``kill`` SIGKILLs this process once (FILE is created first and, if it already
#: exists, nothing happens), ``block`` creates FILE.reached and waits until FILE exists.
TEST_HOOK_ENV = "IMPACT_HARNESS_TEST_HOOK"


def run_test_hook(key: str, point: int) -> None:
    """The test hook of :data:`TEST_HOOK_ENV`, if set for this task and point (else nothing)."""
    spec = os.environ.get(TEST_HOOK_ENV)
    if not spec:
        return
    hook_key, hook_point, action, *rest = spec.split(":", 3)
    if hook_key != key or int(hook_point) != point:
        return
    import signal
    from pathlib import Path

    marker = Path(rest[0]) if rest else None
    if action == "interrupt":
        target = os.getppid() if _POOL_PROGRESS_QUEUE is not None or _IN_POOL else os.getpid()
        os.kill(target, signal.SIGINT)
        if target == os.getpid():
            time.sleep(1e-3)  # let the handler raise KeyboardInterrupt here, before the point
    elif action == "kill":
        if marker is None or not marker.exists():
            if marker is not None:
                marker.touch()
            os.kill(os.getpid(), signal.SIGKILL)
    elif action == "block" and marker is not None:
        Path(str(marker) + ".reached").touch()
        while not marker.exists():
            time.sleep(0.01)


# Progress channel of a process-pool worker, set by the pool's initializer.
_POOL_PROGRESS_QUEUE: Any = None
_IN_POOL = False


def init_pool_worker(progress_queue: Any, parent_pid: int | None = None) -> None:
    """Process-pool initializer: Ctrl-C is left to the parent (which stops the pool and keeps
    the checkpoint), per-point progress goes to ``progress_queue``, SIGTERM removes this
    worker's temporary folder and exits at once, and the worker dies with its parent."""
    import signal

    global _POOL_PROGRESS_QUEUE, _IN_POOL
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _exit_on_signal)
    _POOL_PROGRESS_QUEUE = progress_queue
    _IN_POOL = True
    die_with_parent(parent_pid)


def _reporter(progress: Any) -> Callable[[str, int], None] | None:
    if progress is None:
        return None
    if callable(progress):  # in-process
        return progress
    if progress == "pool":
        queue = _POOL_PROGRESS_QUEUE
        return None if queue is None else (lambda key, n, row: queue.put((key, n, row)))
    if isinstance(progress, str) and progress.startswith("dask:"):
        from distributed import get_worker

        worker, topic = get_worker(), progress[len("dask:"):]
        return lambda key, n, row: worker.log_event(topic, (key, n, row))
    return None


def run_task(task: SweepTask, source: Any, progress: Any = None) -> dict[str, np.ndarray]:
    """Worker entry point: this thread's FMU instance (or a user simulator) runs ``task``.

    ``progress`` selects the channel for per-point progress: a callable (in-process),
    ``"pool"`` (the process pool's queue) or ``"dask:<topic>"`` (a Dask event topic).
    """
    sim = simulator_for(source) if isinstance(source, FmuSource) else source
    return execute(task, sim, _reporter(progress))
