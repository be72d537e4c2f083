"""``impact-harness atlas``: the plane of sigma and a second parameter by brute force, every pixel
run from several starts to its attractors (:mod:`harness.analysis.atlas.run`)."""
from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import HarnessInputError
from ..runs.budget import Budget, Estimate, KERNEL_PERIOD_COST
from .experiment_args import command_line, experiment_of
from .options import count, execution_options, theta_option

__all__ = ["register", "cmd_atlas"]

#: Second parameters and the values each may take (checked before any work).
LIMITS = {"Gamma": (0.0, math.inf, "> 0"), "nu": (-1e-300, math.inf, ">= 0"), "Omega": (0.0, math.inf, "> 0"),
          "r": (0.0, 1.0, "in (0, 1]"), "gamma": (0.0, 1.0, "in (0, 1)"), "alpha": (-2.0, 2.0, "in (-2, 2)")}


def register(sub: Any, parents: dict[str, argparse.ArgumentParser]) -> None:
    """Add the ``atlas`` subcommand."""
    p = sub.add_parser(
        "atlas", parents=[parents["common"]], help="the (sigma, --param2) plane by brute force: every pixel's attractors",
        description="Every pixel of a grid over (--param2, sigma) run from --starts starts (half on a grid, half random) "
        "to its attractors, on the batch kernel (the closed form in C; with --solver cvode or a nonlinear contact law "
        "through the FMU), classified by period, impacts per period, chaos (largest Lyapunov exponent from the exact "
        "Jacobian), sticking and escape; multistable pixels counted. Writes atlas.nc, atlas.json, atlas.png and "
        "report.md into --out DIR; resumable (a rerun goes on from the finished tiles).")
    g = p.add_argument_group("atlas")
    g.add_argument("--param2", required=True, choices=("Gamma", "nu", "Omega", "r", "alpha", "gamma"),
                   help="the second parameter (alpha, gamma: the free flight's trace and determinant, the other held)")
    g.add_argument("--range", required=True, dest="range_", metavar="LO:HI", help="its range")
    g.add_argument("--log", action="store_true", help="geometric values of --param2, log axis")
    g.add_argument("--sigma-range", default="0.05:1.5", metavar="LO:HI", help="sigma range (default 0.05:1.5; "
                   "negative values reach below grazing: --sigma-range=-0.2:1)")
    g.add_argument("--sigma-log", action="store_true", help="geometric values of sigma (LO > 0), log axis")
    g.add_argument("--grid", default="100x100", metavar="NP2xNSIGMA", help="pixels: values of --param2 x values of "
                   "sigma (default 100x100)")
    g.add_argument("--starts", type=count, default=8, metavar="K", help="starts per pixel (default 8)")
    g.add_argument("--seed", type=count, default=0, help="seed of the random starts (default 0)")
    theta_option(g, "sampling__theta", default=None)
    g.add_argument("--M-max", type=count, default=12, dest="M_max", help="largest period told apart (default 12)")
    g.add_argument("--max-periods", type=count, default=500, metavar="N",
                   help="periods a start runs at most before it counts as aperiodic (default 500)")
    g.add_argument("--lyapunov-periods", type=count, default=200, metavar="N",
                   help="periods of an aperiodic start's exponent (its last N; default 200)")
    g.add_argument("--tol", type=float, default=1e-8, help="periodicity tolerance, relative to 1 + |u| + |v| "
                   "(default 1e-8; the FMU route at least 1e-5)")
    g.add_argument("--kernel", choices=("auto", "batch", "fmu"), default="auto",
                   help="batch: the closed form in C (closed-form solver, linear contact law); fmu: every start "
                   "through the FMU; auto (default): batch where it applies")
    g.add_argument("--curves", metavar="CHART.json", help="a chart.json of the same oscillator and --param2: its "
                   "continued edges drawn over the atlas and checked against it")
    execution_options(p, "atlas")
    p.set_defaults(func=cmd_atlas)


def _range(text: str, flag: str) -> tuple[float, float]:
    try:
        a, b = (float(x) for x in text.split(":"))
    except ValueError:
        raise HarnessInputError(flag, f"expected LO:HI (two numbers), got {text!r}") from None
    if not (math.isfinite(a) and math.isfinite(b) and a < b):
        raise HarnessInputError(flag, f"expected finite LO < HI, got {text!r}")
    return a, b


def _grid(text: str) -> tuple[int, int]:
    parts = text.lower().split("x")
    try:
        n = [int(x) for x in parts]
    except ValueError:
        raise HarnessInputError("--grid", f"expected NP2xNSIGMA (e.g. 400x400), got {text!r}") from None
    if len(n) == 1:
        n = n * 2
    if len(n) != 2 or min(n) < 1:
        raise HarnessInputError("--grid", f"expected two counts >= 1 (NP2xNSIGMA), got {text!r}")
    return n[0], n[1]


def _values(lo: float, hi: float, n: int, log: bool, flag: str) -> np.ndarray:
    if log and lo <= 0:
        raise HarnessInputError(flag, f"a geometric range needs LO > 0, got {lo:g}")
    if n == 1:
        return np.array([math.sqrt(lo * hi) if log else (lo + hi) / 2])
    return np.geomspace(lo, hi, n) if log else np.linspace(lo, hi, n)


