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

import argparse
import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from mapcheck.coeffs import Coefficients, coefficients
from mapcheck.compare import (
    best_variant,
    markdown_window_table,
    phase_to_natural,
    predicted_windows,
    scan_confirmation,
    sweep_windows,
    window_differences,
)
from mapcheck.linear import alpha_gamma, invert_alpha_gamma

from ..errors import HarnessInputError
from . import Context, write_outputs
from .windows_report import SCAN_TOL, VARIANT_KEYS, report

__all__ = ["WindowProblem", "WindowSettings", "compare_windows", "run_windows", "default_settings", "register"]

#: FMU ``wall`` parameter codes.
WALL_CODES = {"compliant": 1, "rigid": 2}
#: Coefficients of the maps: "auto" (from the wall), or a ``wall`` of :func:`mapcheck.coeffs.coefficients`.
MAP_WALLS = ("auto", "compliant", "compliant-high", "rigid")


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
    M_max : int
        Highest period looked at.
    theta : float
        Phase of the FMU's stroboscopic section (1/2: half a period from the impacts).
    """

    nu: float
    Omega: float
    r: float = 0.9
    wall: str = "compliant"
    Gamma: float = 10.0
    M_max: int = 4
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
        if not 1 <= self.M_max <= 8:
            raise HarnessInputError("--M-max", f"must be in 1..8, got {self.M_max}")

    @classmethod
    def from_alpha_gamma(cls, alpha: float, gamma: float, **kw: Any) -> "WindowProblem":
        """From the map's (alpha, gamma) of (9) (the overdamped, unique inverse)."""
        if not (0.0 < alpha < 1.0 and 0.0 < gamma < 1.0):
            raise HarnessInputError("--alpha/--gamma", f"must lie in (0, 1), got ({alpha}, {gamma})")
        try:
            inv = invert_alpha_gamma(alpha, gamma)
        except (ValueError, ArithmeticError) as exc:
            raise HarnessInputError("--alpha/--gamma", f"no (nu, Omega) for ({alpha}, {gamma}): {exc}") from exc
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
    xtol : float or dict
        Bisection tolerance of the shooting in sigma (or {M: xtol}).
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


def default_settings(problem: WindowProblem, quick: bool) -> WindowSettings:
    """Grids and tolerances from where the maps put the windows.

    The period-1 flip of the linear-rho and A~ maps (rho = 1/4) sets the top of the range;
    the 2D maps' windows are searched on a geometric grid over five decades below it (the
    2D map's windows of high M can lie far below (64)'s, where the 1D reduction fails), and
    the scans and the shooting cover the A~ map's windows with margin.  When these spread
    over more than a decade of sigma the scan grid is geometric.  The shooting's tolerance
    is a fraction of each window's width (1e-2 quick, 1e-3 full), at most 1e-4 / 1e-5.
    """
    c = problem.coefficients()
    s_1 = float(max(c.sigma_of_rho(0.25, "paper"), c.sigma_of_rho(0.25, "tilde")))
    if not math.isfinite(s_1):  # rho~ saturates below 1/4: the period-1 flip is at no sigma
        s_1 = float(c.sigma_of_rho(0.25, "paper"))
    table_grid = np.geomspace(1e-5 * s_1, 4.0 * s_1, 12001)
    guide = predicted_windows(c, problem.M_max, table_grid)["map_A_tilde"]
    los = [w[0] for w in guide.values() if w is not None]
    s_min = min(los) if los else float(c.sigma_of_rho(1.0 / (4.0 * problem.M_max), "tilde"))
    widths = {M: (w[1] if w[1] is not None else 2.0 * w[0]) - w[0] for M, w in guide.items() if w is not None}
    frac, cap = (1e-2, 1e-4) if quick else (1e-3, 1e-5)
    xtol = {M: min(cap, frac * max(wd, 1e-12)) for M, wd in widths.items()}
    s_scan_lo, s_scan_hi = 0.7 * s_min, 2.5 * s_1  # M = 1 and M = 2 overlap: see both
    log_sigma = s_scan_hi / s_scan_lo > 10.0
    n = 91 if quick else 361
    grid = np.geomspace(s_scan_lo, s_scan_hi, n) if log_sigma else np.linspace(s_scan_lo, s_scan_hi, n)
    return WindowSettings(scan_grid=grid, transient=200 if quick else 300, samples=24 if quick else 40,
                          xtol=xtol, sigma_range=(0.5 * s_min, 4.0 * s_1), table_grid=table_grid,
                          log_sigma=log_sigma)


