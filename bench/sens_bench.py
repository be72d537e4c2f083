"""Benchmark: cost per period of the FMU's solver modes, with and without sensitivities.

    .venv/bin/python bench/sens_bench.py            # measures, rewrites BENCHMARKS.md's sens section
    .venv/bin/python bench/sens_bench.py --quick    # smoke test: fewer periods, prints only

At Figure 9 (sigma = 0.5, the period-2 orbit), from the same state on the attractor, one
process pinned to one core, CPU time per period (best of the repeats), one doStep of one period
per period:

- the FMU through fmpy (FMU2Slave: doStep, getReal of (u, v) -- plus the six sensitivities when
  they are on -- and getInteger of impacts), CVODE mode (solver = 0) and closed-form mode
  (solver = 1), each with sensitivities off and on;
- the FMU driven from C through its FMI 2.0 functions (bench/c_driver.c), both modes;
- the closed form driven from C directly, no FMI (bench/cf_driver.c: STEPPER_CLOSED_FORM, the
  code the FMU runs with solver = 1) -- the "bare C closed form";
and each method's one-period map error against mapcheck.exact from its own states.
The ratio (closed form through fmpy) / (bare C closed form) has the goal <= 5.
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

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import numpy as np  # noqa: E402
from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi2 import FMU2Slave  # noqa: E402

from mapcheck.exact import ExactOscillator  # noqa: E402
from sections import write_section  # noqa: E402

FMU = ROOT / "build" / "fmu" / "ImpactOscillator.fmu"
FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112, sigma=0.5, r=0.9, Gamma=10.0, wall=1)
SENS = ("J_uu", "J_uv", "J_vu", "J_vv", "S_u", "S_v")
GOAL = 5.0
BEGIN, END = "<!-- sens:begin -->", "<!-- sens:end -->"


def build(workdir: Path) -> dict[str, Path]:
    """The two C drivers (system C compiler)."""
    cc = os.environ.get("CC", "cc")
    src = ROOT / "fmu_src"
    cf = workdir / "cf_driver"
    subprocess.run([cc, "-O2", "-I", str(src), str(ROOT / "bench" / "cf_driver.c"),
                    *(str(src / f) for f in ("closed_form.c", "stepper.c", "sens.c", "model.c")),
                    "-lm", "-o", str(cf)],
                   check=True)
    fd = workdir / "c_driver"
    subprocess.run([cc, "-O2", "-I", str(src / "include" / "fmi2"), str(ROOT / "bench" / "c_driver.c"),
                    "-o", str(fd), "-ldl"], check=True)
    return dict(cf=cf, fmi=fd)


def parse_runs(stdout: str) -> list[float]:
    return [float(line.split()[2]) for line in stdout.splitlines() if line.startswith("run ")]


def bare_closed_form(exe: Path, x0, periods: int, repeat: int, sens: bool, workdir: Path):
    out = workdir / "cf.bin"
    args = [str(exe), "0", str(periods), str(repeat), str(int(sens)), str(out)]
    args += [f"{k}={float(v)!r}" for k, v in FIG9.items()] + [f"u0={x0[0]!r}", f"v0={x0[1]!r}"]
    proc = subprocess.run(args, check=True, capture_output=True, text=True)
    rec = np.fromfile(out).reshape(-1, 9)
    return min(parse_runs(proc.stdout)) / periods, rec[:, :2]


def fmi_from_c(exe: Path, unzip: str, md, x0, periods: int, repeat: int, solver: int, workdir: Path):
    out = workdir / "fmi.bin"
    lib = Path(unzip) / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"
    vr = {v.name: v.valueReference for v in md.modelVariables}
    args = [str(exe), str(lib), md.guid, (Path(unzip) / "resources").as_uri(), "0", str(periods), str(repeat),
            str(out)]
    for k, x in dict(FIG9, u0=x0[0], v0=x0[1]).items():
        args.append(f"i:{vr[k]}={int(x)}" if k == "wall" else f"r:{vr[k]}={float(x)!r}")
    args.append(f"i:{vr['solver']}={solver}")
    proc = subprocess.run(args, check=True, capture_output=True, text=True)
    rec = np.fromfile(out).reshape(-1, 3)
    return min(parse_runs(proc.stdout)) / periods, rec[:, :2]


def through_fmpy(unzip: str, md, x0, periods: int, repeat: int, solver: int, sens: bool):
    """doStep + getReal + getInteger per period, as the harness's strobe does."""
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName="bench")
    s.instantiate()
    reals = [vr["u"], vr["v"]] + ([vr[n] for n in SENS] if sens else [])
    imp = [vr["impacts"]]
    best, xs = float("inf"), None
    for rep in range(repeat):
        if rep:
            s.reset()
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        p = dict(FIG9, u0=x0[0], v0=x0[1])
        s.setReal([vr[k] for k in p if k != "wall"], [float(p[k]) for k in p if k != "wall"])
        s.setInteger([vr["wall"], vr["solver"]], [1, solver])
        s.setBoolean([vr["sensitivities"]], [sens])
        s.exitInitializationMode()
        rows = []
        c0 = time.process_time()
        for k in range(periods):
            s.doStep(float(k), 1.0)
            rows.append(s.getReal(reals))
            s.getInteger(imp)
        best = min(best, time.process_time() - c0)
        xs = np.array(rows)[:, :2]
    s.terminate()
    s.freeInstance()
    return best / periods, xs


