"""The subcommands simulate, strobe, sweep and jacobian.

Each command builds an :class:`~harness.runs.experiment.Experiment` (defaults < TOML < flags), runs,
writes a NetCDF file with full provenance and a PNG plot, and prints a short summary on
stdout.  Long runs show a tqdm progress bar on stderr.
"""
from __future__ import annotations

import argparse
import shutil
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from ..dynamics.classify import classify_orbit, windows
from ..runs.budget import Budget, grid_count, jacobian_estimate, simulate_estimate, strobe_estimate, sweep_estimate
from .main import count, overrides_from_args
from ..config import parameter_values
from ..runs.experiment import Experiment
from ..errors import HarnessInputError
from ..io.outputs import check_output, check_plot
from ..io.progress import progress_bar
from .resumable import run_resumable


def register(sub: Any, parents: dict[str, argparse.ArgumentParser]) -> None:
    """Add simulate, strobe, sweep and jacobian to the CLI."""
    common, sampling = parents["common"], parents["sampling"]

    p = sub.add_parser("simulate", parents=[common], help="time series of one run",
                       description="Integrate the FMU from (u0, v0) at --t0 and record u, v and impacts on a uniform grid.")
    g = p.add_argument_group("simulate")
    g.add_argument("--t0", dest="simulate__t0", type=float, metavar="T", help="start time (default 0; t = n is the grazing phase)")
    g.add_argument("--t-end", dest="simulate__t_end", type=float, metavar="T", help="end time (default 10)")
    g.add_argument("--dt", dest="simulate__dt", type=float, metavar="DT", help="output step (default 0.01)")
    p.set_defaults(func=cmd_simulate)

    p = sub.add_parser("strobe", parents=[common, sampling], help="stroboscopic samples at t = n + theta",
                       description="Sample (u, v) at t = n + theta after a transient, count impacts per period and "
                       "classify the orbit (period, impacts per period). Draws the Poincare section.")
    p.set_defaults(func=cmd_strobe)

    p = sub.add_parser("sweep", parents=[common, sampling], help="bifurcation sweep (fresh / up / down / both), 1D or 2D",
                       description="Sweep an FMU parameter (sigma by default): fresh starts from the same state, or "
                       "quasi-static continuation up and/or down carrying the state (both: one hysteresis loop, the down "
                       "scan starting where the up scan ended). Draws the bifurcation diagram.")
    g = p.add_argument_group("sweep")
    g.add_argument("--param", dest="sweep__param", metavar="NAME", help="swept FMU parameter (default sigma)")
    g.add_argument("--start", dest="sweep__start", type=float, metavar="X", help="first value (default 1.0)")
    g.add_argument("--stop", dest="sweep__stop", type=float, metavar="X", help="last value (default 0.1)")
    g.add_argument("--num", dest="sweep__num", type=count, metavar="N", help="number of values (default 91)")
    g.add_argument("--values", dest="sweep__values", metavar="V1,V2,...", help="explicit values (instead of start/stop/num)")
    g.add_argument("--mode", dest="sweep__mode", metavar="MODE",
                   help="fresh, up, down, or both: a hysteresis loop, up and then down from the state where the "
                   "up scan ended (up,down: two independent scans); comma-separated list allowed (default both)")
    g.add_argument("--scan", metavar="NAME=V1,V2,...|NAME=START:STOP:NUM",
                   help="second axis of a 2D scan, e.g. --scan Gamma=10,100,1000")
    execution_options(p, "sweep")
    p.set_defaults(func=cmd_sweep)

    p = sub.add_parser("jacobian", parents=[common], help="Jacobian of the stroboscopic map (at a state, or J(x) near grazing)",
                       description="Jacobian J of the one-period map: exact by default (the FMU's variational "
                       "equations with saltation matrices at impacts) when the FMU reports derivatives, else central "
                       "differences by restarts from perturbed states (--method). With --state: J at that state and its "
                       "eigenvalues (the Floquet multipliers of a fixed point). Without: J against x along the grazing "
                       "family (wall-free state (x, 0) at t = n), in the coordinates of phase --theta (0: the paper's "
                       "t = n, where J11, not J12, is singular), and the exponent q of |J11 - P11| ~ x^q with its "
                       "standard error and fitted x range (a compliant wall: soft and hard contacts fitted apart).")
    g = p.add_argument_group("jacobian")
    g.add_argument("--theta", dest="jacobian__theta", type=float, metavar="PHASE",
                   help="section phase of the coordinates, in [0, 1) (default 0)")
    g.add_argument("--measure-theta", dest="jacobian__measure_theta", type=float, metavar="PHASE",
                   help="phase where J is measured, away from the impact (default 0.5)")
    g.add_argument("--x-start", dest="jacobian__x_start", type=float, metavar="X", help="smallest x (default 1e-6)")
    g.add_argument("--x-stop", dest="jacobian__x_stop", type=float, metavar="X", help="largest x (default 1e-2)")
    g.add_argument("--x-num", dest="jacobian__x_num", type=count, metavar="N", help="number of x values, log-spaced (default 25)")
    g.add_argument("--state", dest="jacobian__state", metavar="U,V",
                   help="J and its eigenvalues (multipliers) at this state at t = theta, instead of a scan")
    g.add_argument("--method", dest="jacobian__method", choices=("auto", "exact", "fd"),
                   help="exact: the FMU's own derivatives (variational equations); fd: central differences; "
                   "auto (default): exact when the FMU reports them")
    p.set_defaults(func=cmd_jacobian)