# ----------------------------------------------------------------------------------------
# The measurements
# ----------------------------------------------------------------------------------------
def _workers(ctx: Context) -> int:
    from ..config import default_workers

    return ctx.workers or min(2, default_workers())


def ode_windows(ctx: Context, problem: WindowProblem, guide: dict, st: WindowSettings) -> dict[str, Any]:
    """ODE windows by Newton shooting on the FMU, started in the A~ map's windows."""
    from ..dynamics.shooting import StroboscopicMap, map_guided_windows

    smap = StroboscopicMap(ctx.simulator(), ctx.params(**problem.fmu_params()), problem.theta)
    return map_guided_windows(smap, problem.coefficients(), guide, st.sigma_range, st.xtol, workers=_workers(ctx))


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


def run_windows(ctx: Context, problem: WindowProblem, st: WindowSettings,
                predicted: dict[str, dict] | None = None) -> tuple[dict[str, Any], str]:
    """The comparison: maps' predictions, scans, shooting, plots; returns (result, report)."""
    c = problem.coefficients()
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    pred = predicted if predicted is not None else predicted_windows(c, problem.M_max, st.table_grid)
    timings["maps"] = time.perf_counter() - t0
    # scans first, then the shooting (on 2 cores a sweep beside the shooting slowed both)
    t1 = time.perf_counter()
    ds = ode_scans(ctx, problem, st)
    timings["scans"] = time.perf_counter() - t1
    t1 = time.perf_counter()
    shoot = ode_windows(ctx, problem, pred["map_A_tilde"], st)
    timings["shooting"] = time.perf_counter() - t1
    windows = {"ode": shoot["windows"], **pred}
    grid = st.scan_grid
    scan = {d: sweep_windows(grid, ds["period"].sel(direction=d).values, ds["orbit_impacts"].sel(direction=d).values)
            for d in ("up", "down")}
    confirm = scan_confirmation(shoot["windows"], scan["up"], scan["down"])
    variants = {k: windows[k] for k in VARIANT_KEYS}
    best, score = best_variant(windows["ode"], variants)
    diffs = {k: window_differences(windows["ode"], w) for k, w in variants.items()}
    t1 = time.perf_counter()
    from .windows_plots import plot_all

    files = plot_all(ctx, problem, st, ds, windows)
    timings["plots"] = time.perf_counter() - t1
    ds.attrs["reproduce.target"] = ctx.target
    from ..io.results import write_netcdf

    write_netcdf(ds, ctx.out / f"{ctx.target}_ode_scans.nc")
    files.append(f"{ctx.target}_ode_scans.nc")
    finite = {k: v for k, v in score.items() if math.isfinite(v)}
    verdict = (f"best map variant: {best} (largest edge difference to the ODE {score[best]:.2g} in sigma); "
               + ", ".join(f"{k}: {v:.2g}" for k, v in score.items() if k != best)) if finite else \
        "no map variant could be compared with the ODE (windows missing)"
    a, g = problem.alpha_gamma
    step = float(grid[1] / grid[0] - 1.0) if st.log_sigma else float(grid[1] - grid[0])
    result = {
        "figure": ctx.target,
        "windows": windows,
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
            "Gamma": problem.Gamma if problem.wall == "compliant" else None, "M_max": problem.M_max,
            "rho_per_sigma": c.rho_per_sigma, "theta": problem.theta,
            "sigma_grid": [float(grid[0]), float(grid[-1]), int(len(grid))], "transient": st.transient,
            "samples": st.samples, "shooting_xtol": st.xtol, "shooting_sigma_range": list(st.sigma_range),
            "fmu_periods_shooting": shoot["fmu_periods"], "shooting_derivatives": shoot["derivatives"], **st.extra,
        },
    }
    return result, report(ctx, problem, result)


def compare_windows(alpha: float | None = None, gamma: float | None = None, *, nu: float | None = None,
                    Omega: float | None = None, r: float = 0.9, wall: str = "compliant", Gamma: float = 10.0,
                    M_max: int = 4, quick: bool = False, out: str | Path = "results/windows",
                    workers: int | None = None, progress: bool = False, fmu_path: str | None = None,
                    solver: str = "cvode", map_wall: str = "auto") -> dict[str, Any]:
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
    kw = dict(r=float(r), wall=wall, Gamma=float(Gamma), M_max=int(M_max), map_wall=map_wall)
    problem = (WindowProblem.from_alpha_gamma(float(alpha), float(gamma), **kw) if alpha is not None
               else WindowProblem(float(nu), float(Omega), **kw))
    if workers is not None and workers < 1:
        raise HarnessInputError("--workers", f"must be >= 1, got {workers}")
    ctx = Context("windows", out, quick, workers, progress, fmu_path, solver)
    ctx.command = _command_line(problem, quick, out)
    result, text = run_windows(ctx, problem, default_settings(problem, quick))
    write_outputs(ctx, result, text)
    return result