def map_error(x0, xs: np.ndarray, n: int) -> float:
    """Max over the first n periods of the one-period error against mapcheck.exact."""
    osc = ExactOscillator(FIG9["nu"], FIG9["Omega"], FIG9["sigma"], FIG9["r"], FIG9["Gamma"], "compliant")
    states = np.vstack([np.asarray(x0)[None, :], xs])
    err = 0.0
    for k in range(min(n, len(xs))):
        s, _ = osc.strobe(states[k, 0], states[k, 1], [float(k + 1)], t0=float(k))
        err = max(err, float(np.max(np.abs(s[0] - states[k + 1]))))
    return err


def measure(quick: bool) -> dict:
    try:
        cpu = max(os.sched_getaffinity(0))
        os.sched_setaffinity(0, {cpu})
        pinned = f"pinned to CPU {cpu}"
    except (AttributeError, OSError):  # pragma: no cover
        pinned = "not pinned"
    n_cv, n_cf, rep, n_err = (40, 400, 2, 5) if quick else (1000, 20000, 5, 40)
    md = read_model_description(str(FMU))
    unzip = extract(str(FMU))
    res = dict(date=_dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M"), quick=quick,
               pinned=pinned, load_start=os.getloadavg()[0], case="Figure 9, sigma = 0.5", methods={})
    with tempfile.TemporaryDirectory(prefix="sens-bench-") as tmp:
        work = Path(tmp)
        exe = build(work)
        # the start: 300 periods from rest, by the closed form (the attractor's period-2 orbit)
        _, xs = bare_closed_form(exe["cf"], (-1.0, 0.0), 300, 1, False, work)
        x0 = (float(xs[-1, 0]), float(xs[-1, 1]))
        res["x0"] = x0
        M = res["methods"]

        def put(key, label, sec, xs, periods):
            M[key] = dict(label=label, us=sec * 1e6, periods=periods, map_error=map_error(x0, xs, n_err))

        for sens in (False, True):
            tag = "+sens" if sens else ""
            sec, xs = through_fmpy(unzip, md, x0, n_cv, rep, 0, sens)
            put("fmpy_cvode" + tag, f"FMU through fmpy, CVODE mode{', sensitivities' if sens else ''}", sec, xs, n_cv)
            sec, xs = through_fmpy(unzip, md, x0, n_cf, rep, 1, sens)
            put("fmpy_closed" + tag, f"FMU through fmpy, closed-form mode{', sensitivities' if sens else ''}",
                sec, xs, n_cf)
            sec, xs = bare_closed_form(exe["cf"], x0, n_cf, rep, sens, work)
            put("bare_closed" + tag, f"bare C closed form (bench/cf_driver.c){', sensitivities' if sens else ''}",
                sec, xs, n_cf)
        sec, xs = fmi_from_c(exe["fmi"], unzip, md, x0, n_cv, rep, 0, work)
        put("c_fmi_cvode", "FMU from C (bench/c_driver.c), CVODE mode", sec, xs, n_cv)
        sec, xs = fmi_from_c(exe["fmi"], unzip, md, x0, n_cf, rep, 1, work)
        put("c_fmi_closed", "FMU from C (bench/c_driver.c), closed-form mode", sec, xs, n_cf)
    res["ratio"] = M["fmpy_closed"]["us"] / M["bare_closed"]["us"]
    res["load_end"] = os.getloadavg()[0]
    return res


