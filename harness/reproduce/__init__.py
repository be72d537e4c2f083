"""``impact-harness reproduce FIG --out DIR [--quick]``: the paper's figures, map vs FMU.

Each target runs what it needs through the FMU (sweeps, Newton shooting, Jacobians), the
maps through :mod:`mapcheck`, compares them with :mod:`mapcheck.compare`, and writes into
DIR only: PNG figures, ``FIG.json`` (the numbers) and ``report.md`` (what was compared,
the table, the verdict, the parameters).

Targets (one module each, ``harness/reproduce/*.py``):

* ``fig9``  -- windows of maximal period-M orbits: (64), the 2D map, the 2D map with
  A~(sigma), and the ODE (FMU, Newton shooting + up/down scans); bifurcation diagrams.
* ``fig6``, ``fig7`` -- J(x) of the FMU's map for Gamma = 10 ... 1e4 (r = 1, 0.9) with
  fitted slopes, and the hysteretic period-3 -> period-1 transition at Gamma = 10, 1000.
* ``fig1``  -- the map's bifurcation diagram at (alpha, gamma) = (0.25, 0.01) and the ODE's.
* ``rescaling`` -- window shift soft compliant vs rigid wall against (1+r)^2/(1-r)^2.
* ``direct`` -- one-step map prediction against the FMU's pre-impact map, error order in eps.

``impact-harness windows`` (:mod:`harness.reproduce.windows`) is Figure 9's comparison for any
parameter set; ``reproduce fig9`` runs it with the paper's parameters.

``--quick`` gives a coarse version (under a minute on 2 cores); the default is the
publication-quality run.

Layer: the top (beside :mod:`harness.cli`): applications of the library, which may import
every layer below and :mod:`mapcheck`; nothing in the library imports them.
"""
from __future__ import annotations

import argparse
import importlib
import json
import math
import platform
import time
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ..errors import HarnessInputError

__all__ = ["TARGETS", "register", "cmd_reproduce", "run_target", "to_jsonable", "Context"]

#: target -> module defining ``run(ctx) -> dict``.
TARGETS: dict[str, str] = {
    "fig9": "harness.reproduce.fig9",
    "fig6": "harness.reproduce.fig67",
    "fig7": "harness.reproduce.fig67",
    "fig1": "harness.reproduce.fig1",
    "rescaling": "harness.reproduce.rescaling",
    "direct": "harness.reproduce.direct",
}


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


def run_target(target: str, out: str | Path, quick: bool = False, workers: int | None = None,
               progress: bool = False, fmu_path: str | None = None, solver: str = "cvode") -> dict[str, Any]:
    """Run one reproduction; returns its result dict (also written to ``out``)."""
    if target not in TARGETS:
        raise HarnessInputError("FIG", f"unknown target {target!r}; choose from {', '.join(TARGETS)}")
    ctx = Context(target, out, quick, workers, progress, fmu_path, solver)
    module = importlib.import_module(TARGETS[target])
    result, report = module.run(ctx)
    write_outputs(ctx, result, report)
    return result


def register(sub: Any, parents: dict[str, argparse.ArgumentParser]) -> None:
    """Add the ``reproduce`` and ``windows`` subcommands (picked up by :mod:`harness.cli.main`)."""
    p = sub.add_parser(
        "reproduce", help="reproduce a figure of the paper: FMU vs maps, with a report",
        description="Run the FMU sweeps / shooting / Jacobians and the maps for one of the paper's figures, "
        "compare them, and write PNG figures, FIG.json and report.md into --out.")
    p.add_argument("figure", metavar="FIG", choices=sorted(TARGETS),
                   help="one of: " + ", ".join(TARGETS))
    p.add_argument("--out", "-o", metavar="DIR", help="output directory (default results/FIG)")
    p.add_argument("--quick", action="store_true", help="coarse version (under a minute on 2 cores)")
    p.add_argument("--workers", "-j", type=int, metavar="N", help="local worker processes for sweeps (default: all cores)")
    p.add_argument("--fmu", metavar="PATH", help="FMU (default build/fmu/ImpactOscillator.fmu)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.add_argument("--solver", choices=("cvode", "closed-form"), default="cvode",
                   help="the FMU's integrator (default cvode: the paper's question is about the ODE as a general "
                   "integrator solves it; closed-form: exact propagation, linear contact law)")
    p.set_defaults(func=cmd_reproduce)
    from .chart_command import register as register_chart
    from .windows_cli import register as register_windows

    register_windows(sub, parents)
    register_chart(sub, parents)


def cmd_reproduce(args: argparse.Namespace) -> int:
    if args.workers is not None and args.workers < 1:
        raise HarnessInputError("--workers", f"must be >= 1, got {args.workers}")
    out = args.out or f"results/{args.figure}"
    t0 = time.perf_counter()
    result = run_target(args.figure, out, args.quick, args.workers, not args.no_progress, args.fmu,
                        getattr(args, "solver", "cvode"))
    verdict = result.get("verdict", "")
    print(f"{args.figure}: {verdict}")
    print(f"wrote {Path(out) / 'report.md'} and {Path(out) / (args.figure + '.json')} "
          f"({time.perf_counter() - t0:.1f} s)")
    return 0


