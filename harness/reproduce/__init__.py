"""The paper's figures, map vs FMU (``impact-harness reproduce FIG --out DIR [--quick]``, whose
command line is :mod:`harness.cli.reproduce`).

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

``impact-harness windows`` (:mod:`harness.analysis.windows.compare_windows`) is Figure 9's comparison for any
parameter set; ``reproduce fig9`` runs it with the paper's parameters.

``--quick`` gives a coarse version (under a minute on 2 cores); the default is the
publication-quality run.

Layer: above :mod:`harness.analysis` (the figures use its window comparison and its
:class:`~harness.analysis.context.Context`), below :mod:`harness.cli`; may import every layer
below and :mod:`mapcheck`; only the command line imports it.
"""
from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any

from ..analysis.context import Context, to_jsonable, write_outputs
from ..errors import HarnessInputError

__all__ = ["TARGETS", "run_target", "to_jsonable", "write_outputs", "Context"]

#: target -> module defining ``run(ctx) -> dict``.
TARGETS: dict[str, str] = {
    "fig9": "harness.reproduce.fig9",
    "fig6": "harness.reproduce.fig67",
    "fig7": "harness.reproduce.fig67",
    "fig1": "harness.reproduce.fig1",
    "rescaling": "harness.reproduce.rescaling",
    "direct": "harness.reproduce.direct",
}


def run_target(target: str, out: str | Path, quick: bool = False, workers: int | None = None,
               progress: bool = False, fmu_path: str | None = None, solver: str | None = None, *,
               run: Any = None, command: str | None = None) -> dict[str, Any]:
    """Run one reproduction; returns its result dict (also written to ``out``).

    ``run``: the run object (:class:`~harness.runs.experiment.Experiment`) the command line built
    from its layers; without it, one is built from ``fmu_path``, ``solver``, ``workers`` and
    ``progress`` with the same defaults and checks (errors name these arguments).  The figure's
    own parameters override the run's.  ``command``: the command line recorded in the report.
    """
    if target not in TARGETS:
        raise HarnessInputError("target", f"unknown target {target!r}; choose from {', '.join(TARGETS)}")
    if run is None:
        from ..runs.experiment import Experiment

        run = Experiment.for_python(fmu_path, solver, workers, progress)
    ctx = Context(target, out, quick, run, command)
    module = importlib.import_module(TARGETS[target])
    result, report = module.run(ctx)
    write_outputs(ctx, result, report)
    return result
