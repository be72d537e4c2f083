"""What one run of an analysis or of a paper's figure needs (:class:`Context`: the run object
-- :class:`~harness.runs.experiment.Experiment`, which opened the FMU and checked the solver --,
the output directory, quality, the command line) and how its results are written
(:func:`write_outputs`: ``NAME.json`` and ``report.md``; :func:`to_jsonable`).
"""
from __future__ import annotations

import json
import math
import platform
import time
from pathlib import Path
from typing import Any, Mapping

import numpy as np

__all__ = ["Context", "to_jsonable", "write_outputs"]


class Context:
    """What a target needs: the run (its FMU and settings), output directory, quality.

    Attributes
    ----------
    target : str
    run : Experiment
        The run object: the FMU (opened once), its parameters with the solver (checked once),
        workers and progress, from the same layers as every command.
    out : Path
        Output directory (created).
    quick : bool
    workers : int or None
        Worker processes asked for (None: the analysis's own default).
    progress : bool
    fmu : FmuModel
    solver : str
        The FMU's integrator, "cvode" (the default: the paper's question is about the ODE as a
        general integrator solves it) or "closed-form".
    command : str
        The command line that reproduces this run (the report's footer).
    figures : bool
        Whether the figures are drawn (False: the JSON, the report and the data only, for a
        caller that reads numbers: drawing is a tenth of a quick run).
    """

    def __init__(self, target: str, out: str | Path, quick: bool = False, run: Any = None,
                 command: str | None = None, figures: bool = True) -> None:
        from ..runs.experiment import Experiment

        self.target = target
        self.run = run if run is not None else Experiment.for_python()
        self.out = Path(out)
        self.out.mkdir(parents=True, exist_ok=True)
        self.quick = bool(quick)
        self.figures = bool(figures)
        self.workers = self.run.run.workers if self.run.given("run", "workers") else None
        self.progress = self.run.run.progress
        self.fmu = self.run.model
        self.solver = self.run.solver
        self.t_start = time.perf_counter()
        #: the command line that ran this (report footer); called from Python: the call
        self.command = command or f"run_target({target!r}, out={str(self.out)!r}, quick={self.quick!r}) from Python"

    def simulator(self):
        """A fresh in-process FMU simulator (for shooting and Jacobians)."""
        from ..fmu.simulator import FmuSimulator

        return FmuSimulator(self.fmu.source(), instance_name=f"reproduce-{self.target}")

    def params(self, **overrides: Any) -> dict[str, Any]:
        """The run's parameters (the FMU's defaults, the file's and the flags' values, the solver;
        no initial state) with ``overrides``."""
        p = dict(self.run.params)
        for k, v in overrides.items():
            p[k] = self.fmu.coerce(k, v, k)
        return p

    def elapsed(self) -> float:
        return time.perf_counter() - self.t_start


def to_jsonable(obj: Any) -> Any:
    """numpy scalars/arrays, tuples, inf/nan -> JSON (non-finite numbers -> null)."""
    if isinstance(obj, Mapping):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(float(obj)) else None
    if isinstance(obj, (complex, np.complexfloating)):
        return [to_jsonable(obj.real), to_jsonable(obj.imag)]
    return obj


def write_outputs(ctx: Context, result: Mapping[str, Any], report: str) -> tuple[Path, Path]:
    """Write ``FIG.json`` and ``report.md`` into the output directory."""
    from .. import __version__

    data = dict(result)
    data.setdefault("run", {})
    data["run"].update({
        "target": ctx.target, "quick": ctx.quick, "solver": ctx.solver, "runtime_s": round(ctx.elapsed(), 2),
        "fmu": str(ctx.fmu.path), "fmu_sha256": ctx.fmu.sha256, "version": __version__,
        "python": platform.python_version(),
    })
    jpath = ctx.out / f"{ctx.target}.json"
    jpath.write_text(json.dumps(to_jsonable(data), indent=2) + "\n")
    rpath = ctx.out / "report.md"
    footer = (f"\n\n---\nRun: `{ctx.command}`, {ctx.elapsed():.1f} s, FMU sha256 {ctx.fmu.sha256[:12]}, "
              f"harness {__version__}. Numbers: `{jpath.name}`.\n")
    rpath.write_text(report.rstrip() + footer)
    return jpath, rpath
