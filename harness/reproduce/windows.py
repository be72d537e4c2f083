"""Map vs ODE window edges for any parameter set: ``impact-harness windows`` and
:func:`compare_windows`.

For (alpha, gamma) or (nu, Omega), restitution r and a wall (rigid, or compliant with
stiffness Gamma), four sources of the sigma-edges of the stable maximal period-M windows
(one impact per M forcing periods):

* ``theory_64``   -- (64), rho in [1/(4M), 1/M^2], with rho(sigma) linear ((48) for the
  compliant wall, (39) for the rigid one);
* ``map``         -- the 2D map (37)/(38) with the same coefficients (closed-form orbits);
* ``map_A_tilde`` -- the same with |A~(sigma)| in rho (docs/theory.md, "The A~ variant");
* ``ode``         -- the FMU: Newton shooting on its stroboscopic M-period map, started in
  the A~ map's window, each edge bracketed and bisected by the shooting itself
  (:func:`harness.dynamics.shooting.map_guided_windows`); confirmed by quasi-static up/down scans.

Output in DIR: ``report.md``, ``windows.json`` (``{"windows": {"ode": {"1": [lo, hi], ...},
"theory_64": ..., "map": ..., "map_A_tilde": ...}, "parameters": ...}``, the format of
``fig9.json``), ``windows_map.png``, ``windows_ode.png``, ``windows_windows.png`` and the
scans as NetCDF.  ``reproduce fig9`` is this comparison with the paper's parameters.
"""
from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mapcheck.coeffs import Coefficients, coefficients
from mapcheck.compare import (
    best_variant,
    predicted_windows,
    scan_confirmation,
    sweep_windows,
    window_differences,
)
from mapcheck.linear import alpha_gamma, invert_alpha_gamma

from ..errors import HarnessInputError
from . import Context, write_outputs
from .windows_report import SCAN_TOL, VARIANT_KEYS, report

__all__ = ["WindowProblem", "WindowSettings", "compare_windows", "run_windows", "default_settings"]

#: FMU ``wall`` parameter codes.
WALL_CODES = {"compliant": 1, "rigid": 2}
#: Coefficients of the maps: "auto" (from the wall), or a ``wall`` of :func:`mapcheck.coeffs.coefficients`.
MAP_WALLS = ("auto", "compliant", "compliant-high", "rigid")
#: Highest period classified by the scans (and searched with --M-max auto).
M_AUTO_LIMIT = 12


