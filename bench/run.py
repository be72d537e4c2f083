"""Benchmarks (issue 7): cost per drive period against peers and against the closed-form limit.

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
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import math
import os
import platform
import shlex
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one core

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

from harness.fmu.fmi import FmuModel, open_source  # noqa: E402
from harness.dynamics.maps.sampling import sample_periods, strobe  # noqa: E402
from harness.fmu.simulator import FmuSimulator  # noqa: E402
from mapcheck.exact import ExactOscillator, forcing_amplitude_phase  # noqa: E402
from sections import keep_sections  # noqa: E402  (bench/sections.py, next to this script)

C_FMU = ROOT / "build" / "fmu" / "ImpactOscillator.fmu"
PY_FMU = ROOT / "build" / "fmu" / "ImpactOscillatorPy.fmu"
PYTHON = sys.executable
TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class Case:
    key: str
    title: str
    params: dict  # FMU parameters (wall 1 = compliant)


CASES = (
    Case("fig9", "Figure 9: (alpha, gamma) = (0.99, 0.01), Gamma = 10, r = 0.9, sigma = 0.5 (period 2)",
         dict(nu=4.605170185988091, Omega=0.3059238689620112, sigma=0.5, r=0.9, Gamma=10.0, wall=1)),
    Case("underdamped", "underdamped: nu = 0.196, Omega = 7.368, Gamma = 1000, r = 0.9, sigma = 0.01 (period 3)",
         dict(nu=0.196, Omega=7.368, sigma=0.01, r=0.9, Gamma=1000.0, wall=1)),
)

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
DOP853_RTOLS = (1e-8, 3e-9, 1e-9, 3e-10, 1e-10, 3e-11, 1e-11, 3e-12, 1e-12, 1e-13)
DOP853_ATOL_OVER_RTOL = 1e-2

GOALS = {
    "harness_over_c": 1.15,      # FMU through the harness / bare C driver  <= 1.15
    "dop853_over_fmu": 10.0,     # DOP853 at equal accuracy / FMU through the harness >= 10
    "efficiency_2": 0.85,        # 2-worker parallel efficiency >= 0.85
    "map_iterations": 1e7,       # map iterations per second >= 1e7
}


# ------------------------------------------------------------------------------------------
# helpers
# ------------------------------------------------------------------------------------------
_ALL_CPUS: set[int] | None = None


def pin_one_core() -> str:
    """Pin this process (and the C driver it starts) to one core."""
    global _ALL_CPUS
    try:
        _ALL_CPUS = set(os.sched_getaffinity(0))
        cpu = max(_ALL_CPUS)
        os.sched_setaffinity(0, {cpu})
        return f"pinned to CPU {cpu}"
    except (AttributeError, OSError):  # pragma: no cover - not Linux
        return "not pinned"


def unpin() -> None:
    """Give the process (and the parallel jobs it starts) all its cores back."""
    if _ALL_CPUS:
        os.sched_setaffinity(0, _ALL_CPUS)


def fmu_params(model: FmuModel, case: Case) -> dict:
    """All settable parameters as the harness sets them: the FMU's defaults, then the case's."""
    p = model.defaults()
    p.pop("u0", None)
    p.pop("v0", None)
    p.update({k: v for k, v in case.params.items() if k in model.variables})
    return p


def oracle(case: Case) -> ExactOscillator:
    p = case.params
    return ExactOscillator(p["nu"], p["Omega"], p["sigma"], r=p["r"], Gamma=p["Gamma"], wall="compliant")


@dataclass
class Orbit:
    """x[k] = (u, v) at t = k (x[0] the common start), n[k] = contacts in period k -> k+1."""

    x: np.ndarray
    n: np.ndarray


def map_accuracy(osc: ExactOscillator, orbit: Orbit, n_eval: int) -> dict:
    """One-period map error against the closed form from the method's own states, and contacts."""
    errs, missed, invented, exact_total = [], 0, 0, 0
    for k in range(min(n_eval, len(orbit.n))):
        s, c = osc.strobe(orbit.x[k, 0], orbit.x[k, 1], [1.0], t0=0.0)  # the ODE is 1-periodic
        errs.append(float(np.max(np.abs(orbit.x[k + 1] - s[0]))))
        missed += max(int(c[0]) - int(orbit.n[k]), 0)
        invented += max(int(orbit.n[k]) - int(c[0]), 0)
        exact_total += int(c[0])
    return dict(map_error=max(errs), map_error_median=float(np.median(errs)), eval_periods=len(errs),
                contacts_exact=exact_total, missed=missed, invented=invented)


