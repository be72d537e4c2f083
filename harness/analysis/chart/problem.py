"""What a chart asks, checked where it is asked: :func:`chart_problem` builds a
:class:`~harness.analysis.chart.run.ChartProblem` from ranges (the grids of the second parameter
and of sigma), :func:`chart_params` the oscillator from a run object, and :func:`check_problem`
checks any problem before :func:`harness.analysis.chart.chart.chart` runs it, so that a Python
caller gets the command's checks, each error naming the Python argument."""
from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from ...config.defaults import SECTION_PHASE, WALLS
from ...errors import HarnessInputError
from .run import ChartProblem

__all__ = ["chart_problem", "chart_params", "check_problem", "M_MAX_LIMIT", "CHART_WALLS"]

#: Highest period a chart follows.
M_MAX_LIMIT = 12
#: The walls a chart takes (its windows need impacts: no ``"none"``).
CHART_WALLS = ("compliant", "rigid")


def chart_params(run: Any) -> dict[str, Any]:
    """The chart's FMU parameters from a run object (:class:`~harness.runs.experiment.Experiment`):
    nu, Omega and r (given by a file or a flag: required), the wall, the solver, Gamma on a compliant
    wall, then every other parameter the file or the flags set."""
    for k in ("nu", "Omega", "r"):
        if not run.given("model", k):
            raise HarnessInputError(k, "required (a flag, or --config with a [model] table)")
    p = run.params
    params: dict[str, Any] = {k: p[k] for k in ("nu", "Omega", "r", "wall")}
    if "solver" in p:
        params["solver"] = p["solver"]
    if int(p["wall"]) == WALLS["compliant"]:
        params["Gamma"] = p["Gamma"]
    for k in run.layers.values["model"]:
        if run.given("model", k) and k in p and k not in params:
            params[k] = p[k]
    return params


def chart_problem(params: dict[str, Any], param2: str, p_range: Sequence[float], num: int = 30, log: bool = False,
                  M_max: int = 5, sigma_range: Sequence[float] = (0.05, 400.0), per_decade: int | None = None,
                  quick: bool = False, xtol: float | None = None, theta: float = SECTION_PHASE) -> ChartProblem:
    """The chart of ``params`` over sigma in ``sigma_range`` and ``param2`` in ``p_range`` (``num``
    values, geometric with ``log``): the scans' sigma grid geometric above grazing (``per_decade``
    points a decade, default 16, 10 with ``quick``), even where ``sigma_range`` reaches sigma <= 0."""
    a, b = _pair(p_range, "p_range")
    if a == b:
        raise HarnessInputError("p_range", f"must be two different finite numbers, got {a:g}:{b:g}")
    a, b = min(a, b), max(a, b)
    if isinstance(num, bool) or not isinstance(num, (int, np.integer)) or num < 2:
        raise HarnessInputError("num", f"must be an integer >= 2, got {num!r}")
    if log and a <= 0:
        raise HarnessInputError("p_range", "a log range must be positive")
    s0, s1 = _pair(sigma_range, "sigma_range")
    if s0 <= -1.0 or s1 <= s0:
        raise HarnessInputError("sigma_range", f"needs -1 < LO < HI (sigma = -1: no forcing), got {s0:g}:{s1:g}")
    if per_decade is not None and (isinstance(per_decade, bool) or not isinstance(per_decade, (int, np.integer))
                                   or per_decade < 1):
        raise HarnessInputError("per_decade", f"must be an integer >= 1, got {per_decade!r}")
    per = per_decade or (10 if quick else 16)
    if s0 > 0:
        grid = np.geomspace(s0, s1, int(math.ceil(per * math.log10(s1 / s0))) + 1)
    else:  # below grazing: an even grid (its edges are followed in sigma itself, not ln sigma)
        grid = np.linspace(s0, s1, 4 * per + 1)
    values = np.geomspace(a, b, num) if log else np.linspace(a, b, num)
    problem = ChartProblem(params, param2, values, log, M_max, grid, transient=150 if quick else 250, samples=24,
                           xtol_rel=1e-3 if quick else 1e-4, xtol=xtol, theta=theta)
    check_problem(problem)
    return problem


def check_problem(problem: ChartProblem) -> None:
    """Raise :class:`HarnessInputError` naming the argument where ``problem`` cannot be charted."""
    p = problem.params
    for k in ("nu", "Omega", "r"):
        if k not in p:
            raise HarnessInputError(k, "required: the chart's parameters need nu, Omega and r")
    wall = p.get("wall", WALLS["compliant"])
    if wall not in [WALLS[w] for w in CHART_WALLS]:
        raise HarnessInputError("wall", f"must be compliant or rigid, got {wall!r}")
    if wall == WALLS["compliant"] and "Gamma" not in p:
        raise HarnessInputError("Gamma", "required on a compliant wall")
    v = np.asarray(problem.values, dtype=float)
    if v.ndim != 1 or v.size < 2 or not np.all(np.isfinite(v)) or not np.all(np.diff(v) > 0):
        raise HarnessInputError("values", "needs at least 2 finite values of the second parameter, increasing")
    if problem.log and v[0] <= 0:
        raise HarnessInputError("p_range", "a log range must be positive")
    if isinstance(problem.M_max, bool) or not isinstance(problem.M_max, (int, np.integer)) \
            or not 1 <= problem.M_max <= M_MAX_LIMIT:
        raise HarnessInputError("M_max", f"must be in 1..{M_MAX_LIMIT}, got {problem.M_max!r}")
    g = np.asarray(problem.sigma_grid, dtype=float)
    if g.ndim != 1 or g.size < 2 or not np.all(np.isfinite(g)) or g[0] <= -1.0 or not np.all(np.diff(g) > 0):
        raise HarnessInputError("sigma_range", "the sigma grid needs increasing finite values above -1")
    if not 0.0 <= problem.theta < 1.0:
        raise HarnessInputError("theta", f"the section phase must lie in [0, 1), got {problem.theta}")
    if problem.xtol is not None and not (math.isfinite(problem.xtol) and problem.xtol > 0):
        raise HarnessInputError("xtol", f"must be a finite number > 0, got {problem.xtol!r}")


def _pair(value: Any, argument: str) -> tuple[float, float]:
    """Two finite numbers ``(lo, hi)`` from a pair or a ``"LO:HI"`` text."""
    if isinstance(value, str):
        value = value.split(":")
    try:
        lo, hi = (float(x) for x in value)
    except (TypeError, ValueError):
        raise HarnessInputError(argument, f"expected two numbers LO:HI, got {value!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise HarnessInputError(argument, f"must be two finite numbers, got {lo:g}:{hi:g}")
    return lo, hi
