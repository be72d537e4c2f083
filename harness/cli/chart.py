"""``impact-harness chart``: where the ODE's windows close over (sigma, a second parameter)
(:mod:`harness.analysis.chart.run`; written by :func:`harness.analysis.chart.chart.chart`).

The run comes from the same layers as every command (the FMU's start values < ``--config``
file < flags and ``--set``); the problem is built and checked by the library
(:func:`harness.analysis.chart.problem.chart_problem`), whose errors name its Python arguments
(``p_range``, ``M_max``), shown here as the flags that set them."""
from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

from ..analysis.chart.chart import chart
from ..analysis.chart.problem import chart_params, chart_problem
from .experiment_args import command_line, experiment_of
from .options import count, experiment_options, theta_option, xtol_option

__all__ = ["register", "cmd_chart"]


def register(sub: Any, parents: dict[str, argparse.ArgumentParser]) -> None:
    """Add the ``chart`` subcommand."""
    p = sub.add_parser("chart", help="where the ODE's windows close over (sigma, a second parameter): edges continued, maps (48)/(39) beside",
                       description="The stable maximal windows found at the start of --range, their edges continued "
                       "in (sigma, --param2) and where each window closes, and how; every edge point checked across "
                       "itself; the windows measured again from scratch at --num values (the brute-force check); "
                       "chart.json, chart.png, report.md. nu, Omega and r from flags or an experiment file's [model] "
                       "table (--config harness/experiments/fig9.toml); --set any other FMU parameter.")
    experiment_options(p)
    c = p.add_argument_group("chart")
    c.add_argument("--param2", required=True, help="second parameter: Gamma, r, nu, Omega or any FMU parameter")
    c.add_argument("--range", required=True, dest="p_range", metavar="START:STOP", help="its range")
    c.add_argument("--num", type=count, default=30, metavar="N", help="values of the second parameter (default 30)")
    c.add_argument("--log", action="store_true", help="geometric values, log axis")
    c.add_argument("--M-max", type=count, default=5, dest="M_max", metavar="M", help="highest period charted (default 5)")
    c.add_argument("--sigma-range", default="0.05:400", metavar="LO:HI",
                   help="sigma range of the scans (default 0.05:400, geometric); LO <= 0 (> -1) reaches below "
                   "grazing, an even grid of 4 x --per-decade intervals (--sigma-range=-0.3:0.3)")
    xtol_option(c, "1e-4 x the edge's sigma, 1e-3 with --quick")
    c.add_argument("--per-decade", type=count, default=None, metavar="N", help="scan points per decade of sigma (default 16, quick 10)")
    theta_option(c)
    c.add_argument("--quick", action="store_true", help="coarser scans and tolerances")
    r = p.add_argument_group("run")
    r.add_argument("--backend", dest="run__backend", choices=("processes", "dask", "serial"), default=None)
    r.add_argument("--scheduler", dest="run__scheduler", metavar="tcp://HOST:PORT", help="Dask scheduler address (tcp://HOST:PORT)")
    r.add_argument("--workers", "-j", dest="run__workers", type=count, metavar="N", help="worker processes (default: all cores)")
    r.add_argument("--out", "-o", default="results/chart", metavar="DIR", help="output directory")
    p.set_defaults(func=cmd_chart)


def cmd_chart(args: argparse.Namespace) -> int:
    run = experiment_of(args)
    problem = chart_problem(chart_params(run), args.param2, args.p_range, args.num, args.log, args.M_max,
                            args.sigma_range, args.per_decade, args.quick, args.xtol, args.theta)
    t0 = time.perf_counter()
    res = chart(problem, args.out, command=command_line(args), run=run)
    from ..analysis.chart.contradictions import count_line
    from ..analysis.chart.wall_free import row_label

    for M, cl in res["closes"].items():
        if cl["closes"] is None:
            print(f"M = {row_label(M)}: does not close in {args.param2} in [{args.p_range}]")
        else:
            print(f"M = {row_label(M)}: closes at {args.param2} = {cl['closes']:.6g} (sigma {cl['sigma']:.4g}): {cl['how']}")
    print(count_line(res["contradictions"]))
    print(f"wrote {Path(args.out) / 'chart.json'}, chart.png, report.md ({time.perf_counter() - t0:.1f} s)")
    return 0
