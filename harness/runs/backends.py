"""Execution backends: in-process, a local process pool, a Dask cluster.

A backend runs ``func(task, source)`` for every task and hands each result to a callback
as soon as it arrives (so results can be checkpointed and progress shown).  The tasks are
pure functions of their inputs and every worker resets its FMU instance before each task,
so the results do not depend on the backend, the number of workers or the order of
completion.

Fault tolerance:

* process pool: if a worker process dies, the pool breaks; the backend starts a new pool
  and resubmits the tasks that had not returned (results already delivered are kept);
* Dask: the scheduler reruns the tasks of a lost worker on the others by itself.
"""
from __future__ import annotations

import multiprocessing
import os
import threading
import time
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from typing import Any, Callable, Hashable, Mapping, Protocol

from ..errors import FmuError, HarnessInputError, SweepTaskError

ResultCallback = Callable[[Hashable, Any], None]


def _task_result(key: Hashable, get: Callable[[], Any], where: str) -> Any:
    """The result of one task; an unexpected failure is re-raised naming the task.

    Bad input and FMU failures pass unchanged (they already say what went wrong); anything
    else (a worker without the package, a crash in the harness) becomes
    :class:`SweepTaskError`.
    """
    try:
        return get()
    except (HarnessInputError, FmuError, BrokenProcessPool, KeyboardInterrupt):
        raise
    except Exception as exc:
        raise SweepTaskError(f"task {key} failed {where}: {type(exc).__name__}: {exc}") from exc
#: ``on_progress(key, points_done, row)``: a task reports how far it got and the results of
#: the point it just finished (long chains: progress bar and checkpoint inside the chain).
ProgressCallback = Callable[[Hashable, int], None]


class Backend(Protocol):
    """What the sweep code needs from a backend."""

    name: str

    def run(self, func: Callable, tasks: Mapping[Hashable, Any], source: Any, on_result: ResultCallback,
            on_progress: ProgressCallback | None = None) -> None:
        """Run ``func(task, source, progress=...)`` for each task; call ``on_result(key, result)``
        as they finish and ``on_progress(key, points_done, row)`` as tasks report."""

    def describe(self) -> str:
        """One line for the results' attributes (backend, workers, address)."""

    def close(self) -> None: ...


class SerialBackend:
    """Everything in the calling process (debugging, tiny runs, unpicklable mappings)."""

    name = "serial"

    def run(self, func: Callable, tasks: Mapping[Hashable, Any], source: Any, on_result: ResultCallback,
            on_progress: ProgressCallback | None = None) -> None:
        for key, task in tasks.items():
            on_result(key, _task_result(key, lambda: func(task, source, progress=on_progress), "in this process"))

    def describe(self) -> str:
        return "serial (1 process)"

    def close(self) -> None:
        pass


class ProcessBackend:
    """A pool of local worker processes (the default; one per core).

    Parameters
    ----------
    workers : int
        Number of processes.
    max_restarts : int
        How many times a broken pool (a worker died) is replaced before giving up.
    """

    name = "processes"

    def __init__(self, workers: int, max_restarts: int = 3) -> None:
        if workers < 1:
            raise HarnessInputError("workers", f"must be >= 1, got {workers}")
        self.workers = int(workers)
        self.max_restarts = max_restarts
        self.restarts = 0
        self._pool: ProcessPoolExecutor | None = None

    def _new_pool(self) -> ProcessPoolExecutor:
        from ..io.main_guard import require_main_guard
        from .tasks import init_pool_worker

        require_main_guard("backend")  # before any worker re-imports an unguarded script
        # spawn, not fork: the parent may hold loaded FMU libraries and helper threads
        # (tqdm's monitor, Dask), which a forked child must not inherit.
        ctx = multiprocessing.get_context("spawn")
        self._queue = ctx.Queue()
        return ProcessPoolExecutor(self.workers, mp_context=ctx, initializer=init_pool_worker,
                                   initargs=(self._queue, os.getpid()))

    def _drain(self, on_progress: ProgressCallback, stop: threading.Event) -> None:
        """Forward the workers' progress reports to ``on_progress`` (a helper thread)."""
        import queue as _queue

        while not stop.is_set():
            try:
                item = self._queue.get(timeout=0.2)
            except (_queue.Empty, OSError, EOFError, ValueError):
                continue
            on_progress(*item)

    def run(self, func: Callable, tasks: Mapping[Hashable, Any], source: Any, on_result: ResultCallback,
            on_progress: ProgressCallback | None = None) -> None:
        stop = threading.Event()
        try:
            self._run(func, tasks, source, on_result, on_progress, stop)
        finally:
            stop.set()

    def _run(self, func: Callable, tasks: Mapping[Hashable, Any], source: Any, on_result: ResultCallback,
             on_progress: ProgressCallback | None, stop: threading.Event) -> None:
        pending = dict(tasks)
        while pending:
            if self._pool is None:
                self._pool = self._new_pool()
                if on_progress is not None:
                    threading.Thread(target=self._drain, args=(on_progress, stop), daemon=True).start()
            mode = "pool" if on_progress is not None else None
            futures = {self._pool.submit(func, task, source, progress=mode): key for key, task in pending.items()}
            try:
                not_done = set(futures)
                while not_done:
                    done, not_done = wait(not_done, return_when=FIRST_COMPLETED)
                    for fut in done:
                        key = futures[fut]
                        # re-raises task errors and BrokenProcessPool
                        result = _task_result(key, fut.result, "in a worker process")
                        del pending[key]
                        on_result(key, result)
            except BrokenProcessPool:
                # A worker died (killed, out of memory): keep what was delivered, rerun the rest.
                self._shutdown(cancel=True)
                self.restarts += 1
                if self.restarts > self.max_restarts:
                    raise
            except BaseException:
                # Interrupted or a task failed: do not wait for running tasks (a continuation
                # chain may run for minutes); finished results are already delivered.
                self._kill_workers()
                self._shutdown(cancel=True)
                raise

    def _kill_workers(self) -> None:
        processes = getattr(self._pool, "_processes", None) or {}
        for proc in list(processes.values()):
            if proc.is_alive():
                proc.terminate()

    def _shutdown(self, cancel: bool) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=not cancel, cancel_futures=cancel)
            self._pool = None

    def describe(self) -> str:
        return f"processes ({self.workers} local worker process{'es' if self.workers != 1 else ''})"

    def close(self) -> None:
        self._shutdown(cancel=False)


