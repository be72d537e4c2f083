"""``impact-harness basins``: basins of attraction over a grid of initial states (u0, v0) at
t = theta, parallel and resumable like ``sweep``; NetCDF, a figure with one colour per
attractor, and the attractors listed on stdout."""
from __future__ import annotations

import argparse
import json
import shutil
from typing import Any

import numpy as np

from ..config import parameter_values
from ..errors import HarnessInputError
from ..runs.budget import Budget, grid_count, sweep_estimate
from .experiment_args import command_line, experiment_of, output_paths
from .options import execution_options
from .resumable import run_resumable


def register(sub: Any, parents: dict[str, argparse.ArgumentParser]) -> None:
    """Add ``basins`` to the CLI."""
    p = sub.add_parser(
        "basins", parents=[parents["common"], parents["sampling"]], help="basins of attraction in (u0, v0)",
        description="Start from every (u0, v0) of a grid at t = theta (the section phase), follow each start "
        "for the transient and sample it; starts that reach the same periodic orbit (the same period, impacts "
        "per period and stroboscopic points within --match-tol) share an attractor. Starts inside a rigid wall "
        "are marked invalid. Draws the basins with one colour per attractor.")
    g = p.add_argument_group("basins")
    g.add_argument("--u0-grid", required=True, metavar="START:STOP:NUM",
                   help="initial displacements at t = theta, e.g. -1.2:0:60")
    g.add_argument("--v0-grid", required=True, metavar="START:STOP:NUM",
                   help="initial velocities at t = theta, e.g. -8:8:60")
    g.add_argument("--match-tol", type=float, metavar="D",
                   help="largest distance (max norm, units of u and v) between two orbits of one attractor "
                   "(default 1000 x --tol x the orbits' size)")
    execution_options(p, "scan")
    p.set_defaults(func=cmd_basins)


def _grid(text: str, flag: str) -> tuple[str, str, str]:
    parts = text.split(":")
    if len(parts) != 3:
        raise HarnessInputError(flag, f"expected START:STOP:NUM, got {text!r}")
    return parts[0], parts[1], parts[2]


def cmd_basins(args: argparse.Namespace) -> int:
    """``basins``: the scan, the attractors, NetCDF + figure."""
    from ..io.results import write_netcdf
    from ..runs.basin_scan import run_basins
    from ..runs.sweeps import SweepStats

    exp = experiment_of(args)
    gu, gv = _grid(args.u0_grid, "--u0-grid"), _grid(args.v0_grid, "--v0-grid")
    s = exp.sampling
    n_u, n_v = grid_count(gu[2], None), grid_count(gv[2], None)
    factors = {"--u0-grid": n_u, "--v0-grid": n_v, exp.layers.arg("sampling", "transient"): s.n_transient,
               exp.layers.arg("sampling", "samples"): s.n_samples}
    blame = max(factors, key=lambda k: factors[k])  # the flag the user most likely mistyped
    Budget.from_args(args).check(sweep_estimate(n_u, 1, n_v, s.n_transient, s.n_samples, s.extend + 5 * s.lyapunov, blame))
    u0 = parameter_values(*gu, None, ("--u0-grid",) * 4)
    v0 = parameter_values(*gv, None, ("--v0-grid",) * 4)
    if args.match_tol is not None and not (np.isfinite(args.match_tol) and args.match_tol > 0):
        raise HarnessInputError("--match-tol", f"must be a finite number > 0, got {args.match_tol!r}")
    out, plot = output_paths(args, exp, "basins")
    stats = SweepStats()

    def scan(checkpoint: str) -> Any:
        return run_basins(exp.model, u0, v0, exp.params, s, args.match_tol,
                          backend=exp.run.backend, workers=exp.run.workers, scheduler=exp.run.scheduler,
                          checkpoint=checkpoint, progress=exp.run.progress,
                          settings={**exp.as_attrs(), "command": command_line(args)}, stats=stats)

    ds, ckpt = run_resumable(scan, exp, out, stats, args.no_resume)
    write_netcdf(ds, out)
    shutil.rmtree(ckpt, ignore_errors=True)  # the NetCDF file now holds everything
    print(report(ds))
    print(f"wrote {out}")
    if plot:
        from ..io.basin_plot import basin_figure

        print(f"plot: {basin_figure(ds, plot)}")
    return 0


def report(ds: Any) -> str:
    """The attractors found, with their basins' shares and stroboscopic points."""
    n = ds.sizes["u0"] * ds.sizes["v0"]
    lines = [f"basins over u0 in [{float(ds.u0[0]):g}, {float(ds.u0[-1]):g}] x v0 in [{float(ds.v0[0]):g}, "
             f"{float(ds.v0[-1]):g}] ({ds.sizes['u0']} x {ds.sizes['v0']} starts at t = theta = "
             f"{ds.attrs.get('sampling.theta', 0.0):g}); orbits matched within {ds.attrs['basins.match_tol']:.3g}"]
    names = json.loads(ds.attrs["basins.attractors"])
    if not names:
        lines.append("  no periodic attractor reached from this grid")
    for i, name in enumerate(names):
        p = int(ds["attractor_period"].values[i])
        pts = ds["attractor_points"].values[i, :p]
        share = int(ds["attractor_starts"].values[i]) / n
        where = "; ".join(f"({u:.6g}, {v:.6g})" for u, v in pts[:4]) + (" ..." if p > 4 else "")
        lines.append(f"  {name}: {share:.1%} of the starts; points {where}")
    for key, what in (("basins.not_periodic_starts", "not periodic (chaotic, quasi-periodic or not converged)"),
                      ("basins.invalid_starts", "invalid (refused by the FMU: inside a rigid wall)")):
        if ds.attrs[key]:
            lines.append(f"  {what}: {ds.attrs[key]} start(s)")
    return "\n".join(lines)
