"""Parameter sweeps and 2D scans: fresh starts and quasi-static continuation.

Two kinds of task:

* **fresh**: one point, started from the same initial state (embarrassingly parallel);
* **continuation** (``up`` / ``down``): one run through the whole grid of the swept
  parameter, changed between periods with the state carried on (through the FMU's tunable
  ``sigma``; a non-tunable parameter is changed by restarting from the current state).
  This is how the experiment and the paper's figures show hysteresis.  A single direction
  starts from the initial state at its first grid value.  With both directions the sweep
  is one hysteresis loop (task ``both``): up from the initial state, then down from the
  state where the up scan ended.

A chain reports each finished point; with a checkpoint those points are stored as they
come (``<key>.partial.npz``), so an interrupted chain resumes at its first missing point
from the stored state instead of starting over.

In a 2D scan the second parameter (e.g. Gamma) is fixed per task: fresh points cover the
grid, continuation runs one chain per value of the second parameter.

Tasks are plain data; :func:`run_task` executes one on whatever process it lands on, with
that process's reused FMU instance.
"""
from __future__ import annotations

import pickle
import time
from typing import Any, Mapping

import numpy as np
import xarray as xr

from .backends import Backend, make_backend
from .checkpoint import Checkpoint, fingerprint
from .sweep_collect import SweepCollector, SweepStats
from ..config import SamplingSpec, SweepSpec, sweep_directions
from ..errors import HarnessInputError
from ..fmu.fmi import INITIAL_STATE, FmuModel
from ..io.results import ORBIT_IMPACTS_ATTRS, PERIOD_ATTRS, provenance
from .tasks import RESULT_FIELDS, SweepTask, execute, run_task

__all__ = ["SweepStats", "SweepTask", "assemble", "execute", "plan_tasks", "run_sweep", "run_task"]

# ----------------------------------------------------------------------------------------
# Planning
# ----------------------------------------------------------------------------------------
def plan_tasks(spec: SweepSpec, params: Mapping[str, Any], state0: tuple[float, float],
               sampling: SamplingSpec) -> dict[str, SweepTask]:
    """All tasks of a sweep, keyed by a stable key."""
    if {spec.param, spec.scan_param} & set(INITIAL_STATE) and any(m != "fresh" for m in spec.modes):
        name = spec.param if spec.param in INITIAL_STATE else spec.scan_param
        raise HarnessInputError("spec.modes", f"the initial state {name!r} can only be swept with fresh starts")
    grid = np.sort(np.asarray(spec.values, dtype=float))
    scan = [None] if spec.scan_param is None else list(np.asarray(spec.scan_values, dtype=float))
    tasks: dict[str, SweepTask] = {}
    for j, second in enumerate(scan):
        base = dict(params)
        start = state0
        if second is not None:
            base[spec.scan_param] = float(second)  # also for u0/v0: it places the task on the grid
            if spec.scan_param in INITIAL_STATE:  # a basin scan: the second axis is part of the start
                start = (float(second), state0[1]) if spec.scan_param == INITIAL_STATE[0] else (state0[0], float(second))
        suffix = "" if second is None else f"-s{j:04d}"
        for mode in spec.modes:
            if mode == "fresh":
                for i, value in enumerate(grid):
                    key = f"fresh{suffix}-p{i:05d}"
                    tasks[key] = SweepTask(key, mode, spec.param, (float(value),), base, start, sampling)
            elif mode == LOOP:  # one task: up, then down from where up ended
                chain = np.concatenate([grid, grid[::-1]])
                key = f"{LOOP}{suffix}"
                tasks[key] = SweepTask(key, LOOP, spec.param, tuple(float(x) for x in chain), base, start, sampling)
            else:
                chain = grid if mode == "up" else grid[::-1]
                key = f"{mode}{suffix}"
                tasks[key] = SweepTask(key, mode, spec.param, tuple(float(x) for x in chain), base, start, sampling)
    return tasks


#: Mode of the task that runs a hysteresis loop: its first half is the up scan, its
#: second half the down scan from the state the up scan ended in.
LOOP = "both"