@dataclass(frozen=True)
class WindowProblem:
    """One parameter set: the oscillator, the wall, and the periods looked at.

    Attributes
    ----------
    nu, Omega : float
        Forcing-to-natural frequency ratio and its damped counterpart (the FMU's parameters).
    r : float
        Coefficient of restitution (rigid wall) / of the compliant wall's damping.
    wall : {"compliant", "rigid"}
    Gamma : float
        Stiffness of the compliant wall (ignored for a rigid wall).
    M_max : int or None
        Highest period looked at; None ("auto"): until period adding truncates (no stable
        maximal window at M and M + 1), up to :data:`M_AUTO_LIMIT`.
    theta : float
        Phase of the FMU's stroboscopic section (1/2: half a period from the impacts).
    """

    nu: float
    Omega: float
    r: float = 0.9
    wall: str = "compliant"
    Gamma: float = 10.0
    M_max: int | None = 4
    theta: float = 0.5
    map_wall: str = "auto"

    def __post_init__(self) -> None:
        if self.wall not in WALL_CODES:
            raise HarnessInputError("--wall", f"must be compliant or rigid, got {self.wall!r}")
        if self.map_wall not in MAP_WALLS:
            raise HarnessInputError("--map", f"must be one of {', '.join(MAP_WALLS)}, got {self.map_wall!r}")
        if not (0.0 < self.r <= 1.0):
            raise HarnessInputError("--r", f"must be in (0, 1], got {self.r}")
        if self.wall == "compliant" and not self.Gamma > 0:
            raise HarnessInputError("--Gamma", f"must be > 0, got {self.Gamma}")
        if not (self.nu > 0 and self.Omega > 0):
            raise HarnessInputError("--nu/--Omega", f"must be > 0, got nu = {self.nu}, Omega = {self.Omega}")
        if self.M_max is not None and not 1 <= self.M_max <= M_AUTO_LIMIT:
            raise HarnessInputError("--M-max", f"must be 'auto' or in 1..{M_AUTO_LIMIT}, got {self.M_max}")

    @classmethod
    def from_alpha_gamma(cls, alpha: float, gamma: float, branch: int | None = None, **kw: Any) -> "WindowProblem":
        """From the map's (alpha, gamma) of (9): unique when P(1) has real eigenvalues; underdamped
        (alpha^2 < 4 gamma) the psi branch must be chosen (it sets sign(P12) = c1).  Whether the
        maps apply to the oscillator is reported by the run, as for --nu/--Omega."""
        if not 0.0 < gamma < 1.0:
            raise HarnessInputError("--gamma", f"gamma = det P(1) = exp(-nu) must lie in (0, 1) (nu > 0), got {gamma}")
        try:
            inv = invert_alpha_gamma(alpha, gamma, branch)
        except (ValueError, ArithmeticError) as exc:
            raise HarnessInputError("--alpha/--gamma", f"no (nu, Omega) for ({alpha}, {gamma}): {exc}"
                                    + ("; give --branch 0, 1, ... or --nu/--Omega" if "branch" in str(exc) else "")
                                    ) from exc
        return cls(float(inv.nu), float(inv.Omega), **kw)

    @property
    def alpha_gamma(self) -> tuple[float, float]:
        a, g = alpha_gamma(self.nu, self.Omega)
        return float(a), float(g)

    @property
    def map_coefficients_wall(self) -> str:
        """The ``wall`` of :func:`mapcheck.coeffs.coefficients` for the maps: by default the FMU's
        wall ((48) low-velocity map for compliant, (39) for rigid); ``map_wall`` overrides it,
        e.g. "compliant-high" ((39): high-velocity impacts on a stiff compliant wall)."""
        return self.wall if self.map_wall == "auto" else self.map_wall

    def coefficients(self) -> Coefficients:
        return coefficients(self.nu, self.Omega, self.r, self.map_coefficients_wall)

    def fmu_params(self) -> dict[str, Any]:
        p: dict[str, Any] = {"nu": self.nu, "Omega": self.Omega, "r": self.r, "wall": WALL_CODES[self.wall]}
        if self.wall == "compliant":
            p["Gamma"] = self.Gamma
        return p

    def describe(self) -> str:
        a, g = self.alpha_gamma
        wall = f"compliant wall, Gamma = {self.Gamma:g}" if self.wall == "compliant" else "rigid wall"
        return f"(alpha, gamma) = ({a:.4g}, {g:.4g}), r = {self.r:g}, {wall}"

    def coefficient_eq(self) -> str:
        return "(48)" if self.map_coefficients_wall == "compliant" else "(39)"


@dataclass
class WindowSettings:
    """How hard to look.

    Attributes
    ----------
    scan_grid : ndarray
        Sorted sigma values of the up/down scans (and of the map's bifurcation diagrams).
    transient, samples : int
        Periods per scan point before classifying, and periods sampled.
    xtol : float or None
        Bisection tolerance of the shooting in sigma (absolute); None: ``xtol_rel`` times the
        sigma where the window was seen.
    sigma_range : (float, float)
        Search range of the shooting.
    table_grid : ndarray
        sigma grid of the 2D maps' window search.
    log_sigma : bool
        Geometric scan grid (windows spread over decades of sigma): log axes in the plots.
    """

    scan_grid: np.ndarray
    transient: int
    samples: int
    xtol: Any
    sigma_range: tuple[float, float]
    table_grid: np.ndarray
    log_sigma: bool = False
    extra: dict[str, Any] = field(default_factory=dict)
    xtol_rel: float = 1e-3