def best(runs: list[tuple[float, float]], periods: int) -> dict:
    """Best (CPU, wall) seconds of repeated runs -> per-period numbers."""
    cpu = min(r[0] for r in runs) / periods
    wall = min(r[1] for r in runs) / periods
    return dict(us_cpu=cpu * 1e6, us_wall=wall * 1e6, periods_per_s=1.0 / cpu, timed_periods=periods,
                repeats=len(runs))


# ------------------------------------------------------------------------------------------
# the methods
# ------------------------------------------------------------------------------------------
def transient_state(case: Case, n: int) -> tuple[float, float]:
    """(u, v) at t = n from (-1, 0) at t = 0, by the C FMU through the harness."""
    model = FmuModel(C_FMU)
    with FmuSimulator(model.source(), instance_name="transient") as sim:
        r = strobe(sim, fmu_params(model, case), (-1.0, 0.0), theta=0.0, n_transient=n - 1, n_samples=1)
    return r.final_state


def run_harness(path: Path, case: Case, x0, periods: int, repeat: int) -> tuple[dict, Orbit]:
    model = FmuModel(path)
    params = fmu_params(model, case)
    runs = []
    with FmuSimulator(model.source(), instance_name="bench") as sim:
        for _ in range(repeat):
            c0, w0 = time.process_time(), time.perf_counter()
            sim.start(params, 0.0, x0)
            r = sample_periods(sim, 0, periods)
            runs.append((time.process_time() - c0, time.perf_counter() - w0))
    x = np.vstack([np.asarray(x0, dtype=float)[None, :], np.column_stack([r.u, r.v])])
    return best(runs, periods), Orbit(x, r.impacts.astype(int))


def build_c_driver(workdir: Path) -> Path:
    exe = workdir / "c_driver"
    cc = os.environ.get("CC", "cc")
    cmd = [cc, "-O2", "-I", str(ROOT / "fmu_src" / "include" / "fmi2"), str(ROOT / "bench" / "c_driver.c"),
           "-o", str(exe), "-ldl"]
    subprocess.run(cmd, check=True)
    return exe


def c_driver_args(driver: Path, case: Case, x0, periods: int, repeat: int, out: Path) -> list[str]:
    model = FmuModel(C_FMU)
    unzipdir, _ = open_source(model.source())
    lib = Path(unzipdir) / "binaries" / "linux64" / f"{model.model_identifier}.so"
    resources = (Path(unzipdir) / "resources").as_uri()
    values = {**fmu_params(model, case), "u0": float(x0[0]), "v0": float(x0[1])}
    args = [str(driver), str(lib), model.guid, resources, "0", str(periods), str(repeat), str(out)]
    for name, value in values.items():
        var = model.variables[name]
        if var.type == "Real":
            args.append(f"r:{var.value_reference}={float(value)!r}")
        elif var.type == "Boolean":
            args.append(f"b:{var.value_reference}={int(bool(value))}")
        else:
            args.append(f"i:{var.value_reference}={int(value)}")
    return args


def run_c_driver(driver: Path, case: Case, x0, periods: int, repeat: int, workdir: Path) -> tuple[dict, Orbit]:
    out = workdir / f"c_{case.key}.bin"
    proc = subprocess.run(c_driver_args(driver, case, x0, periods, repeat, out), check=True,
                          capture_output=True, text=True)
    runs = [(float(c), float(w)) for _, w, c in (line.split() for line in proc.stdout.splitlines()
                                                 if line.startswith("run "))]
    rec = np.fromfile(out, dtype=np.float64).reshape(-1, 3)
    x = np.vstack([np.asarray(x0, dtype=float)[None, :], rec[:, :2]])
    n = np.diff(np.concatenate([[0.0], rec[:, 2]])).astype(int)
    return best(runs, periods), Orbit(x, n)