# ----------------------------------------------------------------------------------------
def execution_options(p: argparse.ArgumentParser, what: str) -> None:
    """Where a grid of runs executes, and its checkpoint (sweep, basins)."""
    b = p.add_argument_group("execution")
    b.add_argument("--backend", dest="run__backend", choices=["serial", "processes", "dask"],
                   help="where to run (default processes, or dask with --scheduler)")
    b.add_argument("--workers", "-j", dest="run__workers", type=count, metavar="N",
                   help="local worker processes (default: all cores)")
    b.add_argument("--scheduler", dest="run__scheduler", metavar="tcp://HOST:PORT", help="run on this Dask scheduler")
    b.add_argument("--checkpoint", dest="run__checkpoint", metavar="DIR",
                   help=f"directory of finished points, to resume an interrupted {what} (default: OUT.partial)")
    b.add_argument("--no-resume", action="store_true", help="discard an existing checkpoint and start over")


def _experiment(args: argparse.Namespace, extra: dict[str, dict[str, Any]] | None = None) -> Experiment:
    layer = overrides_from_args(args)
    for section, entries in (extra or {}).items():
        layer.setdefault(section, {}).update(entries)
    return Experiment.from_sources(getattr(args, "config", None), layer)


def _outputs(args: argparse.Namespace, exp: Experiment, default_stem: str) -> tuple[Path, Path | None]:
    """The result and plot files, checked writable before any work is done."""
    out = check_output(exp.run.out or f"results/{default_stem}.nc", exp.layers.arg("run", "out"))
    if args.no_plot:
        return out, None
    origin = exp.layers.origin
    # a file's plot path goes with that file's result path: with --out on the command line and
    # the plot only in the file (another command's, say), the plot goes next to --out
    if exp.run.plot and not (origin.get(("run", "out")) == "cli" and origin.get(("run", "plot")) != "cli"):
        return out, check_plot(exp.run.plot, exp.layers.arg("run", "plot"))
    return out, check_plot(out.with_suffix(".png"), "--out")  # OUT.png may be a directory


def _command_line(args: argparse.Namespace | None = None) -> str:
    line = getattr(args, "command_line", None)
    return line if line else " ".join(["impact-harness", *sys.argv[1:]])


def _finite(layers: Any, section: str, key: str) -> float:
    """A finite number from the settings, or a one-line error naming the flag or file key."""
    from ..config import _number

    return _number(layers, section, key)


