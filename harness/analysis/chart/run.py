"""``impact-harness chart``: the ODE's windows in the plane of sigma and a second parameter.

Two measurements, the second checking the first:

1. **Continuation** (:mod:`.chart_curves`): at the first value of the second parameter (``--param2``:
   Gamma, r, nu, Omega or any FMU parameter) the stable maximal windows (one impact per period,
   M <= M_max) are found from the ODE, each continued in sigma to its edges, and every edge is
   continued in (sigma, p2): flip/fold/NS on the extended system, grazes located across the curve.
   Where each window closes (``closes`` per M, with how) is the first candidate where its edges
   meet that direct shooting confirms on both sides (:mod:`.window_region`); every point of
   every edge curve is then checked across itself (``edge_check``).
2. **Scans per value** (the brute-force check): for each value of p2 the windows are measured
   from scratch as ``windows`` does (:mod:`.ode_windows`: up/down scans over sigma, every attractor
   seen shot to its edges); ``scans`` per M, joined across the values, and ``scan_check``: where
   they differ from the continued edges by more than 1 %.

Beside the ODE: the windows of the low-velocity compliant map (48) and of the hard-wall map (39)
(both with A~(sigma)), and beta = r v_c kappa / |A~| of (43) along the scanned orbits
(kappa^2 = Gamma Omega^2; v_c the impact velocity of the ODE's orbit at the window's seed), so that
the chart shows where each map holds (beta << 1: (48); beta >> 1: (39)).

Output in DIR: ``chart.json``, ``chart.png``, ``report.md``.  The scans run in parallel on the
harness's backends (processes, or Dask with ``--scheduler``); the continuation in the main process.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any, Mapping, Sequence

import numpy as np

from ...config.defaults import SECTION_PHASE, WALLS
from ...errors import HarnessInputError
from .edge_curves import edge_check, scan_check, widened
from .window_region import chart_regions

__all__ = ["ChartProblem", "run_chart", "chart_value_task", "curves_from_values", "closing"]


@dataclass
class ChartProblem:
    """What to chart.

    Attributes
    ----------
    params : dict
        FMU parameters (nu, Omega, r, wall code, Gamma, solver ...), without sigma.
    param2 : str
        The second parameter (an FMU parameter name).
    values : ndarray
        Its values, sorted.
    log : bool
        Log axis for the second parameter.
    M_max : int
        Highest period charted.
    sigma_grid : ndarray
        The scans' geometric sigma grid (every value uses the same).
    xtol_rel : float
        Bisection tolerance of every edge, relative to its sigma.
    xtol : float or None
        An absolute bisection tolerance in sigma instead (None: ``xtol_rel``); an edge near
        sigma = 0, or two edges closer than ``xtol_rel`` x sigma, needs one.
    """

    params: dict[str, Any]
    param2: str
    values: np.ndarray
    log: bool
    M_max: int
    sigma_grid: np.ndarray
    transient: int = 200
    samples: int = 24
    xtol_rel: float = 1e-3
    theta: float = SECTION_PHASE
    xtol: float | None = None


def chart_value_task(task: Mapping[str, Any], source: Any, progress: Any = None) -> dict[str, Any]:
    """One value of the second parameter: scans, then every attractor shot to its edges
    (runs on a backend worker; ``source`` the FMU)."""
    from ...config import SamplingSpec, SweepSpec
    from ...dynamics.maps.shooting import StroboscopicMap
    from ...fmu.fmi import open_source
    from ...fmu.simulator import FmuSimulator
    from ...runs.sweeps import run_sweep
    from ..windows.ode_windows import measure

    t0 = time.perf_counter()
    params = dict(task["params"])
    grid = np.asarray(task["grid"], dtype=float)
    _, model = open_source(source)
    above = bool(grid[0] > 0)  # a geometric grid above grazing, else an even one reaching sigma <= 0
    mid = float(np.sqrt(grid[0] * grid[-1])) if above else float(0.5 * (grid[0] + grid[-1]))
    state0 = (-(1.0 + mid) - 1.0, 0.0)  # on the wall-free orbit (4) at t = 1/2
    sampling = SamplingSpec(theta=task["theta"], n_transient=task["transient"], n_samples=task["samples"],
                            tol=1e-4 * min(1.0, 10.0 * float(grid[0])) if above else 1e-5)
    ds = run_sweep(model, SweepSpec("sigma", grid, ("up", "down")), params, state0, sampling, backend="serial",
                   progress=False)
    smap = StroboscopicMap(FmuSimulator(source, instance_name="chart"), params, task["theta"])
    sigma_range = (0.1 * float(grid[0]), 4.0 * float(grid[-1])) if above else widened(grid)
    # an absolute tolerance, where given, replaces the relative one (as in ``windows --xtol``)
    xtol = task.get("xtol")
    res = measure(smap, grid, ds, sigma_range, task["xtol_rel"] if xtol is None else xtol, task["M_max"],
                  workers=1, relative=xtol is None)
    from .contradictions import scan_seeds

    # the scans' own states: where the shooting that settles a contradiction starts
    return {"value": task["value"], "all": res["all"], "fmu_periods": res["fmu_periods"],
            "seeds": scan_seeds(grid, ds, task["M_max"]), "seconds": time.perf_counter() - t0}


def closing(values: Sequence[float], present: Sequence[bool], log: bool) -> dict[str, Any]:
    """Where a window disappears along the second parameter.

    Returns ``{"closes": value or None, "bracket": [last with, first without] or None,
    "opens": ..., "searched": [first, last]}``; the value is the bracket's (geometric) midpoint."""
    v = [float(x) for x in values]
    out: dict[str, Any] = {"closes": None, "bracket": None, "opens": None, "opens_bracket": None,
                           "searched": [v[0], v[-1]], "present_at": [x for x, p in zip(v, present) if p]}
    mid = (lambda a, b: math.sqrt(a * b)) if log else (lambda a, b: 0.5 * (a + b))
    idx = [i for i, p in enumerate(present) if p]
    if not idx:
        return out
    if idx[-1] < len(v) - 1:
        i = idx[-1]
        out["closes"], out["bracket"] = mid(v[i], v[i + 1]), [v[i], v[i + 1]]
    if idx[0] > 0:
        i = idx[0]
        out["opens"], out["opens_bracket"] = mid(v[i - 1], v[i]), [v[i - 1], v[i]]
    return out