def accuracy() -> dict:
    """The sensitivities against the closed form, and the two solver modes against each other.

    - regular: J and S of one period (both modes) against Richardson-extrapolated central
      differences of mapcheck.exact (the Python closed form, exact crossing times), max relative
      error over the cases of tests/fmu/test_sensitivities.py;
    - near grazing: a contact x deep (the wall-free orbit at sigma = x), CVODE mode against
      closed-form mode, and both against differences of mapcheck.exact with steps 1e-2 x; the
      slope of log max|J| against log x (expected -1/2);
    - CVODE mode against closed-form mode, one period from the same state, max |du|, |dv| over
      12 periods of each case of tests/fmu/test_closed_form.py.
    """
    from tests.support.fmu import on_orbit
    from tests.support.sensitivities import UNDERDAMPED, Fmu, exact_derivatives, one_period
    from tests.fmu.test_closed_form import CASES as CF_CASES
    from tests.fmu.test_sensitivities import CASES as SENS_CASES

    def rel(a, b):
        return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))

    f = Fmu(2)
    out: dict = {}
    worst = {0: 0.0, 1: 0.0}
    errs = []
    for p in SENS_CASES.values():
        for t0 in (0.55, 0.8):
            st = on_orbit(p["sigma"], t0)
            x0 = (st["u0"], st["v0"])
            Jx, Sx = exact_derivatives(p, x0, t0)
            for solver in (0, 1):
                _, J, S = one_period(f, p, x0, t0, solver=solver)
                e = max(rel(J, Jx), rel(S, Sx))
                worst[solver] = max(worst[solver], e)
                errs.append(e)
    out["regular"] = dict(cvode=worst[0], closed=worst[1], median=float(np.median(errs)), n=len(errs))
    rows = []
    for wall in (1, 2):
        p = dict(UNDERDAMPED, wall=wall, Gamma=100.0)
        for x in (1e-4, 1e-6, 1e-8, 1e-9):
            q = dict(p, sigma=x)
            st = on_orbit(x, 0.5)
            x0 = (st["u0"], st["v0"])
            _, J0, S0 = one_period(f, q, x0, 0.5, solver=0)
            _, J1, S1 = one_period(f, q, x0, 0.5, solver=1)
            row = dict(wall=wall, depth=x, norm=float(np.max(np.abs(J1))), cvode_vs_closed=rel(J0, J1))
            if x >= 1e-6:
                Jx, _ = exact_derivatives(q, x0, 0.5, h=1e-2 * x)
                row["closed_vs_differences"] = rel(J1, Jx)
            rows.append(row)
        d = np.logspace(-5, -12, 8)
        norms = []
        for x in d:
            st = on_orbit(x, 0.5)
            norms.append(np.max(np.abs(one_period(f, dict(p, sigma=x), (st["u0"], st["v0"]), 0.5, solver=1)[1])))
        out[f"slope_wall{wall}"] = float(np.polyfit(np.log(d), np.log(norms), 1)[0])
    out["grazing"] = rows
    worst_state = 0.0
    for p in CF_CASES.values():
        f.start(0.5, **p, **on_orbit(p["sigma"], 0.5), solver=1)
        xs = []
        for k in range(1, 13):
            f.step(0.5 + k)
            xs.append(f.state())
        for k in range(len(xs) - 1):
            a, _, _ = one_period(f, p, xs[k], 0.5 + k + 1, sens=False, solver=0)
            b, _, _ = one_period(f, p, xs[k], 0.5 + k + 1, sens=False, solver=1)
            worst_state = max(worst_state, float(np.max(np.abs(a - b))))
    out["cvode_vs_closed_per_period"] = worst_state
    f.close()
    return out


def fig9_both(workdir: Path) -> dict:
    """`reproduce fig9 --quick` with each solver (one worker): wall and CPU seconds, ODE edges."""
    out = {}
    for solver in ("cvode", "closed-form"):
        dest = workdir / f"fig9_{solver}"
        t0, c0 = time.perf_counter(), os.times()
        subprocess.run([sys.executable, "-m", "harness", "reproduce", "fig9", "--quick", "--workers", "1",
                        "--solver", solver, "--out", str(dest)], check=True, cwd=ROOT, capture_output=True)
        c1 = os.times()
        out[solver] = dict(wall=time.perf_counter() - t0, cpu=c1.children_user + c1.children_system
                           - c0.children_user - c0.children_system,
                           edges=json.loads((dest / "fig9.json").read_text())["windows"]["ode"])
    out["same_edges"] = out["cvode"]["edges"] == out["closed-form"]["edges"]
    return out