def cmd_simulate(args: argparse.Namespace) -> int:
    """``simulate``: time series from (u0, v0) at --t0 to --t-end; NetCDF + PNG."""
    from ..io.plots import timeseries_plot
    from ..io.results import provenance, timeseries_dataset, write_netcdf
    from ..dynamics.sampling import simulate
    from ..fmu.simulator import FmuSimulator

    exp = _experiment(args)
    L = exp.layers
    t0, t_end = _finite(L, "simulate", "t0"), _finite(L, "simulate", "t_end")
    dt = _finite(L, "simulate", "dt")
    out, plot = _outputs(args, exp, "simulate")
    if not dt > 0:
        raise HarnessInputError(L.arg("simulate", "dt"), f"the output step must be > 0, got {dt}")
    if not t_end > t0:
        raise HarnessInputError(L.arg("simulate", "t_end"), f"must be greater than the start time {t0}, got {t_end}")
    Budget.from_args(args).check(simulate_estimate(t0, t_end, dt, L.arg("simulate", "dt")))
    t_start = time.perf_counter()
    sim = FmuSimulator(exp.model.source())
    n = max(1, int((t_end - t0) / dt)) if dt > 0 else 1
    with progress_bar(total=n, desc="simulate", unit="step", disable=not exp.run.progress) as bar:
        series = simulate(sim, exp.params, exp.state0, t0, t_end, dt, progress=bar)
    settings = {**exp.as_attrs(), "simulate.t0": t0, "simulate.t_end": t_end, "simulate.dt": dt}
    ds = timeseries_dataset(series, provenance(settings, exp.model, "serial", time.perf_counter() - t_start, _command_line(args)))
    write_netcdf(ds, out)
    print(f"{len(series['t'])} points, {int(series['impacts'][-1])} impacts; wrote {out}")
    if plot:
        print(f"plot: {timeseries_plot(ds, plot)}")
    return 0


def cmd_strobe(args: argparse.Namespace) -> int:
    """``strobe``: samples at t = n + theta, classified; NetCDF + Poincare section."""
    from ..io.plots import poincare_section
    from ..io.results import provenance, strobe_dataset, write_netcdf
    from ..dynamics.sampling import strobe
    from ..fmu.simulator import FmuSimulator

    exp = _experiment(args)
    s = exp.sampling
    out, plot = _outputs(args, exp, "strobe")
    L = exp.layers
    blame = L.arg("sampling", "transient") if s.n_transient > s.n_samples else L.arg("sampling", "samples")
    # a Lyapunov period costs up to 5 runs (differences when the FMU has no derivatives)
    Budget.from_args(args).check(strobe_estimate(s.n_transient, s.n_samples + 5 * s.lyapunov, blame))
    t_start = time.perf_counter()
    sim = FmuSimulator(exp.model.source())
    exact = bool(s.lyapunov) and sim.derivatives_available
    sim.track_derivatives(exact)
    with progress_bar(total=s.n_transient + s.n_samples, desc="strobe", unit="period", disable=not exp.run.progress) as bar:
        r = strobe(sim, exp.params, exp.state0, s.theta, s.n_transient, s.n_samples, progress=bar)
    orbit = classify_orbit(r.u, r.v, r.impacts, s.tol, s.max_period)
    ly = None
    if s.lyapunov:
        from ..dynamics.classify import DECIDED, DYNAMICS_NAMES, REASON_NAMES, explain_dynamics, still_settling
        from ..dynamics.lyapunov import lyapunov_continued

        ly = lyapunov_continued(sim, exp.params, s.lyapunov, exact)
        settling = orbit.periodic and still_settling(r.u, r.v, orbit.period, s.tol)
        code, reason = explain_dynamics(orbit.period, settling, ly.largest, ly.largest_uncertainty)
        dynamics = DYNAMICS_NAMES[code] + ("" if reason == DECIDED else f" ({REASON_NAMES[reason]})")
    attrs = provenance(exp.as_attrs(), exp.model, "serial", time.perf_counter() - t_start, _command_line(args))
    ds = strobe_dataset(r, orbit, attrs)
    if ly is not None:
        ds = ds.assign_coords(exponent=[1, 2])
        ds["lyapunov"] = ("exponent", ly.exponents, {"long_name": "Lyapunov exponents of the stroboscopic map",
                                                     "units": "1/forcing period", "method": ly.method,
                                                     "comment": f"QR method over {ly.periods} periods after the samples"})
        ds["lyapunov_err"] = ("exponent", ly.uncertainty, {"long_name": "standard error (batch means of 10 blocks)"})
        ds.attrs["dynamics"] = dynamics
    write_netcdf(ds, out)
    print(f"{orbit.label} (residual {orbit.residual:.2e})"
          + ("" if ly is None else f"; Lyapunov exponents {ly} per period ({ly.method}): {dynamics}")
          + f"; wrote {out}")
    if plot:
        print(f"plot: {poincare_section(ds, plot)}")
    return 0


