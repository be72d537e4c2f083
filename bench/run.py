"""Benchmarks: cost per drive period against peers and against the closed-form limit.

    .venv/bin/python bench/run.py             # full run, writes BENCHMARKS.md (~15 min)
    .venv/bin/python bench/run.py --quick     # smoke test (< 1 min), prints the table only

For two cases -- Figure 9 (sigma = 0.5, a period-2 orbit) and the underdamped oscillator
(nu = 0.196, Omega = 7.368, Gamma = 1000, sigma = 0.01, a period-3 orbit) -- and from the same
state on the attractor (after a transient), one process pinned to one core measures:

1. the C FMU driven by the harness (``strobe``: one doStep of one period, one getReal of (u, v),
   one getInteger of impacts per period);
2. the same FMU, same settings, driven by ``bench/c_driver.c`` (compiled here with the system C
   compiler against the FMU's extracted shared library): the same FMI calls, no Python;
3. the pythonfmu twin through the harness;
4. scipy ``solve_ivp`` (DOP853) with a direction-aware terminal event on u, restarted at each
   crossing, one call per period on the local time [0, 1], at the loosest tolerance of a search
   that is as accurate as the FMU;
5. ``mapcheck.exact.ExactOscillator.strobe`` (the closed form).

Costs are CPU seconds of the process (``time.process_time`` / ``CLOCK_PROCESS_CPUTIME_ID``),
best of several repeats, because the machine is shared (wall seconds are reported too).
Accuracy: the one-period map error of every method against the closed form, from the method's
own state at the start of each evaluated period (max over u and v, max over the periods), and
wall contacts per period against the closed form's (missed / invented).
Also: the Figure 9 reproduction (``python -m harness reproduce fig9 --quick``) and a plain
process-pool sweep on 1 and 2 workers (parallel efficiency, peak memory), a 10^6-period run of
the C driver with its one-period error at the end, and mapcheck's map iterations per second.

The parts, next to this script: ``methods.py`` (the five methods and their accuracy against the
closed form), ``parallel_jobs.py`` (parallel efficiency and memory), ``markdown_report.py`` (the
Markdown of BENCHMARKS.md), ``sections.py`` (the sections other benchmark scripts keep in it).
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

# the benchmark's parts, next to this script (bench/ is the script's folder, first on sys.path)
from markdown_report import goals_table, machine, markdown, report  # noqa: E402
from methods import (  # noqa: E402
    C_FMU, CASES, DOP853_ATOL_OVER_RTOL, PY_FMU, Case, Orbit, best, build_c_driver, c_driver_args,
    dop853_tolerance, map_accuracy, oracle, run_c_driver, run_dop853, run_exact, run_harness,
    transient_state,
)
from parallel_jobs import parallel_runs  # noqa: E402
from sections import keep_sections  # noqa: E402

SETTINGS = {
    # periods: timed periods per method; repeat: best of; eval: periods whose one-period map
    # error and contacts are checked against the closed form; search: periods per DOP853
    # tolerance tried.
    False: dict(transient=300, periods_c=2000, repeat_c=5, periods_twin=200, repeat_twin=2,
                periods_dop=200, repeat_dop=2, periods_exact=100, eval=100, search=40,
                long_periods=1_000_000, map_orbits=200_000, map_iter=200, parallel_repeat=2),
    True: dict(transient=100, periods_c=200, repeat_c=3, periods_twin=10, repeat_twin=1,
               periods_dop=20, repeat_dop=1, periods_exact=10, eval=8, search=6,
               long_periods=10_000, map_orbits=50_000, map_iter=50, parallel_repeat=1),
}


def pin_one_core() -> str:
    """Pin this process (and the C driver it starts) to one core."""
    try:
        cpu = max(os.sched_getaffinity(0))
        os.sched_setaffinity(0, {cpu})
        return f"pinned to CPU {cpu}"
    except (AttributeError, OSError):  # pragma: no cover - not Linux
        return "not pinned"


# ------------------------------------------------------------------------------------------
# long run, map speed
# ------------------------------------------------------------------------------------------
def long_run(driver: Path, periods: int, workdir: Path) -> dict:
    case = CASES[0]
    x0 = transient_state(case, 300)
    out = workdir / "long.bin"
    proc = subprocess.run(c_driver_args(driver, case, x0, periods, 1, out), check=True, capture_output=True, text=True)
    _, wall, cpu = next(line.split() for line in proc.stdout.splitlines() if line.startswith("run "))
    rec = np.fromfile(out, dtype=np.float64).reshape(-1, 3)
    osc = oracle(case)
    x = np.vstack([np.asarray(x0)[None, :], rec[:, :2]])
    n = np.diff(np.concatenate([[0.0], rec[:, 2]])).astype(int)
    early = map_accuracy(osc, Orbit(x[:6], n[:5]), 5)
    late = map_accuracy(osc, Orbit(x[-6:], n[-5:]), 5)
    return dict(periods=periods, cpu_s=float(cpu), wall_s=float(wall), us_cpu=float(cpu) / periods * 1e6,
                error_first=early["map_error"], error_last=late["map_error"],
                contacts=int(rec[-1, 2]), missed_last=late["missed"], invented_last=late["invented"])


def map_speed(n_orbits: int, n_iter: int) -> dict:
    from mapcheck import coefficients
    from mapcheck.bifurcation import PiecewiseMap
    from mapcheck.linear import invert_alpha_gamma
    from mapcheck.windows import MapParams

    inv = invert_alpha_gamma(0.99, 0.01)
    c = coefficients(inv.nu, inv.Omega, 0.9, "compliant")
    f = PiecewiseMap(MapParams.from_coefficients(c))
    rho = c.rho(np.linspace(0.0, 1.0, n_orbits))
    rates = []
    for _ in range(3):
        x, y = np.zeros(n_orbits), np.zeros(n_orbits)
        t0 = time.process_time()
        f.iterate_inplace(x, y, rho, n_iter)
        rates.append(n_orbits * n_iter / (time.process_time() - t0))
    return dict(orbits=n_orbits, iterations=n_iter, per_s=max(rates))


def measure_case(case: Case, S: dict, driver: Path, work: Path) -> dict:
    """Cost per period and accuracy of the five methods on one case, from the same start."""
    print(f"[{case.key}] transient ...", file=sys.stderr, flush=True)
    x0 = transient_state(case, S["transient"])
    osc = oracle(case)
    methods = {}
    # C FMU: harness and bare C driver interleaved (load changes hit both)
    h_runs, c_runs = [], []
    for _ in range(S["repeat_c"]):
        h, h_orb = run_harness(C_FMU, case, x0, S["periods_c"], 1)
        c, c_orb = run_c_driver(driver, case, x0, S["periods_c"], 1, work)
        h_runs.append((h["us_cpu"], h["us_wall"]))
        c_runs.append((c["us_cpu"], c["us_wall"]))
    same = bool(np.array_equal(h_orb.x, c_orb.x) and np.array_equal(h_orb.n, c_orb.n))
    for key, runs, orb, label in (("harness", h_runs, h_orb, "C FMU through the harness"),
                                  ("c_driver", c_runs, c_orb, "C FMU, bare C driver")):
        m = best([(a * 1e-6, b * 1e-6) for a, b in runs], 1)
        m.update(timed_periods=S["periods_c"], repeats=len(runs), label=label,
                 settings="CVODE Adams, rtol 1e-12, atol 1e-14; doStep 1 period")
        m.update(map_accuracy(osc, orb, S["eval"]))
        methods[key] = m
    print(f"[{case.key}] twin ...", file=sys.stderr, flush=True)
    m, orb = run_harness(PY_FMU, case, x0, S["periods_twin"], S["repeat_twin"])
    m.update(label="pythonfmu twin through the harness",
             settings="CVODE (scikit-sundae) Adams, rtol 1e-12, atol 1e-14")
    m.update(map_accuracy(osc, orb, min(S["eval"], S["periods_twin"])))
    methods["twin"] = m
    print(f"[{case.key}] DOP853 ...", file=sys.stderr, flush=True)
    rtol, tried = dop853_tolerance(case, osc, x0, S["search"], methods["harness"])
    m, orb = run_dop853(case, x0, S["periods_dop"], S["repeat_dop"], rtol)
    m.update(label="scipy solve_ivp DOP853, event restarts",
             settings=f"rtol {rtol:.0e}, atol {rtol * DOP853_ATOL_OVER_RTOL:.0e}")
    m.update(map_accuracy(osc, orb, min(S["eval"], S["periods_dop"])))
    methods["dop853"] = m
    print(f"[{case.key}] closed form ...", file=sys.stderr, flush=True)
    m, orb = run_exact(osc, x0, S["periods_exact"])
    m.update(label="closed form (mapcheck.exact)", settings="ExactOscillator.strobe")
    m.update(map_accuracy(osc, orb, min(S["eval"], S["periods_exact"])))
    methods["exact"] = m
    return dict(key=case.key, title=case.title, x0=list(map(float, x0)), same_orbit=same,
                dop853_rtol=rtol, dop853_search=tried, methods=methods)


def measure(args: argparse.Namespace, S: dict) -> dict:
    """Every measurement of the run: parallel jobs first (they need both cores), then each case
    pinned to one core, map speed and the long run."""
    res = dict(quick=args.quick, date=_dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M"),
               load_start=os.getloadavg()[0], pinned="not pinned", transient=S["transient"], machine=machine(),
               settings=S, cases=[])
    with tempfile.TemporaryDirectory(prefix="impact-bench-") as tmp:
        work = Path(tmp)
        driver = build_c_driver(work)
        if args.no_parallel:
            res["parallel"] = []
        else:  # first: it needs both cores, and a shared machine is often quieter at the start
            print("parallel ...", file=sys.stderr, flush=True)
            res["parallel"] = parallel_runs(args.quick, S["parallel_repeat"], work)
        res["pinned"] = pin_one_core()
        res["cases"] = [measure_case(case, S, driver, work) for case in CASES]
        print("map speed ...", file=sys.stderr, flush=True)
        res["map_speed"] = map_speed(S["map_orbits"], S["map_iter"])
        print(f"long run ({S['long_periods']} periods) ...", file=sys.stderr, flush=True)
        res["long_run"] = long_run(driver, S["long_periods"], work)
    res["load_end"] = os.getloadavg()[0]
    _, g = goals_table(res)
    res["goals"] = {k: dict(value=v, met=ok) for k, (v, ok) in g.items()}
    return res


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="smoke test: few periods, small parallel job")
    ap.add_argument("--out", help="markdown report (default: BENCHMARKS.md in full mode, none with --quick)")
    ap.add_argument("--json", help="also write all numbers as JSON")
    ap.add_argument("--long-periods", type=int, help="periods of the long run (default 10^6, quick 10^4)")
    ap.add_argument("--no-parallel", action="store_true", help="skip the parallel-efficiency runs")
    ap.add_argument("--from-json", metavar="FILE", help="no measurement: rewrite the report from a --json file")
    args = ap.parse_args(argv)
    if args.from_json:
        res = json.loads(Path(args.from_json).read_text())
        text = report(res, "python bench/run.py" + (" --quick" if res["quick"] else ""))
        path = Path(args.out or ROOT / "BENCHMARKS.md")
        path.write_text(keep_sections(path, text))
        return 0
    S = dict(SETTINGS[args.quick])
    if args.long_periods:
        S["long_periods"] = args.long_periods
    res = measure(args, S)
    text = report(res, "python bench/run.py" + (" --quick" if args.quick else ""))
    print(markdown(res))
    print()
    print(goals_table(res)[0])
    out = args.out or (None if args.quick else str(ROOT / "BENCHMARKS.md"))
    if out:
        Path(out).write_text(keep_sections(Path(out), text))
        print(f"wrote {out}", file=sys.stderr)
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=1, default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
