"""``impact-harness basins``: basins of attraction over a grid of initial states (u0, v0) at
t = theta, parallel and resumable like ``sweep``; NetCDF, a figure with one colour per
attractor, and the attractors listed on stdout with the basins' quantifiers (fractions with
errors, basin entropies, uncertainty exponent).  With the closed-form solver the scan runs on
the batch kernel (the FMU's closed form in C, early-stopped, in tiles); ``--kernel fmu`` keeps
the FMU path."""
from __future__ import annotations

import argparse
import json
import shutil
from typing import Any

import numpy as np

from ..config import parameter_values
from ..errors import HarnessInputError
from ..runs.budget import Budget, basin_kernel_estimate, grid_count, sweep_estimate
from .experiment_args import command_line, experiment_of, output_paths
from .options import count, execution_options
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
    g.add_argument("--kernel", choices=("auto", "batch", "fmu"), default="auto",
                   help="batch: the FMU's closed form in C for many starts at once, stopping each start as soon "
                   "as it comes round a known attractor (closed-form solver and linear contact law only); fmu: "
                   "every start through the FMU; auto (default): batch with --solver closed-form and no "
                   "--lyapunov/--extend, else fmu")
    g.add_argument("--tile-size", type=count, default=32768, metavar="N",
                   help="starts per tile of the batch kernel (checkpointed one tile at a time; default 32768)")
    g.add_argument("--zoom", metavar="U1:U2:V1:V2",
                   help="also scan this sub-rectangle of (u0, v0) with as many starts, to show the boundary at a "
                   "second scale (drawn beside the whole grid)")
    g.add_argument("--check-fmu", type=count, default=0, metavar="N",
                   help="run N random starts of the grid through the FMU without early stopping and report how "
                   "many are labelled alike (default 0: no check)")
    g.add_argument("--uncertainty-pairs", type=count, default=0, metavar="N",
                   help="also measure the uncertainty exponent from N random pairs of starts per eps (eps = 2^-3 .. "
                   "2^-10 of the box; batch kernel only; default 0: from the grid alone)")
    execution_options(p, "scan")
    p.set_defaults(func=cmd_basins)


def _grid(text: str, flag: str) -> tuple[str, str, str]:
    parts = text.split(":")
    if len(parts) != 3:
        raise HarnessInputError(flag, f"expected START:STOP:NUM, got {text!r}")
    return parts[0], parts[1], parts[2]


def _zoom(text: str | None) -> tuple[float, float, float, float] | None:
    if text is None:
        return None
    parts = text.split(":")
    try:
        u1, u2, v1, v2 = (float(x) for x in parts)
    except ValueError:
        raise HarnessInputError("--zoom", f"expected U1:U2:V1:V2 (four numbers), got {text!r}") from None
    if not all(np.isfinite([u1, u2, v1, v2])) or not (u1 < u2 and v1 < v2):
        raise HarnessInputError("--zoom", f"expected finite U1 < U2 and V1 < V2, got {text!r}")
    return u1, u2, v1, v2


def _use_batch(args: argparse.Namespace, exp: Any) -> bool:
    """Whether the scan runs on the batch kernel (``--kernel``)."""
    s = exp.sampling
    closed = exp.solver == "closed-form" and int(exp.params.get("contact", 0)) == 0
    if args.kernel == "batch":
        if not closed:
            raise HarnessInputError("--kernel", "the batch kernel is the closed form: it needs --solver closed-form "
                                    "and the linear contact law (contact = 0)")
        if s.lyapunov or s.extend:
            raise HarnessInputError("--kernel", "the batch kernel computes no Lyapunov exponents and does not "
                                    "extend: use --kernel fmu with --lyapunov or --extend")
        return True
    return args.kernel == "auto" and closed and not s.lyapunov and not s.extend