def _scan_option(text: str | None) -> dict[str, Any]:
    """``NAME=V1,V2`` or ``NAME=START:STOP:NUM`` -> the sweep layer entries."""
    if text is None:
        return {}
    name, sep, spec = text.partition("=")
    if not sep or not name.strip() or not spec.strip():
        raise HarnessInputError("--scan", f"expected NAME=V1,V2,... or NAME=START:STOP:NUM, got {text!r}")
    if ":" in spec:
        parts = spec.split(":")
        if len(parts) != 3:
            raise HarnessInputError("--scan", f"expected START:STOP:NUM, got {spec!r}")
        values = parameter_values(parts[0], parts[1], parts[2], None, ("--scan",) * 4)
    else:
        values = parameter_values(None, None, None, spec, ("--scan",) * 4)
    return {"scan_param": name.strip(), "scan_values": [float(v) for v in values]}


def _scan_count(text: str) -> float:
    """Points of the ``--scan`` grid, read from its text without building it."""
    spec = text.partition("=")[2]
    if ":" in spec:
        parts = spec.split(":")
        return grid_count(parts[-1], None) if len(parts) == 3 else 0.0
    return grid_count(None, spec)


def _check_sweep_budget(args: argparse.Namespace, exp: Experiment) -> None:
    """Refuse a sweep whose grid, samples or periods exceed the limits, before any grid
    array exists (``np.linspace(0, 1, 10**9)`` alone is 8 GB)."""
    from ..config import parse_modes, sweep_directions

    L, s = exp.layers, exp.sampling
    if args.scan:
        n_scan = _scan_count(args.scan)
    elif L.get("sweep", "scan_param") is not None:
        n_scan = grid_count(None, L.get("sweep", "scan_values"))
    else:
        n_scan = 0.0
    n_values = grid_count(L.get("sweep", "num"), L.get("sweep", "values"))
    modes = parse_modes(L.get("sweep", "mode"), L.arg("sweep", "mode"))
    # blame the largest factor: the flag the user most likely mistyped
    grid_arg = L.arg("sweep", "values") if L.get("sweep", "values") is not None else L.arg("sweep", "num")
    factors = {grid_arg: n_values, "--scan" if args.scan else L.arg("sweep", "scan_values"): n_scan,
               L.arg("sampling", "transient"): s.n_transient, L.arg("sampling", "samples"): s.n_samples,
               L.arg("sampling", "extend"): s.extend, L.arg("sampling", "lyapunov"): s.lyapunov}
    blame = max(factors, key=lambda k: factors[k])
    # a Lyapunov period costs up to 5 runs (central differences when the FMU has no derivatives)
    Budget.from_args(args).check(
        sweep_estimate(n_values, len(sweep_directions(modes)), n_scan, s.n_transient, s.n_samples, s.extend + 5 * s.lyapunov, blame))