#: The sigma range every default scan covers, whatever the maps say (geometric grid): the
#: windows of the oscillators tried so far lie inside it (Figure 9: 0.12 to 0.8; underdamped
#: nu = 0.8, Omega = 2.5, r = 0.8: period 1 from 1.6 (rigid), period 2 to 0.125 (Gamma = 100)).
BASE_RANGE = (1e-3, 3.0)


def map_guide(problem: WindowProblem, M_max: int) -> tuple[Coefficients | None, str | None]:
    """The maps' coefficients, or None with the reason they do not exist."""
    try:
        return problem.coefficients(), None
    except (ValueError, ArithmeticError) as exc:
        return None, str(exc)


def default_settings(problem: WindowProblem, quick: bool) -> WindowSettings:
    """Grids and tolerances: the ODE is scanned over :data:`BASE_RANGE`, widened to hold the
    maps' windows where the maps give finite ones, on a geometric grid (24 points per decade
    quick, 80 full); the shooting may follow an orbit beyond the grid, a decade below and a factor
    4 above.  The bisection tolerance is relative to the window's sigma (1e-3 quick, 1e-4 full)."""
    lo, hi = BASE_RANGE
    c, _ = map_guide(problem, problem.M_max or M_AUTO_LIMIT)
    table_grid = np.geomspace(1e-6, 1e3, 12001)
    if c is not None:
        with np.errstate(all="ignore"):
            s_1 = float(max(c.sigma_of_rho(0.25, "paper"), c.sigma_of_rho(0.25, "tilde")))
            if not math.isfinite(s_1):
                s_1 = float(c.sigma_of_rho(0.25, "paper"))
        if math.isfinite(s_1) and s_1 > 0:
            table_grid = np.geomspace(1e-5 * s_1, 4.0 * s_1, 12001)
            guide = predicted_windows(c, problem.M_max or 8, table_grid)["map_A_tilde"]
            los = [w[0] for w in guide.values() if w is not None and w[0] is not None]
            if los:
                lo, hi = min(lo, 0.7 * min(los)), max(hi, 2.5 * s_1)
    lo, hi = max(lo, 1e-6), min(hi, 1e3)
    # the maps are cheap: search them over the ODE's whole range too
    table_grid = np.geomspace(min(table_grid[0], 0.01 * lo), max(table_grid[-1], 4.0 * hi), 16001)
    per_decade = 24 if quick else 80
    n = int(math.ceil(per_decade * math.log10(hi / lo))) + 1
    grid = np.geomspace(lo, hi, n)
    return WindowSettings(scan_grid=grid, transient=200 if quick else 300, samples=24 if quick else 40,
                          xtol=None, sigma_range=(0.1 * lo, 4.0 * hi), table_grid=table_grid, log_sigma=True,
                          xtol_rel=1e-3 if quick else 1e-4)


# ----------------------------------------------------------------------------------------
# The measurements
# ----------------------------------------------------------------------------------------
def _workers(ctx: Context) -> int:
    from ..config import default_workers

    return ctx.workers or min(2, default_workers())


def ode_scans(ctx: Context, problem: WindowProblem, st: WindowSettings):
    """Quasi-static up and down scans of the FMU over sigma (the harness's sweeps)."""
    from ..config import SamplingSpec, SweepSpec
    from ..runs.sweeps import run_sweep

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
    return run_sweep(ctx.fmu, spec, ctx.params(**problem.fmu_params()), state0, sampling,
                     workers=_workers(ctx), progress=ctx.progress)


def _safe_predictions(problem: WindowProblem, M_maps: int, st: WindowSettings) -> tuple[dict[str, dict], str | None]:
    """The maps' windows, or empty tables with the reason the maps do not exist."""
    c, why = map_guide(problem, M_maps)
    if c is None:
        return {k: {M: None for M in range(1, M_maps + 1)} for k in VARIANT_KEYS}, why
    with np.errstate(all="ignore"):
        return predicted_windows(c, M_maps, st.table_grid), None