class Dop853Oscillator:
    """The oscillator as a scipy user would write it: solve_ivp(DOP853) with a terminal,
    direction-aware event on u, restarted at each crossing, one call per period on the local
    time [0, 1] (the ODE is 1-periodic)."""

    def __init__(self, case: Case, rtol: float, atol: float):
        p = case.params
        self.nu, self.Om2 = p["nu"], p["Omega"] ** 2
        self.k2 = p["Gamma"] * self.Om2
        self.r = p["r"]
        F_g, self.phi = forcing_amplitude_phase(p["nu"], p["Omega"])
        self.A = (1.0 + p["sigma"]) * F_g
        self.rtol, self.atol = rtol, atol
        nu, Om2, k2, A, phi = self.nu, self.Om2, self.k2, self.A, self.phi
        cos = math.cos

        def free(t, y):
            return [y[1], A * cos(TWO_PI * t + phi) - nu * y[1] - Om2 * (y[0] + 1.0)]

        def wall(t, y):
            return [y[1], A * cos(TWO_PI * t + phi) - nu * y[1] - Om2 * (y[0] + 1.0) - k2 * y[0]]

        def enter(t, y):
            return y[0]

        def leave(t, y):
            return y[0]

        enter.terminal, enter.direction = True, 1.0
        leave.terminal, leave.direction = True, -1.0
        self.modes = {False: (free, enter), True: (wall, leave)}

    def orbit(self, x0, periods: int) -> Orbit:
        x = np.empty((periods + 1, 2))
        n = np.zeros(periods, dtype=int)
        y = np.array(x0, dtype=float)
        x[0] = y
        inside = y[0] > 0.0
        for k in range(periods):
            t = 0.0
            while True:
                f, ev = self.modes[inside]
                sol = solve_ivp(f, (t, 1.0), y, method="DOP853", rtol=self.rtol, atol=self.atol, events=ev)
                if sol.status == 1:  # a crossing: jump, switch mode, restart there
                    t = float(sol.t_events[0][0])
                    u, v = sol.y_events[0][0]
                    if inside:
                        y = np.array([0.0, v])
                    else:
                        y = np.array([0.0, self.r * v])
                        n[k] += 1
                    inside = not inside
                    continue
                if sol.status != 0:
                    raise RuntimeError(sol.message)
                y = sol.y[:, -1].copy()
                break
            x[k + 1] = y
        return Orbit(x, n)


def run_dop853(case: Case, x0, periods: int, repeat: int, rtol: float) -> tuple[dict, Orbit]:
    solver = Dop853Oscillator(case, rtol, rtol * DOP853_ATOL_OVER_RTOL)
    runs = []
    for _ in range(repeat):
        c0, w0 = time.process_time(), time.perf_counter()
        orb = solver.orbit(x0, periods)
        runs.append((time.process_time() - c0, time.perf_counter() - w0))
    return best(runs, periods), orb


def dop853_tolerance(case: Case, osc: ExactOscillator, x0, periods: int, target: dict) -> tuple[float, list]:
    """Loosest rtol of DOP853_RTOLS at least as accurate as ``target`` (the FMU's accuracy:
    max and median one-period map error, no contact missed or invented); else the tightest."""
    tried = []
    for rtol in DOP853_RTOLS:
        orb = Dop853Oscillator(case, rtol, rtol * DOP853_ATOL_OVER_RTOL).orbit(x0, periods)
        acc = map_accuracy(osc, orb, periods)
        tried.append(dict(rtol=rtol, map_error=acc["map_error"], map_error_median=acc["map_error_median"],
                          missed=acc["missed"], invented=acc["invented"]))
        if (acc["map_error"] <= target["map_error"] and acc["map_error_median"] <= target["map_error_median"]
                and acc["missed"] == 0 and acc["invented"] == 0):
            return rtol, tried
    return DOP853_RTOLS[-1], tried


def run_exact(osc: ExactOscillator, x0, periods: int) -> tuple[dict, Orbit]:
    c0, w0 = time.process_time(), time.perf_counter()
    s, c = osc.strobe(x0[0], x0[1], np.arange(1, periods + 1, dtype=float), t0=0.0)
    run = (time.process_time() - c0, time.perf_counter() - w0)
    x = np.vstack([np.asarray(x0, dtype=float)[None, :], s])
    return best([run], periods), Orbit(x, np.diff(np.concatenate([[0], c])).astype(int))


