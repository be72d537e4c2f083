"""Map vs ODE window edges for any parameter set: :func:`compare_windows` (``impact-harness
windows``); the parameter set and its settings are in :mod:`.window_problem`.

For (alpha, gamma) or (nu, Omega), restitution r and a wall (rigid, or compliant with
stiffness Gamma), four sources of the sigma-edges of the stable maximal period-M windows
(one impact per M forcing periods):

* ``theory_64``   -- (64), rho in [1/(4M), 1/M^2], with rho(sigma) linear ((48) for the
  compliant wall, (39) for the rigid one);
* ``map``         -- the 2D map (37)/(38) with the same coefficients (closed-form orbits);
* ``map_A_tilde`` -- the same with |A~(sigma)| in rho (docs/theory.md, "The A~ variant");
* ``ode``         -- the FMU: Newton shooting on its stroboscopic M-period map, started in
  the A~ map's window, each edge bracketed and bisected by the shooting itself
  (:func:`harness.dynamics.maps.shooting.map_guided_windows`); confirmed by quasi-static up/down scans.

Output in DIR: ``report.md``, ``windows.json`` (``{"windows": {"ode": {"1": [lo, hi], ...},
"theory_64": ..., "map": ..., "map_A_tilde": ...}, "parameters": ...}``, the format of
``fig9.json``), ``windows_map.png``, ``windows_ode.png``, ``windows_windows.png`` and the
scans as NetCDF.  ``reproduce fig9`` is this comparison with the paper's parameters.
"""
from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from mapcheck.coeffs import Coefficients
from mapcheck.compare import (
    best_variant,
    predicted_windows,
    scan_confirmation,
    sweep_windows,
    window_differences,
)

from ...config.defaults import SECTION_PHASE
from ...errors import HarnessInputError
from ..context import Context, write_outputs
from .problem import M_AUTO_LIMIT, WindowProblem, WindowSettings, default_settings, map_guide
from .report import SCAN_TOL, VARIANT_KEYS, report

__all__ = ["WindowProblem", "WindowSettings", "compare_windows", "run_windows", "default_settings"]


# ----------------------------------------------------------------------------------------
# The measurements
# ----------------------------------------------------------------------------------------
def _workers(ctx: Context) -> int:
    from ...config import default_workers

    return ctx.workers or min(2, default_workers())


def ode_scans(ctx: Context, problem: WindowProblem, st: WindowSettings):
    """Quasi-static up and down scans of the FMU over sigma (the harness's sweeps)."""
    from ...config import SamplingSpec, SweepSpec
    from ...runs.backends import make_backend
    from ...runs.sweeps import run_sweep

    grid = st.scan_grid
    spec = SweepSpec("sigma", grid, ("up", "down"))
    # tol 1e-4: distinct points of a period-M orbit at phase 1/2 are O(0.1 sigma) apart,
    # while near a flip the decaying period-2M oscillation (multiplier near -1) must fall
    # below tol before the point counts as period M
    sampling = SamplingSpec(theta=problem.theta, n_transient=st.transient, n_samples=st.samples,
                            tol=SCAN_TOL * (min(1.0, 10.0 * float(grid[0])) if st.log_sigma else 1.0))
    # start on the wall-free orbit (4) at the middle of the range (p(1/2) = -(1 + sigma) - 1)
    mid = float(np.sqrt(grid[0] * grid[-1]) if st.log_sigma else np.mean(grid))
    th = 2.0 * math.pi * problem.theta
    sin_th = math.sin(th) if abs(math.sin(th)) > 1e-12 else 0.0  # exactly 0 at theta = 1/2
    state0 = ((1.0 + mid) * math.cos(th) - 1.0, -2.0 * math.pi * (1.0 + mid) * sin_th)
    params = ctx.params(**problem.fmu_params())
    # one backend for both scans: one pool of workers started, not two; with one worker the
    # scans run here (a pool of one would only add a process start and the FMU's loading)
    workers = _workers(ctx)
    be = make_backend("serial" if workers == 1 else "processes", workers)
    try:
        ds = run_sweep(ctx.fmu, spec, params, state0, sampling, backend=be, progress=ctx.progress)
        if not st.far_start:
            return ds
        # three times the wall-free orbit's amplitude away, at rest: it hits the wall hard and
        # settles on an impacting attractor where one coexists with the wall-free orbit
        far = run_sweep(ctx.fmu, spec, params, (-3.0 * (1.0 + abs(mid)) - 1.0, 0.0), sampling, backend=be,
                        progress=ctx.progress)
    finally:
        be.close()
    import xarray as xr

    far = far.assign_coords(direction=[f"{d}-far" for d in far["direction"].values])
    return xr.concat([ds, far], dim="direction", combine_attrs="override")


