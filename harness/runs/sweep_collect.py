"""What a running sweep gathers: finished tasks, the leading points of unfinished chains (also
from a checkpoint of an earlier run), the progress bar, and the counts of :class:`SweepStats`.

The backends report from their result loop and from progress threads
(:func:`harness.runs.sweeps.run_sweep` hands them :meth:`SweepCollector.on_result` and
:meth:`SweepCollector.on_progress`); the shared state is kept here, under one lock.
"""
from __future__ import annotations

import dataclasses
import threading
import time
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from .checkpoint import Checkpoint
from ..io.progress import progress_bar
from .tasks import RESULT_FIELDS, SweepTask

__all__ = ["PARTIAL_FIELDS", "SweepCollector", "SweepStats"]

#: What a checkpoint keeps of each finished point of an unfinished chain: its results and
#: ``end`` = (t, u, v), the state the chain went on from.
PARTIAL_FIELDS = (*RESULT_FIELDS, "end")


@dataclass
class SweepStats:
    """What a sweep did: tasks computed now, tasks taken from the checkpoint, wall time."""

    computed: int = 0
    resumed: int = 0
    wall_time: float = 0.0
    #: points of unfinished chains taken from the checkpoint (not recomputed)
    resumed_points: int = 0
    #: points on disk in the checkpoint now (whole tasks and leading points of chains)
    kept_points: int = 0
    #: points of the whole sweep (directions x grid [x second axis])
    total_points: int = 0


class SweepCollector:
    """Results and progress of one sweep's tasks.

    Parameters
    ----------
    tasks : mapping key -> SweepTask
        Every task of the sweep.
    store : Checkpoint or None
        Finished tasks and leading points of chains are stored there as they come.
    stats : SweepStats
        Filled in place.

    Attributes
    ----------
    results : dict key -> arrays
        Finished tasks (from the checkpoint, then as they finish).
    todo : dict key -> SweepTask
        The tasks to run, a chain with stored leading points set to resume after them.
    """

    def __init__(self, tasks: Mapping[str, SweepTask], store: Checkpoint | None, stats: SweepStats) -> None:
        self.tasks, self.store, self.stats = tasks, store, stats
        self.results: dict[str, dict[str, np.ndarray]] = {}
        self.todo: dict[str, SweepTask] = {}
        # leading points of chains: from the checkpoint, then as the chains report them
        self.partial: dict[str, dict[str, list]] = {}
        self.in_flight: dict[str, int] = {}  # points reported by tasks still running
        self.lock = threading.Lock()
        self.bar: Any = None
        self.last_draw = 0.0
        self.resume()

    def resume(self) -> None:
        """Take finished tasks and the leading points of chains from the checkpoint."""
        store, stats = self.store, self.stats
        for key, task in self.tasks.items():
            if store is not None and store.has(key):
                self.results[key] = store.load(key)
                continue
            rows = store.load_partial(key) if store is not None else None
            if rows is not None and "end" in rows and 0 < len(rows["period"]) < len(task.values):
                done = len(rows["period"])
                self.partial[key] = {name: list(rows[name]) for name in PARTIAL_FIELDS}
                t_last, u_last, v_last = rows["end"][-1]  # the state after the last finished point
                task = dataclasses.replace(task, resume=(done, float(t_last), float(u_last), float(v_last)))
                stats.resumed_points += done
            self.todo[key] = task
        stats.resumed = len(self.results)
        stats.kept_points = sum(len(self.tasks[k].values) for k in self.results) + stats.resumed_points
        self.first_of = {key: (task.resume[0] if task.resume else 0) for key, task in self.todo.items()}
        self.total_points = sum(len(t.values) for t in self.tasks.values())
        self.finished = stats.kept_points

    def open_bar(self, desc: str, show: bool) -> None:
        """The progress bar (per finished point), starting at the points already done."""
        self.stats.total_points = self.total_points
        self.bar = progress_bar(total=self.total_points, initial=self.finished, desc=desc, unit="pt",
                                disable=not show)

    def show(self, force: bool = False) -> None:
        # Called from the result loop and from progress threads; a task rerun after a lost
        # worker reports from 1 again, so the count is recomputed, never accumulated.
        self.bar.n = min(self.total_points, self.finished + sum(self.in_flight.values()))
        now = time.monotonic()
        if force or now - self.last_draw > 0.2:  # redraw at most 5 times a second
            self.bar.refresh()
            self.last_draw = now

    def on_progress(self, key: str, points: int, row: Mapping[str, Any] | None = None) -> None:
        """A chain finished its ``points``-th point (``row``: its results)."""
        with self.lock:
            if key in self.results:
                return  # a late report of a task already finished
            rows = self.partial.setdefault(key, {name: [] for name in PARTIAL_FIELDS})
            if row is not None and points == len(rows["period"]) + 1:  # the next point, in order
                for name in PARTIAL_FIELDS:
                    rows[name].append(row[name])
                if self.store is not None:
                    self.store.save_partial(key, {name: np.asarray(rows[name]) for name in PARTIAL_FIELDS})
                    self.stats.kept_points += 1
            self.in_flight[key] = points - self.first_of[key]  # points computed in this run
            self.show()

    def count_kept_on_disk(self) -> None:
        """Set ``stats.kept_points`` to the points the checkpoint holds now, counted on disk.

        After an interrupt the running count can lag the files by one report: a progress
        thread (or the result loop) saves its point and counts it a moment later, and the
        interrupt can fall in between. The files are written atomically, so they are the truth.
        """
        if self.store is None:
            return
        with self.lock:
            kept = 0
            for key, task in self.tasks.items():
                if self.store.has(key):
                    kept += len(task.values)
                else:
                    rows = self.store.load_partial(key)
                    kept += len(rows["period"]) if rows else 0
            self.stats.kept_points = kept

    def on_result(self, key: str, arrays: dict[str, np.ndarray]) -> None:
        """A task finished with ``arrays``."""
        rows = self.partial.get(key)
        first = self.first_of[key]
        if first:  # the leading points came from the checkpoint
            for name in RESULT_FIELDS:
                if name in rows:  # a checkpoint written before a field existed lacks it
                    arrays[name][:first] = np.asarray(rows[name][:first])
        if self.store is not None:
            self.store.save(key, arrays)
            self.store.remove_partial(key)
        with self.lock:
            self.results[key] = arrays
            self.partial.pop(key, None)
            self.in_flight.pop(key, None)
            self.finished += len(self.tasks[key].values) - first
            if self.store is not None:  # the whole task is on disk now, its partial rows replaced
                self.stats.kept_points += len(self.tasks[key].values) - (len(rows["period"]) if rows else 0)
            self.stats.computed += 1
            self.show(force=self.finished == self.total_points)