def cmd_sweep(args: argparse.Namespace) -> int:
    """``sweep``: 1D/2D sweep on the chosen backend, resumable; NetCDF + diagram."""
    from ..io.results import write_netcdf
    from ..runs.sweeps import SweepStats, run_sweep

    exp = _experiment(args)
    _check_sweep_budget(args, exp)
    if args.scan:
        exp.layers.merge({"sweep": _scan_option(args.scan)}, "cli")
    spec = exp.sweep_spec()
    out, plot = _outputs(args, exp, f"sweep-{spec.param}")
    stats = SweepStats()

    def sweep(checkpoint: str) -> Any:
        return run_sweep(
            exp.model, spec, exp.params, exp.state0, exp.sampling,
            backend=exp.run.backend, workers=exp.run.workers, scheduler=exp.run.scheduler,
            checkpoint=checkpoint, progress=exp.run.progress,
            settings={**exp.as_attrs(), "command": _command_line(args)}, stats=stats,
        )

    ds, ckpt = run_resumable(sweep, exp, out, stats, args.no_resume)
    write_netcdf(ds, out)
    shutil.rmtree(ckpt, ignore_errors=True)  # the NetCDF file now holds everything
    print(f"{spec.param}: {len(spec.values)} values x {', '.join(spec.modes)}"
          + (f" x {spec.scan_param} ({len(spec.scan_values)} values)" if spec.scan_param else "")
          + f"; {stats.computed} tasks computed, {stats.resumed} resumed"
          + (f" ({stats.resumed_points} points of unfinished chains resumed)" if stats.resumed_points else "")
          + "; "
          f"wall time {stats.wall_time:.2f} s on {ds.attrs['backend']} "
          f"(tasks used {ds.attrs['tasks_cpu_time_s']:.1f} CPU s)")
    grid = ds[spec.param].values
    if "lyapunov" in ds:
        from ..dynamics.classify import DYNAMICS_NAMES

        ran = ds["period"].values >= 0  # -1: a start inside a rigid wall, not run
        codes, counts = np.unique(ds["dynamics"].values[ran], return_counts=True)
        invalid = int(np.sum(~ran))
        print("  dynamics (Lyapunov exponents over " f"{exp.sampling.lyapunov} periods): "
              + ", ".join([f"{DYNAMICS_NAMES[int(c)]} {n}" for c, n in zip(codes, counts)]
                          + ([f"invalid start {invalid}"] if invalid else [])))
    if spec.scan_param is None:
        for direction in ds["direction"].values:
            sel = ds.sel(direction=direction)
            wins = windows(grid, sel["period"].values, sel["orbit_impacts"].values)
            text = ", ".join(f"P{m} [{lo:g}, {hi:g}]" for m, lo, hi in sorted(wins, key=lambda w: -w[2])) or "none"
            print(f"  {direction}: windows of maximal orbits (1 impact per period): {text}")
    print(f"wrote {out}")
    if plot:
        # matplotlib only now: its 0.8 s import would sit on the serial path of every sweep
        from ..io.sweep_plots import bifurcation_diagram, period_map

        drawn = period_map(ds, plot) if spec.scan_param else bifurcation_diagram(ds, plot)
        print(f"plot: {drawn}")
    return 0