def _safe_predictions(problem: WindowProblem, M_maps: int, st: WindowSettings) -> tuple[dict[str, dict], str | None]:
    """The maps' windows, or empty tables with the reason the maps do not exist."""
    c, why = map_guide(problem, M_maps)
    if c is None:
        return {k: {M: None for M in range(1, M_maps + 1)} for k in VARIANT_KEYS}, why
    with np.errstate(all="ignore"):
        return predicted_windows(c, M_maps, st.table_grid), None


def _shoot_ode(ctx: Context, problem: WindowProblem, st: WindowSettings, ds: Any, pred: dict[str, dict],
               c: Coefficients | None, searches: Any = None) -> dict[str, Any]:
    """Every attractor of the scans ``ds`` shot to its window's edges (guided by the A~ map
    where the maps exist: ``c`` not None)."""
    from ...dynamics.maps.shooting import StroboscopicMap
    from .ode_windows import measure
    from .routes import Routes

    smap = StroboscopicMap(ctx.simulator(), ctx.params(**problem.fmu_params()), problem.theta)
    routes = Routes(st.scan_grid, ds, searches, problem.M_max, problem.theta)
    out = measure(smap, st.scan_grid, ds, st.sigma_range, st.xtol if st.xtol is not None else st.xtol_rel,
                  problem.M_max, None if c is None else pred["map_A_tilde"], c, _workers(ctx),
                  relative=st.xtol is None, routes=routes)
    out["transients"] = routes.transients
    return out


def _applicability(problem: WindowProblem, st: WindowSettings, pred: dict[str, dict],
                   no_maps: str | None) -> dict[str, str | None]:
    """Per map variant, why it does not apply to this oscillator (None: it applies)."""
    from mapcheck.applicability import map_applicability

    a, g = problem.alpha_gamma
    applies = map_applicability(problem.nu, problem.Omega, problem.r, problem.map_coefficients_wall, a, g,
                                pred, (float(st.table_grid[0]), float(st.table_grid[-1])))
    if no_maps:
        applies = {k: f"the maps' coefficients do not exist: {no_maps}" for k in VARIANT_KEYS}
    return applies


def _write_scans(ctx: Context, ds: Any) -> str:
    """The scans as NetCDF in the output directory; returns the file name."""
    from ...io.results import write_netcdf

    ds.attrs["reproduce.target"] = ctx.target
    write_netcdf(ds, ctx.out / f"{ctx.target}_ode_scans.nc")
    return f"{ctx.target}_ode_scans.nc"


def _parameters(problem: WindowProblem, st: WindowSettings, shoot: dict[str, Any],
                c: Coefficients | None) -> dict[str, Any]:
    """The result's ``parameters``: the parameter set and how hard it was looked at."""
    a, g = problem.alpha_gamma
    grid = st.scan_grid
    return {
        "alpha": a, "gamma": g, "nu": problem.nu, "Omega": problem.Omega, "r": problem.r, "wall": problem.wall,
        "map_coefficients": f"{problem.coefficient_eq()} (coefficients wall={problem.map_coefficients_wall!r})",
        "Gamma": problem.Gamma if problem.wall == "compliant" else None,
        "M_max": problem.M_max if problem.M_max is not None else "auto", "M_scan_limit": M_AUTO_LIMIT,
        "rho_per_sigma": None if c is None else c.rho_per_sigma, "theta": problem.theta,
        "sigma_grid": [float(grid[0]), float(grid[-1]), int(len(grid))], "transient": st.transient,
        "samples": st.samples, "shooting_xtol": shoot["xtol"], "shooting_sigma_range": list(st.sigma_range),
        "shooting_xtol_rule": (f"{st.xtol:g} absolute" if st.xtol is not None else
                               f"{st.xtol_rel:g} x the window's sigma"),
        "map_sigma_range": [float(st.table_grid[0]), float(st.table_grid[-1])],
        "fmu_periods_shooting": shoot["fmu_periods"], "shooting_derivatives": shoot["derivatives"], **st.extra,
    }


def _coincident_edges(ctx: Context, rows: list[dict[str, Any]]) -> Any:
    """Edges theory says coincide, located once (one point, not two): with CVODE each location
    carries its orbits' error (~1e-9 in sigma), so ten times one period's accuracy is the floor
    of agreement."""
    from ...dynamics.maps.periodic_map import map_accuracy
    from .edge_coincidence import reconcile

    return reconcile(rows, 10.0 * map_accuracy(ctx.params(), 1))