def task_rows(task: SweepTask) -> list[tuple[str, float]]:
    """(direction, value) of each row of a task's results."""
    if task.mode != LOOP:
        return [(task.mode, v) for v in task.values]
    half = len(task.values) // 2
    return [("up" if i < half else "down", v) for i, v in enumerate(task.values)]


def sweep_identity(spec: SweepSpec, params: Mapping[str, Any], state0: tuple[float, float],
                   sampling: SamplingSpec, fmu_sha256: str) -> dict[str, Any]:
    """What a sweep's results depend on (the checkpoint's manifest keeps it, to say what changed)."""
    return {
        "tasks": 2,  # 2: up+down as one loop task, chains checkpointed per point
        "fmu": fmu_sha256,
        "params": dict(params),
        "state0": list(state0),
        "sampling": sampling.__dict__,
        "param": spec.param,
        "values": np.sort(np.asarray(spec.values, dtype=float)),
        "modes": list(spec.modes),
        "scan_param": spec.scan_param,
        "scan_values": None if spec.scan_values is None else np.asarray(spec.scan_values, dtype=float),
    }


# ----------------------------------------------------------------------------------------
# Assembly
# ----------------------------------------------------------------------------------------
def assemble(spec: SweepSpec, tasks: Mapping[str, SweepTask], results: Mapping[str, Mapping[str, np.ndarray]],
             sampling: SamplingSpec, attrs: Mapping[str, Any]) -> xr.Dataset:
    """Put task results on the grid: dims (direction, param[, scan_param], sample)."""
    grid = np.sort(np.asarray(spec.values, dtype=float))
    directions = sweep_directions(spec.modes)
    dims = ["direction", spec.param]
    coords: dict[str, Any] = {"direction": directions, spec.param: grid}
    shape = [len(directions), len(grid)]
    scan = None
    if spec.scan_param is not None:
        scan = np.asarray(spec.scan_values, dtype=float)
        dims.append(spec.scan_param)
        coords[spec.scan_param] = scan
        shape.append(len(scan))
    n = sampling.n_samples
    coords["sample"] = np.arange(n)
    arrays = {
        "u": np.full(shape + [n], np.nan),
        "v": np.full(shape + [n], np.nan),
        "t": np.full(shape + [n], np.nan),
        "impacts": np.full(shape + [n], -1, dtype=np.int64),
        "period": np.full(shape, -1, dtype=np.int64),
        "orbit_impacts": np.full(shape, -1, dtype=np.int64),
        "dynamics": np.full(shape, -1, dtype=np.int64),
        "dynamics_reason": np.full(shape, -1, dtype=np.int64),
        "lyapunov": np.full(shape + [2], np.nan),
        "lyapunov_err": np.full(shape + [2], np.nan),
    }
    index_of_value = {float(x): i for i, x in enumerate(grid)}
    for key, task in tasks.items():
        res = results[key]
        j = None
        if scan is not None:
            j = int(np.flatnonzero(scan == float(task.params[spec.scan_param]))[0])
        for row, (direction, value) in enumerate(task_rows(task)):
            d = directions.index(direction)
            idx = (d, index_of_value[value]) if j is None else (d, index_of_value[value], j)
            for name in RESULT_FIELDS:
                if name in res:  # a checkpoint written before a field existed lacks it
                    arrays[name][idx] = res[name][row]
    sample_dims = dims + ["sample"]
    ds = xr.Dataset(
        {
            "u": (sample_dims, arrays["u"], {"long_name": "displacement at t = n + theta"}),
            "v": (sample_dims, arrays["v"], {"long_name": "velocity at t = n + theta"}),
            "impacts": (sample_dims, arrays["impacts"], {"long_name": "wall entries in the period ending at the sample"}),
            "t": (sample_dims, arrays["t"], {"long_name": "absolute sample time"}),
            "period": (dims, arrays["period"], PERIOD_ATTRS),
            "orbit_impacts": (dims, arrays["orbit_impacts"], ORBIT_IMPACTS_ATTRS),
        },
        coords=coords,
        attrs=dict(attrs),
    )
    from ..dynamics.maps.classify import dynamics_attrs, reason_attrs

    ds["dynamics"] = (dims, arrays["dynamics"], dynamics_attrs())
    ds["dynamics_reason"] = (dims, arrays["dynamics_reason"], reason_attrs())
    if sampling.lyapunov:
        ds = ds.assign_coords(exponent=[1, 2])
        ds["lyapunov"] = (dims + ["exponent"], arrays["lyapunov"], {
            "long_name": "Lyapunov exponents of the stroboscopic map", "units": "1/forcing period",
            "comment": f"QR method over {sampling.lyapunov} periods after the samples, natural log"})
        ds["lyapunov_err"] = (dims + ["exponent"], arrays["lyapunov_err"], {
            "long_name": "standard error of the Lyapunov exponents (batch means of 10 blocks)",
            "units": "1/forcing period"})
    ds[spec.param].attrs["long_name"] = f"swept FMU parameter {spec.param}"
    ds["direction"].attrs["long_name"] = ("fresh: every point from the same state; up/down: continuation "
                                          "(with both, down starts where up ended)")
    return ds


