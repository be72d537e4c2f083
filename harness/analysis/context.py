"""What one run of an analysis or of a paper's figure needs (:class:`Context`: the FMU, the
output directory, quality, workers, progress, solver) and how its results are written
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

from ..errors import HarnessInputError

__all__ = ["Context", "to_jsonable", "write_outputs"]


class Context:
    """What a target needs: FMU, output directory, quality, workers, progress.

    Attributes
    ----------
    target : str
    out : Path
        Output directory (created).
    quick : bool
    workers : int or None
    progress : bool
    fmu : FmuModel
    solver : str
        The FMU's integrator, "cvode" (the default: the paper's question is about the ODE as a
        general integrator solves it) or "closed-form".
    """

    def __init__(self, target: str, out: str | Path, quick: bool = False, workers: int | None = None,
                 progress: bool = False, fmu_path: str | None = None, solver: str = "cvode") -> None:
        from ..config import default_fmu_path
        from ..fmu.fmi import FmuModel

        self.target = target
        self.out = Path(out)
        self.out.mkdir(parents=True, exist_ok=True)
        self.quick = bool(quick)
        self.workers = workers
        self.progress = progress
        self.fmu = FmuModel(fmu_path or default_fmu_path(), "--fmu")
        from ..fmu.fmi import SOLVER_NAMES, SOLVER_PARAMETER

        if solver not in SOLVER_NAMES:
            raise HarnessInputError("--solver", f"unknown solver {solver!r}; one of {', '.join(SOLVER_NAMES)}")
        if SOLVER_PARAMETER not in self.fmu.variables and SOLVER_NAMES[solver] != 0:
            raise HarnessInputError("--solver", f"{self.fmu.path.name} has no closed-form solver mode (no "
                                    f"parameter {SOLVER_PARAMETER!r}); it integrates with CVODE only")
        self.solver = solver
        self.t_start = time.perf_counter()
        #: the ``impact-harness`` command line that reproduces this run (report footer)
        self.command = f"reproduce {target}{' --quick' if self.quick else ''} --out {self.out}"

    def simulator(self):
        """A fresh in-process FMU simulator (for shooting and Jacobians)."""
        from ..fmu.simulator import FmuSimulator

        return FmuSimulator(self.fmu.source(), instance_name=f"reproduce-{self.target}")

    def params(self, **overrides: Any) -> dict[str, Any]:
        """The FMU's defaults with ``overrides`` (initial state removed)."""
        p = self.fmu.defaults()
        p.pop("u0", None)
        p.pop("v0", None)
        from ..fmu.fmi import SOLVER_NAMES, SOLVER_PARAMETER

        if SOLVER_PARAMETER in self.fmu.variables:
            p[SOLVER_PARAMETER] = SOLVER_NAMES[self.solver]
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
    footer = (f"\n\n---\nRun: `impact-harness {ctx.command}`, {ctx.elapsed():.1f} s, FMU sha256 {ctx.fmu.sha256[:12]}, "
              f"harness {__version__}. Numbers: `{jpath.name}`.\n")
    rpath.write_text(report.rstrip() + footer)
    return jpath, rpath