def run_windows(ctx: Context, problem: WindowProblem, st: WindowSettings,
                predicted: dict[str, dict] | None = None) -> tuple[dict[str, Any], str]:
    """The comparison: the ODE's windows (scans over the whole range, each attractor shot to its
    edges), then the maps' predictions beside them; returns (result, report)."""
    from .ode_windows import period_adding_stop

    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    M_maps = problem.M_max or 8
    pred, no_maps = (predicted, None) if predicted is not None else _safe_predictions(problem, M_maps, st)
    timings["maps"] = time.perf_counter() - t0
    # scans first, then the shooting (on 2 cores a sweep beside the shooting slowed both)
    t1 = time.perf_counter()
    ds = ode_scans(ctx, problem, st)
    timings["scans"] = time.perf_counter() - t1
    from .routes import found_only_by_search, run_search, search_summary

    t1 = time.perf_counter()
    searches = run_search(ctx, problem, st, ds)  # fresh starts at every sigma: what no scan path crosses
    timings["global_search"] = time.perf_counter() - t1
    t1 = time.perf_counter()
    c = None if no_maps else problem.coefficients()
    shoot = _shoot_ode(ctx, problem, st, ds, pred, c, searches)
    timings["shooting"] = time.perf_counter() - t1
    M_top = max([M_maps] + list(shoot["windows"]))
    ode = {M: shoot["windows"].get(M) for M in range(1, M_top + 1)}
    for k in VARIANT_KEYS:
        for M in range(1, M_top + 1):
            pred[k].setdefault(M, None)
    windows = {"ode": ode, **pred}
    grid = st.scan_grid
    applies = _applicability(problem, st, pred, no_maps)
    stop = period_adding_stop(ode, M_AUTO_LIMIT) if problem.M_max is None else None
    scan = {d: sweep_windows(grid, ds["period"].sel(direction=d).values, ds["orbit_impacts"].sel(direction=d).values)
            for d in ("up", "down")}
    variants = {k: windows[k] for k in VARIANT_KEYS if applies[k] is None}
    from .plots import labels_for, plot_all
    from .summary import coexistence, summary_lines

    best, score = best_variant(ode, variants) if variants and any(w is not None for w in ode.values()) else (None, {})
    coincident = _coincident_edges(ctx, shoot["all"])  # before the figures and the coexistence
    t1 = time.perf_counter()
    files = plot_all(ctx, problem, st, ds, windows, applies, shoot["all"]) if ctx.figures else []
    timings["plots"] = time.perf_counter() - t1
    files.append(_write_scans(ctx, ds))
    result = {
        "figure": ctx.target,
        "windows": windows,
        "ode_windows_all": shoot["all"],
        "map_applicability": applies,
        "period_adding_stop": stop,
        "edge_kinds": {"ode": shoot["kinds"]},
        "ode_edge_brackets": shoot["brackets"],
        "ode_edge_intervals": shoot["intervals"],
        "ode_unresolved": shoot["unresolved"],
        "ode_multipliers_at_lower_edge": shoot["multipliers_at_lower_edge"],
        "scan_windows": scan,
        "scan_confirmation": scan_confirmation(ode, scan["up"], scan["down"]),
        "scan_grid_step": float(grid[1] / grid[0] - 1.0) if st.log_sigma else float(grid[1] - grid[0]),
        "scan_grid_geometric": st.log_sigma,
        "differences_to_ode": {k: window_differences(ode, w) for k, w in variants.items()},
        "max_abs_difference_to_ode": score,
        "best_variant": best,
        "coexistence": coexistence(shoot["all"], st.sigma_range),
        "coincident_edges": coincident,
        "global_search": search_summary(st.scan_grid, searches),
        "ode_set_aside": shoot["transients"],
        "found_only_by_global_search": [f"{r['M']}/{r['impacts']}" for r in found_only_by_search(shoot["all"])],
        "files": files,
        "timings_s": timings,
        "parameters": _parameters(problem, st, shoot, c),
    }
    result["summary"] = summary_lines(result, labels_for(problem), VARIANT_KEYS)
    result["verdict"] = result["summary"][0]
    return result, report(ctx, problem, result)


def _global_options(starts: int | None, path: str) -> tuple[int, str]:
    """(starts per sigma, path) of the global search, checked: 0 starts turn it off."""
    from ...runs.basins.global_search import DEFAULT_STARTS, PATHS

    n = DEFAULT_STARTS if starts is None else starts
    if isinstance(n, bool) or not isinstance(n, int) or n < 0:
        raise HarnessInputError("--global-starts", f"must be an integer >= 0 (0: no global search), got {starts!r}")
    if path not in PATHS:
        raise HarnessInputError("--global-path", f"must be one of {', '.join(PATHS)}, got {path!r}")
    return n, path