# ----------------------------------------------------------------------------------------
# Driver
def _open_checkpoint(directory: str, spec: SweepSpec, base: Mapping[str, Any], state0: tuple[float, float],
                     sampling: SamplingSpec, sha: str) -> Checkpoint:
    """The checkpoint of this sweep in ``directory``, tied to everything that determines its results."""
    identity = sweep_identity(spec, base, state0, sampling, sha)
    return Checkpoint(directory, fingerprint(identity), identity=identity)


# ----------------------------------------------------------------------------------------
def run_sweep(
    fmu: FmuModel | str | Any,
    spec: SweepSpec,
    params: Mapping[str, Any] | None = None,
    state0: tuple[float, float] = (-1.0, 0.0),
    sampling: SamplingSpec | None = None,
    backend: Any = None,
    workers: int | None = None,
    scheduler: str | None = None,
    checkpoint: str | None = None,
    progress: bool = True,
    settings: Mapping[str, Any] | None = None,
    stats: SweepStats | None = None,
) -> xr.Dataset:
    """Run a sweep (or 2D scan) and return its Dataset.

    Parameters
    ----------
    fmu : FmuModel, path, or simulator
        The FMU to drive, or a picklable simulator object (e.g.
        :class:`~harness.fmu.simulator.MappingSimulator`) used as it is on each worker.
    spec : SweepSpec
        Swept parameter, grid, modes (and second axis).
    params : mapping, optional
        FMU parameters (default: the FMU's start values).
    state0 : (float, float)
        Initial (u, v) at the first section time.
    sampling : SamplingSpec, optional
        Section phase, transient, sampled periods, tolerance.
    backend : str, Backend or distributed.Client, optional
        See :func:`harness.runs.backends.make_backend`; default: local process pool.
    workers : int, optional
        Local processes (default: all usable cores).
    scheduler : str, optional
        Dask scheduler address (selects the Dask backend).
    checkpoint : path, optional
        Directory of finished tasks; a rerun with the same settings resumes from it.
    progress : bool
        Show a tqdm progress bar (per finished point).
    settings : mapping, optional
        Extra settings to record in the attributes.
    stats : SweepStats, optional
        Filled with counts of computed / resumed tasks and the wall time.

    Returns
    -------
    xarray.Dataset
        Variables u, v, impacts, t (direction, param[, scan], sample); period,
        orbit_impacts and dynamics (direction, param[, scan]: periodic, quasi-periodic,
        chaotic, not converged, unclassified, see :func:`harness.classify_dynamics`); with
        ``sampling.lyapunov`` also lyapunov and lyapunov_err (direction, param[, scan],
        exponent): both exponents of the stroboscopic map and their standard errors;
        attributes with the full provenance.
    """
    t_start = time.perf_counter()
    sampling = sampling or SamplingSpec()  # checked on creation
    model, base, source, sha = _resolve_fmu(fmu, spec, params)
    tasks = plan_tasks(spec, base, state0, sampling)
    store = None if checkpoint is None else _open_checkpoint(checkpoint, spec, base, state0, sampling, sha)
    stats = stats if stats is not None else SweepStats()
    collect = SweepCollector(tasks, store, stats)
    be, source = _open_backend(backend, workers, scheduler, model, source)
    collect.open_bar(f"sweep {spec.param}", progress)
    try:
        # reports drive the progress bar and the checkpoint inside chains
        be.run(run_task, collect.todo, source, collect.on_result,
               collect.on_progress if (progress or store is not None) else None)
        description = be.describe()
    except KeyboardInterrupt:
        collect.count_kept_on_disk()  # the message then says what a rerun will find
        raise
    finally:
        collect.bar.close()
        if backend is None or isinstance(backend, str):
            be.close()  # a backend or client passed in stays open for the caller
    stats.wall_time = time.perf_counter() - t_start
    record = _sweep_record(spec, sampling, state0, base, settings, stats, collect)
    attrs = provenance(record, model=model, backend=description, wall_time=stats.wall_time)
    return assemble(spec, tasks, collect.results, sampling, attrs)