def run_windows(ctx: Context, problem: WindowProblem, st: WindowSettings,
                predicted: dict[str, dict] | None = None) -> tuple[dict[str, Any], str]:
    """The comparison: the ODE's windows (scans over the whole range, each attractor shot to its
    edges), then the maps' predictions beside them; returns (result, report)."""
    from mapcheck.applicability import map_applicability

    from ..dynamics.shooting import StroboscopicMap
    from .ode_windows import measure, period_adding_stop

    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    M_maps = problem.M_max or 8
    pred, no_maps = (predicted, None) if predicted is not None else _safe_predictions(problem, M_maps, st)
    timings["maps"] = time.perf_counter() - t0
    # scans first, then the shooting (on 2 cores a sweep beside the shooting slowed both)
    t1 = time.perf_counter()
    ds = ode_scans(ctx, problem, st)
    timings["scans"] = time.perf_counter() - t1
    t1 = time.perf_counter()
    smap = StroboscopicMap(ctx.simulator(), ctx.params(**problem.fmu_params()), problem.theta)
    c = None if no_maps else problem.coefficients()
    shoot = measure(smap, st.scan_grid, ds, st.sigma_range, st.xtol if st.xtol is not None else st.xtol_rel,
                    problem.M_max, None if no_maps else pred["map_A_tilde"], c, _workers(ctx),
                    relative=st.xtol is None)
    timings["shooting"] = time.perf_counter() - t1
    M_top = max([M_maps] + list(shoot["windows"]))
    ode = {M: shoot["windows"].get(M) for M in range(1, M_top + 1)}
    for k in VARIANT_KEYS:
        for M in range(1, M_top + 1):
            pred[k].setdefault(M, None)
    windows = {"ode": ode, **pred}
    a, g = problem.alpha_gamma
    grid = st.scan_grid
    applies = map_applicability(problem.nu, problem.Omega, problem.r, problem.map_coefficients_wall, a, g,
                                pred, (float(st.table_grid[0]), float(st.table_grid[-1])))
    if no_maps:
        applies = {k: f"the maps' coefficients do not exist: {no_maps}" for k in VARIANT_KEYS}
    stop = period_adding_stop(ode, M_AUTO_LIMIT) if problem.M_max is None else None
    scan = {d: sweep_windows(grid, ds["period"].sel(direction=d).values, ds["orbit_impacts"].sel(direction=d).values)
            for d in ("up", "down")}
    confirm = scan_confirmation(ode, scan["up"], scan["down"])
    variants = {k: windows[k] for k in VARIANT_KEYS if applies[k] is None}
    if variants and any(w is not None for w in ode.values()):
        best, score = best_variant(ode, variants)
    else:
        best, score = None, {}
    diffs = {k: window_differences(ode, w) for k, w in variants.items()}
    t1 = time.perf_counter()
    from .windows_plots import plot_all

    files = plot_all(ctx, problem, st, ds, windows, applies)
    timings["plots"] = time.perf_counter() - t1
    ds.attrs["reproduce.target"] = ctx.target
    from ..io.results import write_netcdf

    write_netcdf(ds, ctx.out / f"{ctx.target}_ode_scans.nc")
    files.append(f"{ctx.target}_ode_scans.nc")
    finite = {k: v for k, v in score.items() if math.isfinite(v)}
    if finite and best is not None:
        verdict = (f"best map variant: {best} (largest edge difference to the ODE {score[best]:.2g} in sigma)"
                   + "".join(f"; {k}: {v:.2g}" for k, v in score.items() if k != best))
    elif not any(w is not None for w in ode.values()):
        verdict = (f"the ODE has no stable maximal (one impact per period) window in sigma "
                   f"[{st.sigma_range[0]:.3g}, {st.sigma_range[1]:.3g}]; maps not compared")
    elif not variants:
        verdict = "no map applies to this oscillator (reasons in report.md); ODE windows only"
    else:
        verdict = "the maps miss windows that the ODE has (differences in report.md)"
    step = float(grid[1] / grid[0] - 1.0) if st.log_sigma else float(grid[1] - grid[0])
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
        "scan_confirmation": confirm,
        "scan_grid_step": step,
        "scan_grid_geometric": st.log_sigma,
        "differences_to_ode": diffs,
        "max_abs_difference_to_ode": score,
        "best_variant": best,
        "verdict": verdict,
        "files": files,
        "timings_s": timings,
        "parameters": {
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
        },
    }
    return result, report(ctx, problem, result)