def cmd_basins(args: argparse.Namespace) -> int:
    """``basins``: the scan, the attractors, the quantifiers, NetCDF + figure."""
    from ..analysis.basins.summary import with_measures
    from ..io.results import write_netcdf
    from ..runs.sweeps import SweepStats

    exp = experiment_of(args)
    gu, gv = _grid(args.u0_grid, "--u0-grid"), _grid(args.v0_grid, "--v0-grid")
    s = exp.sampling
    n_u, n_v = grid_count(gu[2], None), grid_count(gv[2], None)
    factors = {"--u0-grid": n_u, "--v0-grid": n_v, exp.layers.arg("sampling", "transient"): s.n_transient,
               exp.layers.arg("sampling", "samples"): s.n_samples}
    blame = max(factors, key=lambda k: factors[k])  # the flag the user most likely mistyped
    batch = _use_batch(args, exp)
    scans = 1 + (args.zoom is not None)
    Budget.from_args(args).check(
        basin_kernel_estimate(scans * n_u * n_v, s.n_transient, s.n_samples, args.tile_size, blame) if batch else
        sweep_estimate(n_u, 1, n_v, s.n_transient, s.n_samples, s.extend + 5 * s.lyapunov, blame))
    u0 = parameter_values(*gu, None, ("--u0-grid",) * 4)
    v0 = parameter_values(*gv, None, ("--v0-grid",) * 4)
    if args.match_tol is not None and not (np.isfinite(args.match_tol) and args.match_tol > 0):
        raise HarnessInputError("--match-tol", f"must be a finite number > 0, got {args.match_tol!r}")
    zoom = _zoom(args.zoom)
    if zoom is not None and not batch:
        raise HarnessInputError("--zoom", "the zoom runs on the batch kernel: use --solver closed-form")
    if args.uncertainty_pairs and not batch:
        raise HarnessInputError("--uncertainty-pairs", "the pairs run on the batch kernel: use --solver closed-form")
    out, plot = output_paths(args, exp, "basins")
    stats = SweepStats()
    scan = _batch_scan(args, exp, u0, v0, zoom, stats) if batch else _fmu_scan(args, exp, u0, v0, stats)
    ds, ckpt = run_resumable(scan, exp, out, stats, args.no_resume)
    ds = with_measures(ds)
    if "attractor_zoom" in ds:
        ds = with_measures(ds, suffix="_zoom")
    if args.uncertainty_pairs:
        from ..analysis.basins.uncertainty import uncertainty_from_pairs, with_pairs

        ds = with_pairs(ds, uncertainty_from_pairs(ds, exp.params, s, args.uncertainty_pairs,
                                                   threads=exp.run.workers))
    if args.check_fmu:
        from ..analysis.basins.agreement import fmu_agreement
        from ..analysis.basins.summary import with_agreement

        ds = with_agreement(ds, fmu_agreement(exp.model, ds, exp.params, s, args.check_fmu), exp.solver)
    write_netcdf(ds, out)
    shutil.rmtree(ckpt, ignore_errors=True)  # the NetCDF file now holds everything
    print(report(ds))
    print(f"wrote {out}")
    if plot:
        from ..io.basin_plot import basin_figure

        print(f"plot: {basin_figure(ds, plot)}")
    return 0


def _fmu_scan(args: argparse.Namespace, exp: Any, u0: np.ndarray, v0: np.ndarray, stats: Any) -> Any:
    from ..runs.basins.scan import run_basins

    def scan(checkpoint: str) -> Any:
        return run_basins(exp.model, u0, v0, exp.params, exp.sampling, args.match_tol,
                          backend=exp.run.backend, workers=exp.run.workers, scheduler=exp.run.scheduler,
                          checkpoint=checkpoint, progress=exp.run.progress,
                          settings={**exp.as_attrs(), "command": command_line(args)}, stats=stats)

    return scan


def _batch_scan(args: argparse.Namespace, exp: Any, u0: np.ndarray, v0: np.ndarray,
                zoom: tuple[float, float, float, float] | None, stats: Any) -> Any:
    from ..runs.basins.kernel_scan import run_basins_kernel, with_zoom

    kw = dict(backend=exp.run.backend, workers=exp.run.workers, scheduler=exp.run.scheduler,
              tile_size=args.tile_size, progress=exp.run.progress,
              settings={**exp.as_attrs(), "command": command_line(args)})

    def scan(checkpoint: str) -> Any:
        ds = run_basins_kernel(exp.model, u0, v0, exp.params, exp.sampling, args.match_tol, checkpoint=checkpoint,
                               stats=stats, **kw)
        if zoom is None:
            return ds
        zu = np.linspace(zoom[0], zoom[1], u0.size)
        zv = np.linspace(zoom[2], zoom[3], v0.size)
        dz = run_basins_kernel(exp.model, zu, zv, exp.params, exp.sampling, checkpoint=f"{checkpoint}/zoom",
                               attractors_from=ds, **kw)
        return with_zoom(ds, dz)

    return scan


def report(ds: Any) -> str:
    """The attractors found, with their basins' shares and stroboscopic points, and the basins'
    quantifiers."""
    from ..analysis.basins.summary import measure_lines

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
                      ("basins.invalid_starts", "invalid (refused by the FMU: inside a rigid wall)"),
                      ("basins.sticking_starts", "sticking or chatter at the samples"),
                      ("basins.escaped_starts", "escaped or failed")):
        if ds.attrs.get(key):
            lines.append(f"  {what}: {ds.attrs[key]} start(s)")
    if ds.attrs.get("basins.kernel") == "batch":
        confirmed = int(np.sum(ds["attractor_confirmed"].values))
        lines.append(f"  batch kernel: {ds.attrs['basins.starts_per_s']:,.0f} starts/s, "
                     f"{ds.attrs['basins.periods_run_mean']:.1f} periods per start on average (early stop; "
                     f"{ds.attrs['basins.full_periods']} in full); {confirmed} of {len(names)} attractors confirmed by "
                     "Newton shooting on the FMU")
    lines += measure_lines(ds)
    if "attractor_zoom" in ds:
        z = ds
        lines.append(f"  zoom on u0 in [{float(z.u0_zoom[0]):g}, {float(z.u0_zoom[-1]):g}] x v0 in "
                     f"[{float(z.v0_zoom[0]):g}, {float(z.v0_zoom[-1]):g}]:")
        lines += ["  " + line for line in measure_lines(ds, "_zoom")]
    return "\n".join(lines)