def section(res: dict) -> str:
    M = res["methods"]
    L = [BEGIN, "## Solver modes and sensitivities", "",
         f"Generated by `python bench/sens_bench.py` on {res['date']} (UTC); {res['case']}, from the state "
         f"(u, v) = ({res['x0'][0]:.17g}, {res['x0'][1]:.17g}) on the attractor (300 periods from rest); "
         f"{res['pinned']}; load average {res['load_start']:.2f} / {res['load_end']:.2f} (start / end). "
         "CPU time per period, best of the repeats, one doStep (or closed-form advance_to) of one period per "
         "period. *Map error*: max one-period error against mapcheck.exact from the method's own states.", "",
         "| method | us/period (CPU) | x bare C closed form | periods timed | map error |",
         "|---|---:|---:|---:|---:|"]
    base = M["bare_closed"]["us"]
    for m in M.values():
        L.append(f"| {m['label']} | {m['us']:.2f} | {m['us'] / base:.1f} | {m['periods']} | {m['map_error']:.1e} |")
    ok = res["ratio"] <= GOAL
    L += ["", f"Goal: closed form through fmpy / bare C closed form <= {GOAL:g}: "
          f"**{res['ratio']:.2f}** ({'met' if ok else 'not met'}). "
          f"Sensitivities cost {M['fmpy_cvode+sens']['us'] / M['fmpy_cvode']['us']:.2f}x in CVODE mode "
          f"(8 equations instead of 2) and {M['bare_closed+sens']['us'] / M['bare_closed']['us']:.2f}x in the "
          f"bare closed form; CVODE mode / closed-form mode through fmpy: "
          f"{M['fmpy_cvode']['us'] / M['fmpy_closed']['us']:.0f}x.", ""]
    A = res.get("accuracy")
    if A:
        L += ["Accuracy (same run): J, S of one period against Richardson-extrapolated differences of "
              f"mapcheck.exact, {A['regular']['n']} cases away from grazing: max relative error "
              f"{A['regular']['cvode']:.1e} (CVODE mode), {A['regular']['closed']:.1e} (closed form), median "
              f"{A['regular']['median']:.1e}. CVODE mode against closed-form mode, one period from the same "
              f"state, every case of tests/fmu/test_closed_form.py: max {A['cvode_vs_closed_per_period']:.1e}. "
              f"Near grazing, max|J| ~ depth^s with s = {A['slope_wall1']:.3f} (compliant), "
              f"{A['slope_wall2']:.3f} (rigid), depths 1e-5 .. 1e-12:", "",
              "| wall | depth | max abs J | CVODE vs closed form (rel) | closed form vs differences (rel) |",
              "|---|---:|---:|---:|---:|"]
        for r in A["grazing"]:
            d = r.get("closed_vs_differences")
            L.append(f"| {'compliant' if r['wall'] == 1 else 'rigid'} | {r['depth']:.0e} | {r['norm']:.3g} | "
                     f"{r['cvode_vs_closed']:.1e} | {'' if d is None else f'{d:.1e}'} |")
        L.append("")
    F = res.get("fig9")
    if F:
        L += [f"`python -m harness reproduce fig9 --quick --workers 1`: CVODE {F['cvode']['wall']:.1f} s wall "
              f"({F['cvode']['cpu']:.1f} s CPU), closed form {F['closed-form']['wall']:.1f} s wall "
              f"({F['closed-form']['cpu']:.1f} s CPU); the ODE's window edges "
              f"{'are identical' if F['same_edges'] else 'differ'} (M: [lo, hi] "
              + "; ".join(f"{k}: [" + ", ".join("none" if x is None else f"{x:.5f}" for x in v) + "]"
                          for k, v in sorted(F['cvode']['edges'].items())) + ").", ""]
    L.append(END)
    return "\n".join(L)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="smoke test: few periods, print only")
    ap.add_argument("--json", help="also write all numbers as JSON")
    ap.add_argument("--fig9", action="store_true", help="with --quick: also time reproduce fig9 in both modes")
    ap.add_argument("--out", help="markdown file to update (default BENCHMARKS.md, none with --quick)")
    args = ap.parse_args(argv)
    res = measure(args.quick)
    res["accuracy"] = accuracy()
    if args.fig9 or not args.quick:
        with tempfile.TemporaryDirectory(prefix="sens-fig9-") as tmp:
            res["fig9"] = fig9_both(Path(tmp))
    text = section(res)
    print(text)
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=1))
    out = args.out or (None if args.quick else str(ROOT / "BENCHMARKS.md"))
    if out:
        write_section(Path(out), text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