# ------------------------------------------------------------------------------------------
# parallel efficiency, memory
# ------------------------------------------------------------------------------------------
def _tree_cpu(pid: int, seen: dict) -> int:
    """Update ``seen[pid] = CPU seconds`` for the process tree of ``pid``; return its summed RSS."""
    import psutil

    try:
        p = psutil.Process(pid)
        procs = [p] + p.children(recursive=True)
    except psutil.Error:
        return 0
    total = 0
    for q in procs:
        try:
            with q.oneshot():
                total += q.memory_info().rss
                t = q.cpu_times()
                seen[q.pid] = t.user + t.system
        except psutil.Error:
            pass
    return total


def timed_command(cmd: list[str]) -> dict:
    """Wall seconds of a command, the peak of the summed RSS of its process tree, and the CPU
    seconds of each of its processes (polled every 50 ms)."""
    peak = [0]
    seen: dict[int, float] = {}
    w0 = time.perf_counter()
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    done = threading.Event()

    def poll():
        while not done.is_set():
            peak[0] = max(peak[0], _tree_cpu(proc.pid, seen))
            done.wait(0.05)

    th = threading.Thread(target=poll, daemon=True)
    th.start()
    out, _ = proc.communicate()
    wall = time.perf_counter() - w0
    done.set()
    th.join()
    if proc.returncode != 0:
        raise RuntimeError(f"{shlex.join(cmd)} failed ({proc.returncode}):\n{out[-2000:]}")
    main_cpu = seen.pop(proc.pid, 0.0)
    others = sorted(seen.values(), reverse=True)
    return dict(wall_s=wall, peak_rss_mb=peak[0] / 2**20, cpu_main=main_cpu, cpu_children=others,
                cpu_total=main_cpu + sum(others), cpu_critical=main_cpu + (others[0] if others else 0.0))


def parallel_runs(quick: bool, repeat: int, workdir: Path) -> list[dict]:
    """Wall time on 1 and 2 workers of the Figure 9 reproduction (full mode only) and of a
    fresh-start sigma sweep at Figure 9's parameters (process-pool backend)."""
    jobs = []
    if not quick:
        jobs.append(("reproduce fig9 --quick",
                     lambda w: [PYTHON, "-m", "harness", "reproduce", "fig9", "--quick", "--workers", str(w),
                                "--no-progress", "--out", str(workdir / f"fig9_w{w}")]))
    n, tr, sa = (8, 60, 12) if quick else (91, 300, 40)
    f9 = CASES[0].params
    sweep_args = ["--set", f"nu={f9['nu']!r}", "--set", f"Omega={f9['Omega']!r}", "--set", "Gamma=10",
                  "--set", "r=0.9", "--start", "0.15", "--stop", "1.0", "--num", str(n), "--mode", "fresh",
                  "--transient", str(tr), "--samples", str(sa), "--no-plot", "--no-progress",
                  "--backend", "processes"]
    jobs.append((f"sweep fig9 fresh, {n} sigma x {tr + sa} periods",
                 lambda w: [PYTHON, "-m", "harness", "sweep", *sweep_args, "--workers", str(w),
                            "--out", str(workdir / f"sweep_w{w}.nc")]))
    rows = []
    for name, make in jobs:
        res = {1: [], 2: []}
        for _ in range(repeat):
            for w in (1, 2):  # interleaved: load changes on the shared machine hit both
                load = os.getloadavg()[0]
                r = timed_command(make(w))
                r["load_before"] = load
                res[w].append(r)
        b1 = min(res[1], key=lambda r: r["wall_s"])
        b2 = min(res[2], key=lambda r: r["wall_s"])
        c1 = min(r["cpu_total"] for r in res[1])
        c2 = min(r["cpu_critical"] for r in res[2])
        rows.append(dict(job=name, command=shlex.join(make(2)).replace(str(workdir), "$TMP").replace(PYTHON, "python"),
                         wall_1=b1["wall_s"], wall_2=b2["wall_s"], efficiency=b1["wall_s"] / (2 * b2["wall_s"]),
                         cpu_total_1=c1, cpu_critical_2=c2, efficiency_cpu=c1 / (2 * c2),
                         cpu_main_2=min(r["cpu_main"] for r in res[2]),
                         cpu_workers_2=min(res[2], key=lambda r: r["cpu_critical"])["cpu_children"][:2],
                         cpu_total_2=min(r["cpu_total"] for r in res[2]),
                         peak_rss_mb_1=max(r["peak_rss_mb"] for r in res[1]),
                         peak_rss_mb_2=max(r["peak_rss_mb"] for r in res[2]),
                         all_walls_1=[r["wall_s"] for r in res[1]], all_walls_2=[r["wall_s"] for r in res[2]],
                         loads=[r["load_before"] for w in (1, 2) for r in res[w]]))
    return rows


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


