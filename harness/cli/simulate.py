"""``impact-harness simulate``: the time series of one run (NetCDF + PNG)."""
from __future__ import annotations

import argparse
import time
from typing import Any

from ..errors import HarnessInputError
from ..io.progress import progress_bar
from ..runs.budget import Budget, simulate_estimate
from .experiment_args import command_line, experiment_of, finite, output_paths

__all__ = ["register", "cmd_simulate"]


def register(sub: Any, parents: dict[str, argparse.ArgumentParser]) -> None:
    """Add ``simulate`` to the CLI."""
    common = parents["common"]
    p = sub.add_parser("simulate", parents=[common], help="time series of one run",
                       description="Integrate the FMU from (u0, v0) at --t0 and record u, v and impacts on a uniform grid.")
    g = p.add_argument_group("simulate")
    g.add_argument("--t0", dest="simulate__t0", type=float, metavar="T", help="start time (default 0; t = n is the grazing phase)")
    g.add_argument("--t-end", dest="simulate__t_end", type=float, metavar="T", help="end time (default 10)")
    g.add_argument("--dt", dest="simulate__dt", type=float, metavar="DT", help="output step (default 0.01)")
    p.set_defaults(func=cmd_simulate)


def cmd_simulate(args: argparse.Namespace) -> int:
    """``simulate``: time series from (u0, v0) at --t0 to --t-end; NetCDF + PNG."""
    from ..io.plots import timeseries_plot
    from ..io.results import provenance, timeseries_dataset, write_netcdf
    from ..dynamics.maps.sampling import simulate
    from ..fmu.simulator import FmuSimulator

    exp = experiment_of(args)
    L = exp.layers
    t0, t_end = finite(L, "simulate", "t0"), finite(L, "simulate", "t_end")
    dt = finite(L, "simulate", "dt")
    out, plot = output_paths(args, exp, "simulate")
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
    ds = timeseries_dataset(series, provenance(settings, exp.model, "serial", time.perf_counter() - t_start, command_line(args)))
    write_netcdf(ds, out)
    print(f"{len(series['t'])} points, {int(series['impacts'][-1])} impacts; wrote {out}")
    if plot:
        print(f"plot: {timeseries_plot(ds, plot)}")
    return 0
