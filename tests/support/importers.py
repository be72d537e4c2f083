"""Shared parts of the independent-importer tests (fmusim, libcosim): where fmusim is, how to run
it, and the closed form with piecewise-constant inputs that every run is compared with.

fmusim is built by scripts/setup.sh from a source tree outside the repository
(``$IMPACT_SHARED/tools/fmusim-v0.0.39``, default ``../shared``). Without that source the fmusim
tests skip, naming the path; with the source but no binary (the build failed) they fail.
"""
from __future__ import annotations

import csv
import os
import subprocess
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description

from mapcheck.exact import ExactOscillator
from tests.support.fmu import ROOT

FMUSIM_VERSION = "fmusim-v0.0.39"
FMUSIM_BIN = ROOT / "build" / "tools" / "fmusim"
WALL_CODES = {"none": 0, "compliant": 1, "rigid": 2}
#: per-period error allowed for Co-Simulation (the FMU's own CVODE at rtol 1e-12)
CS_TOL = 1e-8


def fmusim_source() -> Path:
    """Where scripts/setup.sh looks for fmusim's source (same rule as the script)."""
    shared = os.environ.get("IMPACT_SHARED") or str(ROOT.parent / "shared")
    return Path(shared) / "tools" / FMUSIM_VERSION


def fmusim() -> Path:
    """The built fmusim; skip only when its source is absent, fail when the build is missing."""
    if FMUSIM_BIN.is_file() and os.access(FMUSIM_BIN, os.X_OK):
        return FMUSIM_BIN
    src = fmusim_source()
    if not (src / "build.sh").is_file():
        pytest.skip(f"fmusim source not found at {src} (set IMPACT_SHARED to the folder "
                    "holding tools/); scripts/setup.sh builds it from there")
    pytest.fail(f"fmusim source is at {src} but {FMUSIM_BIN} is missing: the build in "
                "scripts/setup.sh failed (see build/tools/fmusim-build.log)")


@dataclass(frozen=True)
class Case:
    """One oscillator set-up: parameters, start state and the inputs as a step list."""

    nu: float
    Omega: float
    sigma: float
    wall: str = "compliant"
    Gamma: float = 10.0
    r: float = 0.9
    u0: float = -0.1
    v0: float = 0.0

    def start_values(self) -> dict[str, float]:
        return {"nu": self.nu, "Omega": self.Omega, "sigma": self.sigma, "r": self.r,
                "Gamma": self.Gamma, "wall": WALL_CODES[self.wall], "u0": self.u0,
                "v0": self.v0}

    def oscillator(self, F_ext: float = 0.0, u_wall: float = 0.0) -> ExactOscillator:
        return ExactOscillator(self.nu, self.Omega, self.sigma, r=self.r, Gamma=self.Gamma,
                               wall=self.wall, F_ext=F_ext, u_wall=u_wall)


def exact_piecewise(case: Case, holds: list[tuple[float, float, float]],
                    times: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[float]]:
    """The closed form under inputs held constant between switching times.

    Parameters
    ----------
    case : Case
    holds : list of (t_start, F_ext, u_wall)
        Sorted by t_start, the first at the start time 0: the inputs from t_start until the next
        entry. At a switch the state is kept and the compliant wall's mode follows the side the
        mass is on (the FMU's documented CS rule, docs/fmu.md; ExactOscillator's start rule).
    times : ndarray
        Sorted output times >= 0.

    Returns
    -------
    states : ndarray (len(times), 2)
    impacts : ndarray of int
        Cumulative wall entries/impacts since 0.
    entry_times : list of float
        The time of every counted entry/impact (for ``t_impact``).
    """
    times = np.asarray(times, dtype=float)
    states = np.empty((times.size, 2))
    counts = np.zeros(times.size, dtype=int)
    u, v, n, entries = case.u0, case.v0, 0, []
    ends = [t for t, _, _ in holds[1:]] + [np.inf]
    for (t_a, F, w), t_b in zip(holds, ends):
        ex = case.oscillator(F_ext=F, u_wall=w)
        sel = (times >= t_a) & (times < t_b) if np.isfinite(t_b) else times >= t_a
        t_end = t_b if np.isfinite(t_b) else max(float(times[-1]), t_a)
        if np.any(sel):
            s, c = ex.strobe(u, v, times[sel], t_a)
            states[sel], counts[sel] = s, c + n
        entries += [t for t, kind in ex.crossings(u, v, t_a, t_end) if kind in ("enter", "impact")]
        (u, v), = ex.strobe(u, v, [t_end], t_a)[0]
        n = len(entries)
    return states, counts, entries


