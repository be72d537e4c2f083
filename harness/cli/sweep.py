"""``impact-harness sweep``: a 1D or 2D bifurcation sweep, resumable (NetCDF + diagram)."""
from __future__ import annotations

import argparse
import shutil
from typing import Any

import numpy as np

from ..config import parameter_values
from ..dynamics.maps.classify import windows
from ..errors import HarnessInputError
from ..runs.budget import Budget, grid_count, sweep_estimate
from ..runs.experiment import Experiment
from .experiment_args import command_line, experiment_of, output_paths
from .options import count, execution_options
from .resumable import run_resumable

__all__ = ["register", "cmd_sweep"]


def register(sub: Any, parents: dict[str, argparse.ArgumentParser]) -> None:
    """Add ``sweep`` to the CLI."""
    common, sampling = parents["common"], parents["sampling"]
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

    exp = experiment_of(args)
    _check_sweep_budget(args, exp)
    if args.scan:
        exp.layers.merge({"sweep": _scan_option(args.scan)}, "cli")
    spec = exp.sweep_spec()
    out, plot = output_paths(args, exp, f"sweep-{spec.param}")
    stats = SweepStats()

    def sweep(checkpoint: str) -> Any:
        return run_sweep(
            exp.model, spec, exp.params, exp.state0, exp.sampling,
            backend=exp.run.backend, workers=exp.run.workers, scheduler=exp.run.scheduler,
            checkpoint=checkpoint, progress=exp.run.progress,
            settings={**exp.as_attrs(), "command": command_line(args)}, stats=stats,
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
        from ..dynamics.maps.classify import DYNAMICS_NAMES

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
            text = ", ".join(f"P{m} [{lo:.6g}, {hi:.6g}]" for m, lo, hi in sorted(wins, key=lambda w: -w[2])) or "none"
            print(f"  {direction}: windows of maximal orbits (1 impact per period): {text}")
    print(f"wrote {out}")
    if plot:
        # matplotlib only now: its 0.8 s import would sit on the serial path of every sweep
        from ..io.sweep_plots import bifurcation_diagram, period_map

        drawn = period_map(ds, plot) if spec.scan_param else bifurcation_diagram(ds, plot)
        print(f"plot: {drawn}")
    return 0
