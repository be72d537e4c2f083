"""The five ways bench/run.py advances the oscillator one drive period, each timed the same way
and checked against the closed form (:func:`map_accuracy`).

1. the C FMU through the harness (:func:`run_harness`: one doStep, one getReal of (u, v), one
   getInteger of impacts per period);
2. the same FMU driven by ``bench/c_driver.c`` (:func:`run_c_driver`): the same FMI calls, no Python;
3. the pythonfmu twin through the harness (:func:`run_harness` on build/fmu/ImpactOscillatorPy.fmu);
4. scipy ``solve_ivp`` (DOP853) with event restarts (:class:`Dop853Oscillator`), at the loosest
   tolerance as accurate as the FMU (:func:`dop853_tolerance`);
5. ``mapcheck.exact.ExactOscillator.strobe``, the closed form (:func:`run_exact`).
"""
from __future__ import annotations

import math
import os
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

from harness.dynamics.maps.sampling import sample_periods, strobe
from harness.fmu.fmi import FmuModel, open_source
from harness.fmu.simulator import FmuSimulator
from mapcheck.exact import ExactOscillator, forcing_amplitude_phase

ROOT = Path(__file__).resolve().parents[1]
C_FMU = ROOT / "build" / "fmu" / "ImpactOscillator.fmu"
PY_FMU = ROOT / "build" / "fmu" / "ImpactOscillatorPy.fmu"
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

DOP853_RTOLS = (1e-8, 3e-9, 1e-9, 3e-10, 1e-10, 3e-11, 1e-11, 3e-12, 1e-12, 1e-13)
DOP853_ATOL_OVER_RTOL = 1e-2


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
