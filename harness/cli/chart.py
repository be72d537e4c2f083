"""``impact-harness chart``: where the ODE's windows close over (sigma, a second parameter)
(:mod:`harness.analysis.chart.run`; written by :mod:`harness.analysis.chart.chart`)."""
from __future__ import annotations

import argparse
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from ..analysis.chart.run import ChartProblem, parse_range
from ..analysis.chart.chart import chart
from ..errors import HarnessInputError
from .options import model_shortcuts, solver_option, xtol_option

__all__ = ["register", "cmd_chart"]

WALLS = {"compliant": 1, "rigid": 2}


def _model_from_config(path: str | None) -> dict[str, Any]:
    if path is None:
        return {}
    import tomllib

    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise HarnessInputError("--config", f"cannot read {path}: {exc}") from exc
    return dict(data.get("model", {}))


def register(sub: Any, parents: dict[str, argparse.ArgumentParser]) -> None:
    """Add the ``chart`` subcommand."""
    p = sub.add_parser("chart", help="where the ODE's windows close over (sigma, a second parameter): edges continued, maps (48)/(39) beside",
                       description="The stable maximal windows found at the start of --range, their edges continued "
                       "in (sigma, --param2) and where each window closes, and how; every edge point checked across "
                       "itself; the windows measured again from scratch at --num values (the brute-force check); "
                       "chart.json, chart.png, report.md.")
    p.add_argument("--config", help="TOML with a [model] table (nu, Omega, r, Gamma, wall), e.g. "
                   "harness/experiments/fig9.toml")
    model_shortcuts(p, "", walls=tuple(sorted(WALLS)))
    p.add_argument("--param2", required=True, help="second parameter: Gamma, r, nu, Omega or any FMU parameter")
    p.add_argument("--range", required=True, dest="range_", metavar="START:STOP", help="its range")
    p.add_argument("--num", type=int, default=30, help="values of the second parameter (default 30)")
    p.add_argument("--log", action="store_true", help="geometric values, log axis")
    p.add_argument("--M-max", type=int, default=5, dest="M_max", help="highest period charted (default 5)")
    p.add_argument("--sigma-range", default="0.05:400", metavar="LO:HI",
                   help="sigma range of the scans (default 0.05:400, geometric); LO <= 0 (> -1) reaches below "
                   "grazing, an even grid of 4 x --per-decade intervals (--sigma-range=-0.3:0.3)")
    xtol_option(p, "1e-4 x the edge's sigma, 1e-3 with --quick")
    p.add_argument("--per-decade", type=int, default=None, help="scan points per decade of sigma (default 16, quick 10)")
    p.add_argument("--quick", action="store_true", help="coarser scans and tolerances")
    solver_option(p)
    p.add_argument("--backend", choices=("processes", "dask", "serial"), default=None)
    p.add_argument("--scheduler", help="Dask scheduler address (tcp://HOST:PORT)")
    p.add_argument("--workers", "-j", type=int, help="worker processes (default: all cores)")
    p.add_argument("--fmu", help="FMU (default build/fmu/ImpactOscillator.fmu)")
    p.add_argument("--out", "-o", default="results/chart", help="output directory")
    p.set_defaults(func=cmd_chart)


def cmd_chart(args: argparse.Namespace) -> int:
    from ..fmu.fmi import SOLVER_NAMES, SOLVER_PARAMETER

    model = _model_from_config(args.config)
    for k in ("nu", "Omega", "r", "Gamma", "wall"):
        if getattr(args, k) is not None:
            model[k] = getattr(args, k)
    wall = model.get("wall", "compliant")
    if wall not in WALLS:
        raise HarnessInputError("--wall", f"must be compliant or rigid, got {wall!r}")
    for k in ("nu", "Omega", "r"):
        if k not in model:
            raise HarnessInputError(f"--{k}", "required (or --config with a [model] table)")
    params: dict[str, Any] = {"nu": float(model["nu"]), "Omega": float(model["Omega"]), "r": float(model["r"]),
                              "wall": WALLS[wall], SOLVER_PARAMETER: SOLVER_NAMES[args.solver]}
    if wall == "compliant":
        params["Gamma"] = float(model.get("Gamma", 10.0))
    a, b = parse_range(args.range_)
    if args.num < 2:
        raise HarnessInputError("--num", f"must be >= 2, got {args.num}")
    if args.log and a <= 0:
        raise HarnessInputError("--range", "a log range must be positive")
    if not 1 <= args.M_max <= 12:
        raise HarnessInputError("--M-max", f"must be in 1..12, got {args.M_max}")
    s0, s1 = parse_range(args.sigma_range)
    if s0 <= -1.0 or s1 <= s0:
        raise HarnessInputError("--sigma-range", f"needs -1 < LO < HI (sigma = -1: no forcing), got {args.sigma_range}")
    per = args.per_decade or (10 if args.quick else 16)
    if s0 > 0:
        grid = np.geomspace(s0, s1, int(math.ceil(per * math.log10(s1 / s0))) + 1)
    else:  # below grazing: an even grid (its edges are followed in sigma itself, not ln sigma)
        grid = np.linspace(s0, s1, 4 * per + 1)
    values = np.geomspace(a, b, args.num) if args.log else np.linspace(a, b, args.num)
    problem = ChartProblem(params, args.param2, values, args.log, args.M_max, grid,
                           transient=150 if args.quick else 250, samples=24,
                           xtol_rel=1e-3 if args.quick else 1e-4, xtol=args.xtol)
    t0 = time.perf_counter()
    # every model flag written out (not only --config, which may change or be missing later)
    osc = [f"--{k} {params[k]!r}" for k in ("nu", "Omega", "r", "Gamma") if k in params]
    cmd = " ".join(["chart", *osc, f"--wall {wall}", f"--param2 {args.param2}", f"--range={args.range_}",
                    f"--num {args.num}", *(["--log"] if args.log else []), f"--M-max {args.M_max}",
                    f"--sigma-range={args.sigma_range}", *([f"--per-decade {args.per_decade}"] if args.per_decade else []),
                    *(["--quick"] if args.quick else []),
                    *([f"--xtol {args.xtol!r}"] if args.xtol is not None else []), f"--solver {args.solver}", f"--out {args.out}"])
    res = chart(problem, args.out, args.fmu, args.backend, args.workers, args.scheduler, cmd)
    from ..analysis.chart.contradictions import count_line
    from ..analysis.chart.wall_free import row_label

    for M, cl in res["closes"].items():
        if cl["closes"] is None:
            print(f"M = {row_label(M)}: does not close in {args.param2} in [{args.range_}]")
        else:
            print(f"M = {row_label(M)}: closes at {args.param2} = {cl['closes']:.6g} (sigma {cl['sigma']:.4g}): {cl['how']}")
    print(count_line(res["contradictions"]))
    print(f"wrote {Path(args.out) / 'chart.json'}, chart.png, report.md ({time.perf_counter() - t0:.1f} s)")
    return 0