def _beta(entry: Mapping[str, Any], params: Mapping[str, Any]) -> float | None:
    """beta = r v_c kappa / |A~| (43) at the window's seed (compliant wall only)."""
    from mapcheck.coeffs import grazing_acceleration

    if int(params.get("wall", WALLS["compliant"])) != WALLS["compliant"] or entry.get("v_c") is None:
        return None
    Om, s = float(params["Omega"]), float(entry["seed_sigma"])
    kappa = math.sqrt(float(params["Gamma"])) * Om
    return float(params["r"]) * entry["v_c"] * kappa / abs(float(grazing_acceleration(s, Om, "tilde")))


def curves_from_values(problem: ChartProblem, per_value: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """Per M: arrays over the second parameter of the window's edges, kinds, beta; ``closes``."""
    curves: dict[str, Any] = {}
    others: list[dict[str, Any]] = []
    for M in range(1, problem.M_max + 1):
        rows = {"value": [], "lower": [], "upper": [], "kind_lower": [], "kind_upper": [], "beta": [], "v_c": [],
                "multipliers_inside": []}
        present = []
        for res in per_value:
            p = {**problem.params, problem.param2: res["value"]}
            cands = [e for e in res["all"] if e["M"] == M and e["impacts"] == 1 and e["resolved"]]
            present.append(bool(cands))
            if not cands:
                continue
            # several windows of one M (e.g. a second period-1 window far from grazing): chart the
            # one nearest grazing (lowest lower edge), the near-grazing maps' subject
            e = min(cands, key=lambda e: e["lo"] if e["lo"] is not None else e["seen"][0])
            rows["value"].append(res["value"])
            rows["lower"].append(e["lo"])
            rows["upper"].append(e["hi"])
            rows["kind_lower"].append(e["kinds"][0])
            rows["kind_upper"].append(e["kinds"][1])
            rows["beta"].append(_beta(e, p))
            rows["v_c"].append(e.get("v_c"))
            rows["multipliers_inside"].append(e.get("multipliers_inside"))
        curves[str(M)] = {**rows, **closing(problem.values, present, problem.log)}
    for res in per_value:
        others += [{**e, "param2": res["value"]} for e in res["all"] if e["impacts"] != 1 and e["resolved"]]
    return {"scans": curves, "other_windows": others}


def map_overlays(problem: ChartProblem) -> dict[str, Any]:
    """Windows of map (48) and map (39) (A~ variant) per value of the second parameter (they
    depend on it only through nu, Omega or r)."""
    from mapcheck.compare import map_windows
    from mapcheck.coeffs import coefficients

    # the maps' windows lie above grazing: their grid starts at 1e-4 where the chart's reaches sigma <= 0
    lo = problem.sigma_grid[0] * 0.1 if problem.sigma_grid[0] > 0 else 1e-4
    grid = np.geomspace(lo, max(problem.sigma_grid[-1] * 4.0, 10.0 * lo), 8001)
    out: dict[str, Any] = {}
    for key, wall in (("map_48", "compliant"), ("map_39", "compliant-high")):
        rows: dict[str, dict[str, list]] = {str(M): {"value": [], "lower": [], "upper": []}
                                              for M in range(1, problem.M_max + 1)}
        for v in problem.values:
            p = {**problem.params, problem.param2: float(v)}
            try:
                c = coefficients(float(p["nu"]), float(p["Omega"]), float(p["r"]), wall)
            except ValueError:
                continue
            with np.errstate(all="ignore"):
                ws = map_windows(c, problem.M_max, grid, "tilde")
            for M, w in ws.items():
                if w is not None:
                    rows[str(M)]["value"].append(float(v))
                    rows[str(M)]["lower"].append(w[0])
                    rows[str(M)]["upper"].append(w[1])
        out[key] = rows
    return out


def run_chart(problem: ChartProblem, source: Any, backend: Any = None, workers: int | None = None,
              scheduler: str | None = None) -> dict[str, Any]:
    """Measure every value (in parallel on the backend) and join the windows into curves."""
    from ...runs.backends import make_backend

    tasks = {i: {"params": {**problem.params, problem.param2: float(v)}, "value": float(v),
                 "grid": problem.sigma_grid.tolist(), "theta": problem.theta, "transient": problem.transient,
                 "samples": problem.samples, "xtol_rel": problem.xtol_rel, "xtol": problem.xtol,
                 "M_max": problem.M_max}
             for i, v in enumerate(problem.values)}
    results: dict[int, Any] = {}
    be = make_backend(backend, workers, scheduler)
    t0 = time.perf_counter()
    try:
        be.run(chart_value_task, tasks, source, lambda k, r: results.__setitem__(k, r))
    finally:
        be.close()
    wall_s = time.perf_counter() - t0
    per_value = [results[i] for i in sorted(results)]
    out = curves_from_values(problem, per_value)
    t1 = time.perf_counter()
    cont = chart_regions(source, problem.params, problem.param2, (float(problem.values[0]), float(problem.values[-1])),
                        problem.log, problem.sigma_grid, problem.M_max, problem.theta)
    out["windows"], out["closes"], out["continuation_search"] = cont["windows"], cont["closes"], cont["search"]
    out["scan_check"] = scan_check(cont["windows"], out["scans"])
    out["edge_check"] = edge_check(source, problem.params, problem.param2, cont["windows"], problem.log, problem.theta,
                                   sigma_log=bool(problem.sigma_grid[0] > 0))
    out["continuation_seconds"] = time.perf_counter() - t1
    from .contradictions import cross_checks

    # the wall-free window, contradictions settled by shooting, coexistence per value
    scan_range = (0.1 * float(problem.sigma_grid[0]), 4.0 * float(problem.sigma_grid[-1])) \
        if problem.sigma_grid[0] > 0 else widened(problem.sigma_grid)
    cross_checks(source, problem, out, per_value, scan_range)
    from .closing_routes import reconcile_closings

    # each closing held against every route of the run, and the one-parameter route; where one moved,
    # the contradictions and coexistence are read again against the closings that stand
    if reconcile_closings(source, problem, out, per_value):
        cross_checks(source, problem, out, per_value, scan_range)
    out["cross_check_seconds"] = time.perf_counter() - t1 - out["continuation_seconds"]
    out["maps"] = map_overlays(problem)
    out["backend"] = be.describe()
    out["seconds"] = wall_s
    out["task_seconds"] = [r["seconds"] for r in per_value]
    out["fmu_periods_shooting"] = int(sum(r["fmu_periods"] for r in per_value))
    return out


def parse_range(text: str) -> tuple[float, float]:
    """"A:B" -> (A, B)."""
    try:
        a, b = (float(x) for x in text.split(":"))
    except ValueError:
        raise HarnessInputError("--range", f"must be START:STOP, got {text!r}") from None
    if not (math.isfinite(a) and math.isfinite(b)) or a == b:
        raise HarnessInputError("--range", f"must be two different finite numbers, got {text!r}")
    return (a, b) if a < b else (b, a)