def _plane(args: argparse.Namespace, exp: Any) -> Any:
    from ..runs.atlas.plane import AtlasPlane, RunLength

    n_p2, n_s = _grid(args.grid)
    lo, hi = _range(args.range_, "--range")
    if args.log and lo <= 0:
        raise HarnessInputError("--range", f"a geometric range needs LO > 0, got {lo:g}")
    a, b, what = LIMITS[args.param2]
    if not (a < lo and hi <= b) and not (args.param2 == "nu" and lo >= 0 and hi < b):
        raise HarnessInputError("--range", f"{args.param2} must be {what}, got {args.range_}")
    s_lo, s_hi = _range(args.sigma_range, "--sigma-range")
    if s_lo <= -1:
        raise HarnessInputError("--sigma-range", f"needs LO > -1 (sigma = -1: no forcing), got {args.sigma_range}")
    params = dict(exp.params)
    wall = int(params.get("wall", 1))
    if args.param2 == "Gamma" and wall != 1:
        raise HarnessInputError("--param2", "Gamma is the compliant wall's stiffness: it needs --wall compliant")
    if not 1 <= args.starts <= 256:
        raise HarnessInputError("--starts", f"must be in 1..256, got {args.starts}")
    if not 1 <= args.M_max <= 64:
        raise HarnessInputError("--M-max", f"must be in 1..64, got {args.M_max}")
    if not args.max_periods > 2 * args.M_max:
        raise HarnessInputError("--max-periods", f"must exceed twice --M-max ({2 * args.M_max}), got {args.max_periods}")
    if not 0 <= args.lyapunov_periods <= args.max_periods:
        raise HarnessInputError("--lyapunov-periods", f"must be in 0..--max-periods, got {args.lyapunov_periods}")
    if not (math.isfinite(args.tol) and 0 < args.tol < 0.1):
        raise HarnessInputError("--tol", f"must be in (0, 0.1), got {args.tol!r}")
    p2 = _values(lo, hi, n_p2, args.log, "--range")
    if args.param2 in ("alpha", "gamma"):
        from ..runs.atlas.plane import nu_omega

        try:
            nu_omega(params, args.param2, p2)
        except HarnessInputError as exc:
            raise HarnessInputError("--range", exc.reason) from None
    run = RunLength(n_max=args.max_periods, m_max=args.M_max, tol=args.tol, n_lyap=args.lyapunov_periods)
    return AtlasPlane(params, args.param2, p2, _values(s_lo, s_hi, n_s, args.sigma_log, "--sigma-range"), args.starts,
                      float(exp.sampling.theta), args.seed, run)


def _route(args: argparse.Namespace, exp: Any) -> str:
    closed = exp.solver == "closed-form" and int(exp.params.get("contact", 0)) == 0
    if args.kernel == "batch" and not closed:
        raise HarnessInputError("--kernel", "the batch kernel is the closed form: it needs --solver closed-form and the "
                                "linear contact law (contact = 0)")
    return "kernel" if args.kernel == "batch" or (args.kernel == "auto" and closed) else "fmu"


def cmd_atlas(args: argparse.Namespace) -> int:
    """``atlas``: the plane, its files, one line per class on stdout."""
    exp = experiment_of(args)
    plane = _plane(args, exp)
    route = _route(args, exp)
    starts = float(np.prod(plane.shape)) * plane.starts
    cost = KERNEL_PERIOD_COST if route == "kernel" else 1.0
    blame = "--grid" if np.prod(plane.shape) >= plane.starts * 100 else "--starts"
    Budget.from_args(args).check(Estimate(memory=starts * (2 * 8 * plane.run.m_max + 60.0), work=starts * (
        plane.run.n_max + plane.run.m_max) * cost, what=f"atlas of {starts:.3g} starts x up to {plane.run.n_max} "
        "periods", argument=blame))
    out = Path(args.run__out or "results/atlas")
    if out.exists() and not out.is_dir():
        raise HarnessInputError("--out", f"{out} exists and is not a directory")
    ckpt = Path(exp.run.checkpoint or out / "atlas.partial")
    if args.no_resume:
        import shutil

        shutil.rmtree(ckpt, ignore_errors=True)
    from ..analysis.atlas.run import atlas

    res = atlas(plane, out, route=route, model=exp.model, log_p2=args.log, log_sigma=args.sigma_log,
                curves=args.curves, backend=exp.run.backend, workers=exp.run.workers, scheduler=exp.run.scheduler,
                progress=exp.run.progress, plot=not args.no_plot, checkpoint=ckpt,
                settings={**exp.as_attrs(), "command": command_line(args)}, command=command_line(args))
    for s in res["classes"]:
        print(f"{s['name']}: stable at {s['pixels']} pixels, {args.param2} in {s['p2_range']}, sigma in {s['sigma_range']}")
    c = res["counts"]
    print(f"multistable pixels: {c['multistable_pixels']} of {c['pixels']}; {res['timing']['wall_s']:.1f} s, "
          f"{res['timing']['starts_per_s']:,.0f} starts/s")
    if "curves" in res:
        print(f"chart curves: {res['curves']['disagree']} of {res['curves']['checked']} probes disagree with the atlas")
    print(f"wrote {out / 'atlas.nc'}, atlas.json, {'' if args.no_plot else 'atlas.png, '}report.md")
    return 0