def _resolve_fmu(fmu: FmuModel | str | Any, spec: SweepSpec,
                 params: Mapping[str, Any] | None) -> tuple[FmuModel | None, dict[str, Any], Any, str]:
    """(model or None, the FMU parameters of every task, what the workers open, the FMU's
    identity for checkpoints) of an FMU given as a path, an FmuModel or a simulator."""
    model: FmuModel | None = None
    if isinstance(fmu, (str,)) or hasattr(fmu, "__fspath__"):
        model = FmuModel(fmu)
    elif isinstance(fmu, FmuModel):
        model = fmu
    if model is None:
        return None, dict(params or {}), fmu, f"simulator:{type(fmu).__name__}"
    model.check_settable(spec.param, "spec.param")
    if spec.scan_param is not None:
        model.check_settable(spec.scan_param, "spec.scan_param")
    base = model.defaults()
    for name, value in (params or {}).items():
        base[name] = model.coerce(name, value, name)
    for name in INITIAL_STATE:
        base.pop(name, None)
    return model, base, model.source(), model.sha256


def _open_backend(backend: Any, workers: int | None, scheduler: str | None, model: FmuModel | None,
                  source: Any) -> tuple[Backend, Any]:
    """The backend, and the FMU source as its workers need it."""
    be: Backend = make_backend(backend, workers, scheduler)
    if model is None and be.name != "serial":
        try:  # a user simulator travels to the workers by pickle
            pickle.dumps(source)
        except Exception as exc:
            if backend is None or isinstance(backend, str):
                be.close()
            raise HarnessInputError(
                "backend", f"the simulator cannot be sent to {be.name} workers ({exc}); "
                "define its map at module level or use backend='serial'") from None
    if be.name == "dask" and model is not None:
        source = model.source(embed=True)  # remote workers may not share the file system
    return be, source


def _sweep_record(spec: SweepSpec, sampling: SamplingSpec, state0: tuple[float, float], base: Mapping[str, Any],
                  settings: Mapping[str, Any] | None, stats: SweepStats, collect: SweepCollector) -> dict[str, Any]:
    """The settings and counts a sweep's Dataset records in its attributes."""
    return {
        # the caller's record first: the values actually used below win over it
        **dict(settings or {}),
        "sweep.param": spec.param,
        "sweep.values": np.sort(np.asarray(spec.values, dtype=float)),
        "sweep.modes": ",".join(spec.modes),
        "sweep.scan_param": spec.scan_param,
        "sweep.scan_values": spec.scan_values,
        "sampling.theta": sampling.theta,
        "sampling.transient": sampling.n_transient,
        "sampling.samples": sampling.n_samples,
        "sampling.tol": sampling.tol,
        "sampling.max_period": sampling.max_period,
        "sampling.extend": sampling.extend,
        "sampling.lyapunov": sampling.lyapunov,
        "initial.u0": state0[0],
        "initial.v0": state0[1],
        # the swept parameters are coordinates: their FMU defaults would be stale attributes
        **{f"model.{k}": v for k, v in base.items() if k not in (spec.param, spec.scan_param)},
        "tasks_computed": stats.computed,
        "tasks_resumed": stats.resumed,
        # CPU seconds of the tasks computed in this run, summed over workers
        "tasks_cpu_time_s": float(sum(float(collect.results[k].get("cpu_s", 0.0)) for k in collect.todo)),
    }