# ------------------------------------------------------------------------------------------
# report
# ------------------------------------------------------------------------------------------
def machine() -> dict:
    cpu = "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import fmpy
    import scipy

    return dict(cpu=cpu, cores=os.cpu_count(), system=f"{platform.system()} {platform.release()}",
                python=platform.python_version(), numpy=np.__version__, scipy=scipy.__version__,
                fmpy=fmpy.__version__,
                cc=subprocess.run([os.environ.get("CC", "cc"), "--version"], capture_output=True,
                                  text=True).stdout.splitlines()[0])


def fmt_e(x: float) -> str:
    return f"{x:.1e}"


def fmt_us(x: float) -> str:
    return f"{x:,.0f}" if x >= 100 else f"{x:.1f}"


def markdown(res: dict) -> str:
    L = []
    L.append("| case | method | settings | us/period (CPU) | periods/s | us/period (wall) | x bare C | "
             "one-period map error (max / median) | contacts (closed form) | missed | invented |")
    L.append("|---|---|---|---:|---:|---:|---:|---|---:|---:|---:|")
    for case in res["cases"]:
        c_us = case["methods"]["c_driver"]["us_cpu"]
        for key, m in case["methods"].items():
            err = "0 (reference)" if key == "exact" else f"{fmt_e(m['map_error'])} / {fmt_e(m['map_error_median'])}"
            if key == "exact":
                err += f"; restart vs continue {fmt_e(m['map_error'])}"
            L.append(f"| {case['key']} | {m['label']} | {m['settings']} | {fmt_us(m['us_cpu'])} | "
                     f"{m['periods_per_s']:,.0f} | {fmt_us(m['us_wall'])} | {m['us_cpu'] / c_us:.2f} | {err} | "
                     f"{m['contacts_exact']} in {m['eval_periods']} | {m['missed']} | {m['invented']} |")
    return "\n".join(L)


def goals_table(res: dict) -> tuple[str, dict]:
    g = {}
    rows = ["| goal | target | measured | met |", "|---|---|---|---|"]
    for case in res["cases"]:
        m = case["methods"]
        ratio = m["harness"]["us_cpu"] / m["c_driver"]["us_cpu"]
        ok = ratio <= GOALS["harness_over_c"]
        g[f"harness_over_c_{case['key']}"] = (ratio, ok)
        rows.append(f"| FMU through the harness / bare C driver ({case['key']}) | <= {GOALS['harness_over_c']} | "
                    f"{ratio:.3f} | {'yes' if ok else 'no'} |")
    for case in res["cases"]:
        m = case["methods"]
        ratio = m["dop853"]["us_cpu"] / m["harness"]["us_cpu"]
        ok = ratio >= GOALS["dop853_over_fmu"]
        g[f"dop853_over_fmu_{case['key']}"] = (ratio, ok)
        rows.append(f"| DOP853 at equal accuracy / FMU through the harness ({case['key']}) | >= {GOALS['dop853_over_fmu']:g} | "
                    f"{ratio:.1f} | {'yes' if ok else 'no'} |")
    for p in res["parallel"]:
        ok = p["efficiency"] >= GOALS["efficiency_2"]
        g[f"efficiency_{p['job']}"] = (p["efficiency"], ok)
        ok_cpu = p["efficiency_cpu"] >= GOALS["efficiency_2"]
        g[f"efficiency_cpu_{p['job']}"] = (p["efficiency_cpu"], ok_cpu)
        rows.append(f"| 2-worker parallel efficiency ({p['job']}) | >= {GOALS['efficiency_2']} | "
                    f"wall {p['efficiency']:.2f}; CPU critical path {p['efficiency_cpu']:.2f} | "
                    f"{'yes' if ok else 'no'} (wall); {'yes' if ok_cpu else 'no'} (CPU critical path) |")
    ms = res["map_speed"]["per_s"]
    ok = ms >= GOALS["map_iterations"]
    g["map_iterations"] = (ms, ok)
    rows.append(f"| mapcheck map iterations per second (one core) | >= 1e7 | {ms:.3g} | {'yes' if ok else 'no'} |")
    return "\n".join(rows), g