def compare_windows(alpha: float | None = None, gamma: float | None = None, *, nu: float | None = None,
                    Omega: float | None = None, r: float = 0.9, wall: str = "compliant", Gamma: float = 10.0,
                    M_max: int | None = None, quick: bool = False, out: str | Path = "results/windows",
                    workers: int | None = None, progress: bool = False, fmu_path: str | None = None,
                    solver: str = "cvode", map_wall: str = "auto", branch: int | None = None) -> dict[str, Any]:
    """Window edges of the maps and of the ODE (FMU) for one parameter set.

    Give either (``alpha``, ``gamma``) of the map (9) or (``nu``, ``Omega``) of the ODE.
    Writes ``report.md``, ``windows.json``, plots and the scans' NetCDF into ``out`` and
    returns the result (the JSON's content): ``result["windows"]["ode"][M] = (lo, hi)``
    (an edge None: unresolved, or no upper edge for M = 1), the same for ``"theory_64"``,
    ``"map"``, ``"map_A_tilde"``; ``result["edge_kinds"]["ode"]``, ``result["parameters"]``.
    ``map_wall`` chooses the maps' coefficients: "auto" follows ``wall`` ((48) compliant, (39)
    rigid); "compliant-high" uses (39) with a compliant wall (high-velocity impacts, stiff wall).

    A worker pool is used for the scans and the shooting: call it from a script under
    ``if __name__ == "__main__":`` (the workers re-import the main module).
    """
    if (alpha is None) != (gamma is None) or (nu is None) != (Omega is None) or (alpha is None) == (nu is None):
        raise HarnessInputError("--alpha/--gamma, --nu/--Omega", "give exactly one pair: (alpha, gamma) or (nu, Omega)")
    kw = dict(r=float(r), wall=wall, Gamma=float(Gamma), M_max=None if M_max in (None, "auto") else int(M_max),
              map_wall=map_wall)
    problem = (WindowProblem.from_alpha_gamma(float(alpha), float(gamma), branch, **kw) if alpha is not None
               else WindowProblem(float(nu), float(Omega), **kw))
    if workers is not None and workers < 1:
        raise HarnessInputError("--workers", f"must be >= 1, got {workers}")
    ctx = Context("windows", out, quick, workers, progress, fmu_path, solver)
    ctx.command = command_line(problem, quick, out)
    result, text = run_windows(ctx, problem, default_settings(problem, quick))
    write_outputs(ctx, result, text)
    return result


def problem_dict(problem: WindowProblem) -> dict[str, Any]:
    return asdict(problem)


def command_line(problem: WindowProblem, quick: bool, out: Any) -> str:
    a, g = problem.alpha_gamma
    wall = f"--wall compliant --Gamma {problem.Gamma:g}" if problem.wall == "compliant" else "--wall rigid"
    if problem.map_wall != "auto":
        wall += f" --map {problem.map_wall}"
    return (f"windows --nu {problem.nu!r} --Omega {problem.Omega!r} --r {problem.r:g} {wall} --M-max {problem.M_max or 'auto'}"
            f"{' --quick' if quick else ''} --out {out}")
