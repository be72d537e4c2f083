"""Cost per communication step against the step size h, in fmpy and in ecos.

    .venv/bin/python bench/cosim_bench.py            # measures, rewrites BENCHMARKS.md's cosim section
    .venv/bin/python bench/cosim_bench.py --quick    # smoke test: short runs, print only

The ImpactOscillator FMU (FMI 2.0 CS) alone, Figure 9's parameters at sigma = 0.5 (compliant
wall, one contact per period), driven for a fixed simulated time with one doStep per
communication point, h = 1e-3 .. 1:

- fmpy: ``FMU2Slave.doStep`` in a Python loop, plus one ``getReal`` of (u, v) per step (what a
  master does to read the outputs);
- ecos (ecospy): ``EcosSimulation.step()`` per point plus ``get_real`` of u and v, and
  ``step(n)`` (the whole run inside ecos, no Python per step).

Per step: wall time / number of steps; per period: the same times 1/h.  CVODE's work per period
is nearly independent of h (it reads each communication point off its interpolant instead of
restarting there), so at small h the fixed cost of a communication step (the master's calls, the
FMU's step set-up and outputs) dominates.  One run on a shared machine: ratios, not absolutes.
"""
from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))
from sections import write_section  # noqa: E402  (bench/sections.py: the marked sections)

FMU = ROOT / "build" / "fmu" / "ImpactOscillator.fmu"
BEGIN, END = "<!-- cosim:begin -->", "<!-- cosim:end -->"
SIGMA = 0.5
STEPS = [1e-3, 3e-3, 1e-2, 3e-2, 0.1, 0.3, 1.0]


def run_fmpy(h: float, t1: float) -> float:
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(FMU))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(FMU)), modelIdentifier="ImpactOscillator",
                  instanceName="bench")
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.setReal([vr["sigma"], vr["u0"], vr["v0"]], [SIGMA, SIGMA, 0.0])
    s.exitInitializationMode()
    n, t, out = int(round(t1 / h)), 0.0, [vr["u"], vr["v"]]
    start = time.perf_counter()
    for _ in range(n):
        s.doStep(t, h)
        s.getReal(out)
        t += h
    elapsed = time.perf_counter() - start
    s.terminate()
    s.freeInstance()
    return elapsed / n


def run_ecos(h: float, t1: float, per_step: bool) -> float:
    from ecospy import EcosLib, EcosSimulation, EcosSimulationStructure

    EcosLib.set_log_level("warn")
    n = int(round(t1 / h))
    with EcosSimulationStructure() as ss:
        ss.add_model("osc", str(FMU))
        ss.add_parameter_set("init", {"osc::sigma": SIGMA, "osc::u0": SIGMA, "osc::v0": 0.0})
        with EcosSimulation(structure=ss, step_size=h) as sim:
            sim.init(parameter_set="init")
            start = time.perf_counter()
            if per_step:
                for _ in range(n):
                    sim.step()
                    sim.get_real("osc::u")
                    sim.get_real("osc::v")
            else:
                sim.step(n)
            elapsed = time.perf_counter() - start
            sim.terminate()
    return elapsed / n


def measure(quick: bool) -> list[dict]:
    rows = []
    for h in STEPS:
        # simulated time: >= 2 periods, and at most ~20000 steps
        t1 = 2.0 if quick else max(4.0, min(40.0, 20000 * h))
        if quick:
            t1 = max(h, min(2.0, 500 * h))
        row = {"h": h, "t1": t1}
        for name, f in (("fmpy", lambda: run_fmpy(h, t1)),
                        ("ecos_step", lambda: run_ecos(h, t1, True)),
                        ("ecos_run", lambda: run_ecos(h, t1, False))):
            row[name] = min(f() for _ in range(1 if quick else 3))
        rows.append(row)
        print(f"h = {h:g}: " + ", ".join(f"{k} {row[k] * 1e6:.1f} us/step"
                                          for k in ("fmpy", "ecos_step", "ecos_run")),
              file=sys.stderr, flush=True)
    return rows


def section(rows: list[dict]) -> str:
    L = [BEGIN, "## Co-simulation: cost per communication step against h", "",
         "`bench/cosim_bench.py`: the FMU alone (FMI 2.0 CS, Figure 9, sigma = 0.5, compliant "
         "wall), one doStep per communication point; best of 3 runs; "
         f"load average {os.getloadavg()[0]:.1f} at the end (shared 2-core machine). fmpy: "
         "`FMU2Slave.doStep` + `getReal(u, v)` from Python; ecos per step: "
         "`EcosSimulation.step()` + two `get_real`; ecos run: `step(n)` inside ecos.", "",
         "| h | steps | fmpy us/step | ecos us/step (per step) | ecos us/step (run) | "
         "fmpy us/period | ecos us/period (run) |",
         "|---|---|---|---|---|---|---|"]
    for r in rows:
        n = int(round(r["t1"] / r["h"]))
        L.append(f"| {r['h']:g} | {n} | {r['fmpy'] * 1e6:.1f} | {r['ecos_step'] * 1e6:.1f} | "
                 f"{r['ecos_run'] * 1e6:.1f} | {r['fmpy'] / r['h'] * 1e6:.0f} | "
                 f"{r['ecos_run'] / r['h'] * 1e6:.0f} |")
    big, small = rows[-1], rows[0]
    L += ["", f"Per period, h = {small['h']:g} costs {small['fmpy'] / small['h'] / (big['fmpy'] / big['h']):.1f}x "
          f"h = {big['h']:g} in fmpy and {small['ecos_run'] / small['h'] / (big['ecos_run'] / big['h']):.1f}x in ecos: "
          "below h ~ 0.01 the fixed cost of a communication step (the master's calls, the FMU's "
          "step set-up and output) dominates CVODE's work, which depends little on h.",
          END]
    return "\n".join(L)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="smoke test: short runs, print only")
    ap.add_argument("--out", help="markdown file to update (default BENCHMARKS.md, none with --quick)")
    args = ap.parse_args(argv)
    if not FMU.is_file():
        print(f"{FMU} missing: bash scripts/setup.sh", file=sys.stderr)
        return 2
    text = section(measure(args.quick))
    print(text)
    out = args.out or (None if args.quick else ROOT / "BENCHMARKS.md")
    if out:
        write_section(Path(out), text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