def fmusim_holds_cs(inputs: list[tuple[float, float, float]], grid: np.ndarray
                    ) -> list[tuple[float, float, float]]:
    """What a Co-Simulation FMU sees from fmusim's input file: at each communication point t_k
    (the grid, with the file's input events in it) the file's value there, linearly
    interpolated between rows, at a repeated time the later row (FMIStaticInput.c), held over
    the step."""
    t_in = np.array([row[0] for row in inputs])
    out = []
    for t in grid[:-1]:
        i = int(np.searchsorted(t_in, t, side="right")) - 1  # last row with time <= t
        if i >= len(inputs) - 1:
            out.append((float(t), inputs[-1][1], inputs[-1][2]))
            continue
        (t0, F0, w0), (t1, F1, w1) = inputs[i], inputs[i + 1]
        out.append((float(t), F0 + (t - t0) * (F1 - F0) / (t1 - t0),
                    w0 + (t - t0) * (w1 - w0) / (t1 - t0)))
    return merge_holds(out)


def merge_holds(holds: list[tuple[float, float, float]]) -> list[tuple[float, float, float]]:
    """Drop holds that repeat the previous values: no switch there (fewer closed-form
    segments)."""
    return [x for i, x in enumerate(holds) if i == 0 or x[1:] != holds[i - 1][1:]]


def write_input_csv(path: Path, inputs: list[tuple[float, float, float]]) -> Path:
    """fmusim's input file: a header, then time, F_ext, u_wall (a repeated time is a step)."""
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time", "F_ext", "u_wall"])
        w.writerows([(repr(t), repr(F), repr(u)) for t, F, u in inputs])
    return path


OUTPUTS = ("u", "v", "impacts", "t_impact")


def run_fmusim(fmu: Path, tmp: Path, case: Case, *, interface: str, stop: float, h: float,
               flags: tuple[str, ...] = (), input_csv: Path | None = None,
               tolerance: float | None = None) -> np.ndarray:
    """Run fmusim on ``fmu`` and return its result rows as a structured array."""
    out = tmp / f"out_{interface}_{h}_{len(flags)}.csv"
    cmd = [str(fmusim()), "--interface-type", interface, "--stop-time", repr(stop),
           "--output-interval", repr(h), "--output-file", str(out), *flags]
    for k, x in case.start_values().items():
        cmd += ["--start-value", k, repr(x)]
    declared = {v.name for v in read_model_description(str(fmu)).modelVariables}
    for name in OUTPUTS:  # the twin has no t_impact
        if name in declared:
            cmd += ["--output-variable", name]
    if input_csv is not None:
        cmd += ["--input-file", str(input_csv)]
    if tolerance is not None:
        cmd += ["--tolerance", repr(tolerance)]
    # a C host as a user has it: no Python environment variables (the twin must find its own)
    env = {k: v for k, v in os.environ.items()
           if not k.startswith("PYTHON") and k not in ("VIRTUAL_ENV", "LD_PRELOAD")}
    run = subprocess.run(cmd + [str(fmu)], capture_output=True, text=True, timeout=120, env=env)
    assert run.returncode == 0, f"fmusim failed ({run.returncode}): {run.stderr}{run.stdout}"
    return np.genfromtxt(out, delimiter=",", names=True)


def at_periods(t: np.ndarray, n_periods: int) -> np.ndarray:
    """Index of the last row at each t = 1 .. n_periods (after an event's second row)."""
    idx = []
    for n in range(1, n_periods + 1):
        hit = np.nonzero(np.abs(t - n) < 1e-9)[0]
        assert hit.size, f"no output at t = {n}"
        idx.append(int(hit[-1]))
    return np.array(idx)


@dataclass
class PeriodCheck:
    """Per-period comparison of a run with the closed form."""

    err_u: float
    err_v: float
    impacts: int
    impacts_exact: int
    scale: float  # max(1, largest |u|, |v| of the closed form at the periods)


def compare_per_period(t: np.ndarray, u: np.ndarray, v: np.ndarray, impacts: np.ndarray,
                       t_impact: np.ndarray | None, case: Case,
                       holds: list[tuple[float, float, float]], n_periods: int,
                       t_impact_tol: float = 1e-9) -> PeriodCheck:
    """Compare at t = 1 .. n_periods: states, cumulative impact counts (asserted equal at every
    period) and, when given, t_impact (the last entry's time, asserted within t_impact_tol)."""
    k = at_periods(t, n_periods)
    times = t[k]
    want, counts, entries = exact_piecewise(case, holds, times)
    np.testing.assert_array_equal(impacts[k].astype(int), counts)
    if t_impact is not None:
        for j, n in zip(k, counts):
            if n:
                assert abs(t_impact[j] - entries[n - 1]) <= t_impact_tol, (t[j], t_impact[j])
    return PeriodCheck(float(np.max(np.abs(u[k] - want[:, 0]))),
                       float(np.max(np.abs(v[k] - want[:, 1]))), int(impacts[k[-1]]),
                       int(counts[-1]), max(1.0, float(np.abs(want).max())))