class DaskBackend:
    """A Dask ``distributed`` cluster, given by scheduler address or an existing ``Client``.

    The FMU's bytes are scattered once to the workers, so workers on other hosts need
    neither the file nor a shared file system, only this package installed.
    """

    name = "dask"

    def __init__(self, client_or_address: Any) -> None:
        from distributed import Client

        if isinstance(client_or_address, Client):
            self.client = client_or_address
            self._owns_client = False
        else:
            address = str(client_or_address)
            try:
                self.client = Client(address, timeout="10s")
            except (OSError, TimeoutError) as exc:
                raise HarnessInputError("scheduler", f"cannot connect to the Dask scheduler at {address}: {exc}") from None
            self._owns_client = True

    @property
    def address(self) -> str:
        """The scheduler's address."""
        return str(self.client.scheduler.address)

    def run(self, func: Callable, tasks: Mapping[Hashable, Any], source: Any, on_result: ResultCallback,
            on_progress: ProgressCallback | None = None) -> None:
        from distributed import as_completed

        if not tasks:
            return
        remote_source = self.client.scatter(source, broadcast=True, hash=False)
        # Unique keys per run: a rerun of the same sweep must not pick up stale results.
        stamp = f"{time.time_ns():x}"
        topic = f"impact-harness-progress-{stamp}"
        if on_progress is not None:
            # workers log (key, points done) events on this topic; the client forwards them
            self.client.subscribe_topic(topic, lambda event: on_progress(*event[1]))
        keys = list(tasks)
        futures = self.client.map(
            func,
            [tasks[k] for k in keys],
            source=remote_source,
            progress=f"dask:{topic}" if on_progress is not None else None,
            key=[f"impact-harness-{stamp}-{i}" for i in range(len(keys))],
            pure=False,
        )
        by_future = {f.key: k for f, k in zip(futures, keys)}
        try:
            for fut in as_completed(futures):
                key = by_future[fut.key]
                on_result(key, _task_result(key, fut.result, "on a Dask worker"))
        finally:
            self.client.cancel(futures)
            if on_progress is not None:
                self.client.unsubscribe_topic(topic)

    def n_workers(self) -> int:
        """Workers connected to the scheduler now."""
        return len(self.client.scheduler_info().get("workers", {}))

    def describe(self) -> str:
        return f"dask (scheduler {self.address}, {self.n_workers()} workers at start)"

    def close(self) -> None:
        if self._owns_client:
            self.client.close()


def make_backend(backend: Any = None, workers: int | None = None, scheduler: str | None = None) -> Backend:
    """Build a backend from a name, a Dask ``Client``, a scheduler address or a backend.

    Parameters
    ----------
    backend : str, Client, Backend or None
        ``"serial"``, ``"processes"``, ``"dask"``, an existing backend, or a Dask client.
        ``None``: ``"dask"`` if ``scheduler`` is given, else ``"processes"``.
    workers : int, optional
        Processes for the local pool (default: all usable cores).
    scheduler : str, optional
        ``tcp://HOST:PORT`` of a Dask scheduler.
    """
    from ..config import default_workers

    if backend is not None and not isinstance(backend, str):
        if hasattr(backend, "run") and hasattr(backend, "describe"):
            return backend
        return DaskBackend(backend)  # assume a distributed.Client
    name = backend or ("dask" if scheduler else "processes")
    if name == "serial":
        return SerialBackend()
    if name == "processes":
        return ProcessBackend(workers or default_workers())
    if name == "dask":
        if not scheduler:
            raise HarnessInputError("scheduler", "the dask backend needs a scheduler address (tcp://HOST:PORT) or a Client")
        return DaskBackend(scheduler)
    raise HarnessInputError("backend", f"unknown backend {name!r}; choose from serial, processes, dask")