def _command_line(problem: WindowProblem, quick: bool, out: Any) -> str:
    a, g = problem.alpha_gamma
    wall = f"--wall compliant --Gamma {problem.Gamma:g}" if problem.wall == "compliant" else "--wall rigid"
    if problem.map_wall != "auto":
        wall += f" --map {problem.map_wall}"
    return (f"windows --nu {problem.nu!r} --Omega {problem.Omega!r} --r {problem.r:g} {wall} --M-max {problem.M_max}"
            f"{' --quick' if quick else ''} --out {out}")


def register(sub: Any, parents: dict[str, argparse.ArgumentParser]) -> None:
    """Add the ``windows`` subcommand."""
    p = sub.add_parser(
        "windows", help="window edges of the maps vs the ODE (FMU) for any parameter set, with a report",
        description="For (alpha, gamma) or (nu, Omega), r and a wall: the sigma-edges of the stable maximal "
        "period-M windows from (64), the 2D map (37)/(38), the 2D map with A~(sigma), and the ODE (FMU; Newton "
        "shooting, every edge bracketed and bisected, confirmed by up/down scans). Writes report.md, windows.json "
        "(fig9.json's format), PNG plots and the scans' NetCDF into --out.")
    g = p.add_argument_group("parameter set (one pair)")
    g.add_argument("--alpha", type=float, help="map parameter alpha of (9), in (0, 1)")
    g.add_argument("--gamma", type=float, help="map parameter gamma of (9), in (0, 1)")
    g.add_argument("--nu", type=float, help="FMU parameter nu (instead of --alpha/--gamma)")
    g.add_argument("--Omega", type=float, help="FMU parameter Omega (with --nu)")
    p.add_argument("--r", type=float, default=0.9, help="coefficient of restitution (default 0.9)")
    p.add_argument("--wall", choices=sorted(WALL_CODES), default="compliant",
                   help="compliant (map coefficients (48)) or rigid ((39)); default compliant")
    p.add_argument("--Gamma", type=float, default=10.0, help="compliant wall stiffness (default 10)")
    p.add_argument("--map", choices=MAP_WALLS, default="auto", dest="map_wall",
                   help="the maps' coefficients: auto (from --wall: (48) compliant, (39) rigid), or "
                   "compliant ((48), low-velocity impacts), compliant-high ((39), high-velocity impacts on a stiff "
                   "compliant wall), rigid ((39))")
    p.add_argument("--M-max", type=int, default=4, dest="M_max", help="highest period (default 4)")
    p.add_argument("--out", "-o", metavar="DIR", default="results/windows", help="output directory")
    p.add_argument("--quick", action="store_true", help="coarse scans and tolerances (seconds to a minute)")
    p.add_argument("--workers", "-j", type=int, metavar="N", help="worker processes (default: up to 2)")
    p.add_argument("--fmu", metavar="PATH", help="FMU (default build/fmu/ImpactOscillator.fmu)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.add_argument("--solver", choices=("cvode", "closed-form"), default="cvode",
                   help="the FMU's integrator (default cvode; closed-form: exact propagation, linear contact law)")
    p.set_defaults(func=cmd_windows)


def cmd_windows(args: argparse.Namespace) -> int:
    t0 = time.perf_counter()
    res = compare_windows(args.alpha, args.gamma, nu=args.nu, Omega=args.Omega, r=args.r, wall=args.wall,
                          Gamma=args.Gamma, M_max=args.M_max, quick=args.quick, out=args.out, workers=args.workers,
                          progress=not args.no_progress, fmu_path=args.fmu, solver=args.solver,
                          map_wall=args.map_wall)
    print(res["verdict"])
    print(markdown_window_table(res["windows"]))
    print(f"wrote {Path(args.out) / 'report.md'} and {Path(args.out) / 'windows.json'} "
          f"({time.perf_counter() - t0:.1f} s)")
    return 0


def problem_dict(problem: WindowProblem) -> dict[str, Any]:
    return asdict(problem)