def compare_windows(alpha: float | None = None, gamma: float | None = None, *, nu: float | None = None,
                    Omega: float | None = None, r: float = 0.9, wall: str = "compliant", Gamma: float = 10.0,
                    M_max: int | None = None, quick: bool = False, out: str | Path = "results/windows",
                    workers: int | None = None, progress: bool = False, fmu_path: str | None = None,
                    solver: str | None = None, map_wall: str = "auto", branch: int | None = None,
                    sigma_range: tuple[float, float] | None = None, xtol: float | None = None,
                    theta: float = SECTION_PHASE, global_starts: int | None = None,
                    global_path: str = "auto", run: Any = None, command: str | None = None,
                    figures: bool = True, scan_points: int | None = None) -> dict[str, Any]:
    """Window edges of the maps and of the ODE (FMU) for one parameter set.

    Give either (``alpha``, ``gamma``) of the map (9) or (``nu``, ``Omega``) of the ODE.
    Writes ``report.md``, ``windows.json``, plots and the scans' NetCDF into ``out`` and
    returns the result (the JSON's content): ``result["windows"]["ode"][M] = (lo, hi)``
    (an edge None: unresolved, or no upper edge for M = 1), the same for ``"theory_64"``,
    ``"map"``, ``"map_A_tilde"``; ``result["edge_kinds"]["ode"]``, ``result["parameters"]``.
    ``map_wall`` chooses the maps' coefficients: "auto" follows ``wall`` ((48) compliant, (39)
    rigid); "compliant-high" uses (39) with a compliant wall (high-velocity impacts, stiff wall).
    ``global_starts``: fresh starts of the global search at every sigma of the grid (default
    1000; 0: none), ``global_path`` its path ("auto", "batch", "fmu":
    :func:`harness.runs.basins.global_search.global_search`).
    ``sigma_range`` (lo, hi): scan and shoot exactly there, sigma <= 0 allowed (the wall-free
    orbit is then a window, grazing at sigma = 0); ``xtol``: an absolute bisection tolerance in
    sigma; ``theta``: the section phase. ``result["coexistence"]`` lists where attractors coexist,
    ``result["summary"]`` the summary's sentences, each derived from the tables.

    ``run``: the run object (:class:`~harness.runs.experiment.Experiment`: the FMU, the solver,
    workers, progress and any other FMU parameter) the command line built from its layers;
    without it one is built from ``fmu_path``, ``solver``, ``workers`` and ``progress``, with the
    same defaults and checks.  ``command``: the command line recorded in the report.
    ``figures=False``: no PNG (the JSON, report and NetCDF only).  ``scan_points``: the scan grid's
    points over the range (default: 121 quick and 401 full on an even grid, 24 and 80 per decade on
    a geometric one).

    A worker pool is used for the scans and the shooting: call it from a script under
    ``if __name__ == "__main__":`` (the workers re-import the main module).
    """
    if (alpha is None) != (gamma is None) or (nu is None) != (Omega is None) or (alpha is None) == (nu is None):
        raise HarnessInputError("nu" if alpha is None and gamma is None else "alpha",
                                "give exactly one pair: (alpha, gamma) or (nu, Omega)")
    kw = dict(r=_real(r, "r"), wall=wall, Gamma=_real(Gamma, "Gamma"),
              M_max=None if M_max in (None, "auto") else int(M_max), map_wall=map_wall, theta=_real(theta, "theta"))
    problem = (WindowProblem.from_alpha_gamma(_real(alpha, "alpha"), _real(gamma, "gamma"), branch, **kw)
               if alpha is not None else WindowProblem(_real(nu, "nu"), _real(Omega, "Omega"), **kw))
    if run is None:
        from ...runs.experiment import Experiment

        run = Experiment.for_python(fmu_path, solver, workers, progress)
    rng = None if sigma_range is None else (_real(sigma_range[0], "sigma_range"), _real(sigma_range[1], "sigma_range"))
    settings = default_settings(problem, quick, rng, xtol, scan_points)
    settings.global_starts, settings.global_path = _global_options(global_starts, global_path)
    ctx = Context("windows", out, quick, run, command or _python_call(problem, quick, out, rng, xtol), figures)
    result, text = run_windows(ctx, problem, settings)
    write_outputs(ctx, result, text)
    return result


def _real(value: Any, argument: str) -> float:
    """``value`` as a float, or an error naming ``argument``."""
    try:
        return float(value)
    except (TypeError, ValueError):
        raise HarnessInputError(argument, f"expected a number, got {value!r}") from None


def _python_call(problem: WindowProblem, quick: bool, out: Any, sigma_range: Any, xtol: Any) -> str:
    """How a Python caller asked the question (the report's footer where no command line ran)."""
    return (f"compare_windows(nu={problem.nu!r}, Omega={problem.Omega!r}, r={problem.r!r}, wall={problem.wall!r}, "
            f"Gamma={problem.Gamma!r}, M_max={problem.M_max!r}, theta={problem.theta!r}, quick={quick!r}, "
            f"sigma_range={sigma_range!r}, xtol={xtol!r}, out={str(out)!r})")