def report(res: dict, command: str) -> str:
    mc = res["machine"]
    goals, _ = goals_table(res)
    L = ["# Benchmarks", "",
         f"Generated by `{command}` on {res['date']} (UTC). Mode: {'quick (smoke test)' if res['quick'] else 'full'}.",
         "",
         f"Machine: {mc['cpu']}, {mc['cores']} cores, {mc['system']}; Python {mc['python']}, numpy {mc['numpy']}, "
         f"scipy {mc['scipy']}, fmpy {mc['fmpy']}; {mc['cc']}. Shared machine: load average "
         f"{res['load_start']:.2f} at the start, {res['load_end']:.2f} at the end (1-minute). "
         f"Timings: {res['pinned']}; CPU time of the process, best of the repeats "
         "(wall time alongside; under load it is longer).",
         "",
         "## Cost per drive period and accuracy", "",
         "Same start for every method: the state at t = " + str(res["transient"]) + " after a transient "
         "from (u, v) = (-1, 0) at t = 0 (C FMU through the harness), then one period per step. "
         "*x bare C*: CPU time relative to the bare C driver. *One-period map error*: "
         "max(|du|, |dv|) of the method's state one period after its own state at the start of each "
         "evaluated period, against `mapcheck.exact.ExactOscillator`; max and median over the "
         "evaluated periods. *Contacts*: wall entries per period against the closed form's from the "
         "same state.",
         "", markdown(res), ""]
    for case in res["cases"]:
        d = case["dop853_search"]
        L.append(f"- {case['key']}: {case['title']}; start (u, v) = ({case['x0'][0]:.17g}, {case['x0'][1]:.17g}). "
                 f"Harness and bare C driver read the same orbit bit for bit: {case['same_orbit']}. "
                 f"DOP853 tolerance search over {res['settings']['search']} periods (rtol, atol = 1e-2 rtol: "
                 "one-period error max / median, missed/invented): "
                 + "; ".join(f"{t['rtol']:.0e}: {fmt_e(t['map_error'])} / {fmt_e(t['map_error_median'])}, "
                             f"{t['missed']}/{t['invented']}" for t in d)
                 + f" -> rtol {case['dop853_rtol']:.0e}, the loosest at least as accurate as the FMU "
                 f"(max {fmt_e(case['methods']['harness']['map_error'])}, median "
                 f"{fmt_e(case['methods']['harness']['map_error_median'])}, no contact missed or invented).")
    L += ["", "## Goals (ratios measured in the same run)", "", goals, ""]
    L += ["## Parallel efficiency and memory (process-pool backend)", "",
          "| job | wall, 1 worker (s) | wall, 2 workers (s) | efficiency T1/(2 T2), wall | CPU, 1 worker: all processes (s) | CPU, 2 workers: main + busiest worker (s) | efficiency, CPU critical path | peak RSS, all processes, 1 / 2 workers (MB) | load average before each run |",
          "|---|---:|---:|---:|---:|---:|---:|---|---|"]
    for p in res["parallel"]:
        L.append(f"| {p['job']} | {p['wall_1']:.1f} | {p['wall_2']:.1f} | {p['efficiency']:.2f} | "
                 f"{p['cpu_total_1']:.1f} | {p['cpu_main_2']:.1f} + {(p['cpu_workers_2'] or [0])[0]:.1f} | "
                 f"{p['efficiency_cpu']:.2f} | "
                 f"{p['peak_rss_mb_1']:.0f} / {p['peak_rss_mb_2']:.0f} | {', '.join(f'{x:.1f}' for x in p['loads'])} |")
    L += ["", "*Efficiency, wall*: the goal's definition; on a shared 2-core machine it also measures "
          "how much CPU the other users left. *Efficiency, CPU critical path*: CPU seconds of the "
          "1-worker run (all its processes) over twice the CPU seconds of the 2-worker run's critical "
          "path (its main process plus its busiest worker) -- what an idle 2-core machine would give, "
          "load imbalance, serial parts and duplicated start-up included. CPU seconds are polled per "
          "process every 50 ms with psutil.", ""]
    for p in res["parallel"]:
        L.append(f"- `{p['command']}` (and `--workers 1`); all wall times: 1 worker "
                 f"{', '.join(f'{x:.1f}' for x in p['all_walls_1'])} s, 2 workers "
                 f"{', '.join(f'{x:.1f}' for x in p['all_walls_2'])} s (best taken); 2 workers: CPU of the "
                 f"main process {p['cpu_main_2']:.1f} s, of the two busiest workers "
                 f"{', '.join(f'{x:.1f}' for x in p['cpu_workers_2'])} s, all processes {p['cpu_total_2']:.1f} s.")
    lr = res["long_run"]
    L += ["", "## Long run", "",
          f"{lr['periods']:,} periods of the Figure 9 case (sigma = 0.5) with the bare C driver, one doStep per period: "
          f"{lr['cpu_s']:.1f} s CPU ({lr['wall_s']:.1f} s wall), {lr['us_cpu']:.0f} us/period, "
          f"{lr['contacts']:,} contacts. One-period map error at the start {fmt_e(lr['error_first'])}, "
          f"over the last 5 periods {fmt_e(lr['error_last'])} (missed/invented contacts there: "
          f"{lr['missed_last']}/{lr['invented_last']}).", ""]
    ms = res["map_speed"]
    L += ["## Map iterations", "",
          f"mapcheck's 2D map (37)/(38) with (48), Figure 9's parameters, in-place kernel "
          f"(`PiecewiseMap.iterate_inplace`), {ms['orbits']:,} orbits x {ms['iterations']} iterations, one core: "
          f"**{ms['per_s']:.3g} iterations/s** (`python bench/map_speed.py` gives the other variants).", ""]
    L += ["## Rerun", "", "```bash",
          "bash scripts/test.sh -k bench_smoke        # set-up, build, then the smoke test (bench/run.py --quick)",
          ".venv/bin/python bench/run.py              # this file (full mode, ~15-20 min)",
          ".venv/bin/python bench/run.py --quick      # smoke test: table only, < 1 min",
          ".venv/bin/python bench/fmu_long_run.py     # 10^6 periods through fmpy, error after 10 and 10^6",
          ".venv/bin/python bench/map_speed.py        # map iterations per second, all variants",
          ".venv/bin/python bench/sens_bench.py       # solver modes and sensitivities (its own section)",
          ".venv/bin/python bench/basins_bench.py     # basin scans: batch kernel, FMU path (its own section)",
          "```", ""]
    notes = ROOT / "bench" / "analysis.md"
    if notes.exists():
        L += [notes.read_text().rstrip(), ""]
    return "\n".join(L)


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
        pinned = pin_one_core()
        res["pinned"] = pinned
        for case in CASES:
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
            res["cases"].append(dict(key=case.key, title=case.title, x0=list(map(float, x0)), same_orbit=same,
                                     dop853_rtol=rtol, dop853_search=tried, methods=methods))
        print("map speed ...", file=sys.stderr, flush=True)
        res["map_speed"] = map_speed(S["map_orbits"], S["map_iter"])
        print(f"long run ({S['long_periods']} periods) ...", file=sys.stderr, flush=True)
        res["long_run"] = long_run(driver, S["long_periods"], work)
    res["load_end"] = os.getloadavg()[0]
    _, g = goals_table(res)
    res["goals"] = {k: dict(value=v, met=ok) for k, (v, ok) in g.items()}
    command = "python bench/run.py" + (" --quick" if args.quick else "")
    text = report(res, command)
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