def cmd_jacobian(args: argparse.Namespace) -> int:
    """``jacobian``: J at --state, or J(x) along the grazing family; NetCDF + plot."""
    from ..dynamics.jacobian import jacobian_vs_x, map_jacobian
    from ..io.plots import jacobian_plot
    from ..dynamics.singularity_fit import describe, fits_dataset, grazing_fits
    from ..io.results import jacobian_dataset, provenance, state_jacobian_dataset, write_netcdf
    from ..dynamics.sampling import check_count, check_theta
    from ..fmu.simulator import FmuSimulator

    exp = _experiment(args)
    L = exp.layers
    params = dict(exp.params)
    # [jacobian] rtol/atol, when given, override the model's tolerances for these runs only
    # (differences of maps need tight tolerances; the FMU's defaults are tight already).
    for key in ("rtol", "atol"):
        if L.get("jacobian", key) is not None and key in params:
            params[key] = float(L.get("jacobian", key))
    theta = check_theta(L.get("jacobian", "theta"), L.arg("jacobian", "theta"))
    sim = FmuSimulator(exp.model.source())
    t_start = time.perf_counter()
    state = L.get("jacobian", "state")
    if state is not None:
        try:
            u, v = (float(s) for s in str(state).replace(" ", "").split(","))
        except ValueError:
            raise HarnessInputError(L.arg("jacobian", "state"), f"expected U,V, got {state!r}") from None
        out, _ = _outputs(args, exp, "jacobian")
        res = map_jacobian(sim, params, (u, v), theta=theta, method=str(L.get("jacobian", "method")))
        mu = np.linalg.eigvals(res.J)
        print(f"J at (u, v) = ({u}, {v}), t = {theta}:")
        print(np.array2string(res.J, precision=8))
        print("eigenvalues of J (multipliers): " + ", ".join(f"{m:.8g} (|mu| = {abs(m):.6g})" for m in mu)
              + f"; det J = {np.linalg.det(res.J):.8g}")
        print(f"image {res.image}; " + ("exact (the FMU's derivatives)" if res.method == "exact" else
                                         f"central differences, step {res.step:.2e}, estimated error {res.error:.1e}"))
        settings = {**exp.as_attrs(), **{f"model.{k}": v for k, v in params.items()},
                    **{f"jacobian.{k}": v for k, v in L.values["jacobian"].items()}}
        ds = state_jacobian_dataset(res, (u, v), theta, provenance(settings, exp.model, "serial",
                                                                   time.perf_counter() - t_start, _command_line(args)))
        write_netcdf(ds, out)
        print(f"wrote {out}")
        return 0
    n = check_count(L.get("jacobian", "x_num"), L.arg("jacobian", "x_num"), minimum=1)
    Budget.from_args(args).check(jacobian_estimate(n, L.arg("jacobian", "x_num")))
    lo, hi = float(L.get("jacobian", "x_start")), float(L.get("jacobian", "x_stop"))
    if not (0 < lo and 0 < hi):
        raise HarnessInputError(L.arg("jacobian", "x_start"), f"x values must be > 0 (log-spaced), got {lo}, {hi}")
    if n > 1 and lo == hi:
        raise HarnessInputError(L.arg("jacobian", "x_stop"), f"empty range: x_start = x_stop = {lo}")
    x = np.geomspace(lo, hi, n)
    out, plot = _outputs(args, exp, "jacobian")
    with progress_bar(total=n, desc="jacobian", unit="x", disable=not exp.run.progress) as bar:
        scan = jacobian_vs_x(sim, params, x, theta, float(L.get("jacobian", "measure_theta")), progress=bar,
                             method=str(L.get("jacobian", "method")))
    settings = {**exp.as_attrs(), **{f"model.{k}": v for k, v in params.items()},
                **{f"jacobian.{k}": v for k, v in L.values["jacobian"].items()}}
    ds = jacobian_dataset(scan, provenance(settings, exp.model, "serial", time.perf_counter() - t_start, _command_line(args)))
    fits, beta = grazing_fits(scan, params)
    ds = ds.merge(fits_dataset(fits))
    if beta is not None:
        ds["beta"] = ("x", beta, {"long_name": "contact parameter beta = r kappa sqrt(8 pi^2 x) / |A~| "
                                               "(soft <= 0.1, hard >= 5; docs/theory.md section 5)"})
    write_netcdf(ds, out)
    print(f"exponent q of |J11 - P11| ~ x^q ({scan.method}; scanned x in [{lo:g}, {hi:g}]):")
    for regime, fit in fits.items():
        print("  " + describe(regime, fit))
    print(f"wrote {out}")
    if plot:
        print(f"plot: {jacobian_plot(ds, plot)}")
    return 0
