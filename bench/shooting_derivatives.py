"""Figure 9's window edges by Newton shooting on the FMU: the FMU's exact derivatives against
central differences, and the Lyapunov exponents of a periodic and a chaotic orbit
both ways.  Prints the edges, the edge kinds, the one-period FMU runs each needed, the largest
edge difference; ``--write`` puts the numbers into BENCHMARKS.md between
``<!-- senspy:begin -->`` and ``<!-- senspy:end -->`` (bench/run.py keeps such sections).

    .venv/bin/python bench/shooting_derivatives.py [--quick] [--write]

Needs an FMU with sensitivity outputs for the exact column (else only the differences run).
"""
from __future__ import annotations

import argparse
import math
import platform
import time
from pathlib import Path

import numpy as np

from harness.fmu.fmi import FmuModel
from harness.dynamics.maps.lyapunov import lyapunov_exponents
from harness.reproduce.fig9 import problem, settings
from harness.analysis.windows.compare_windows import predicted_windows
from harness.dynamics.maps.shooting import StroboscopicMap, map_guided_windows
from sections import write_section as write_marked_section  # bench/sections.py, next to this script
from harness.fmu.simulator import FmuSimulator


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="Figure 9 --quick tolerances (xtol 1e-4, else 1e-5)")
    ap.add_argument("--fmu", default="build/fmu/ImpactOscillator.fmu")
    ap.add_argument("--write", action="store_true", help="write the senspy section of BENCHMARKS.md")
    args = ap.parse_args()
    model = FmuModel(args.fmu)
    prob, st = problem(), settings(args.quick)
    c = prob.coefficients()
    guide = predicted_windows(c, prob.M_max, st.table_grid)["map_A_tilde"]
    params = {k: v for k, v in model.defaults().items() if k not in ("u0", "v0")}
    params.update(prob.fmu_params())
    methods = ["exact", "fd"] if model.has_sensitivities else ["fd"]
    out = {}
    for method in methods:
        sim = FmuSimulator(model.source(), instance_name=f"bench-{method}")
        smap = StroboscopicMap(sim, params, prob.theta, derivatives=method)
        t0 = time.perf_counter()
        res = map_guided_windows(smap, c, guide, st.sigma_range, st.xtol, workers=1)
        res["wall_s"] = time.perf_counter() - t0
        sim.close()
        out[method] = res
        print(f"{method}: {res['fmu_periods']} one-period FMU runs, {res['wall_s']:.1f} s")
        for M, w in res["windows"].items():
            print(f"  M = {M}: {w}  kinds {res['kinds'].get(M)}  brackets {res['brackets'].get(M)}")
    if len(out) == 2:
        worst = 0.0
        for M, we in out["exact"]["windows"].items():
            wf = out["fd"]["windows"][M]
            if we is None or wf is None:
                continue
            for a, b in zip(we, wf):
                if a is not None and b is not None:
                    worst = max(worst, abs(a - b))
        xtol = st.xtol if np.isscalar(st.xtol) else max(st.xtol.values())
        print(f"largest edge difference exact vs fd: {worst:.2e} (bisection tolerance {xtol:g}); "
              f"FMU runs fd/exact = {out['fd']['fmu_periods'] / out['exact']['fmu_periods']:.1f}")
    else:
        worst, xtol = math.nan, st.xtol
    lyap = {}
    for sigma, n in ((0.5, 2000), (0.03, 4000)):
        p = {**params, "sigma": sigma}
        for method in methods:
            sim = FmuSimulator(model.source(), instance_name=f"lyap-{method}")
            t0 = time.perf_counter()
            r = lyapunov_exponents(sim, p, (-1.0, 0.0), prob.theta, n_transient=300, n_periods=n, method=method)
            wall = time.perf_counter() - t0
            sim.close()
            dissipation = -p["nu"] + 2.0 * math.log(p["r"]) * r.impacts / r.periods
            lyap[(sigma, method)] = (r, wall, r.exponents.sum() - dissipation)
            print(f"sigma = {sigma} {method}: {r} over {r.periods} periods, {wall:.1f} s; "
                  f"sum - (-nu + 2 log r impacts/period) = {lyap[(sigma, method)][2]:+.1e}")
    if args.write:
        write_section(out, lyap, worst, xtol, args.quick)


def write_section(out: dict, lyap: dict, worst: float, xtol, quick: bool) -> None:
    """The senspy section of BENCHMARKS.md (replaced if present, appended otherwise)."""
    L = ["<!-- senspy:begin -->", "## Exact derivatives in the harness: shooting and Lyapunov exponents", "",
         f"`python bench/shooting_derivatives.py{' --quick' if quick else ''} --write`, one run on "
         f"{platform.node() or 'this machine'} ({time.strftime('%Y-%m-%d')}); Figure 9 (alpha, gamma) = (0.99, 0.01), "
         "r = 0.9, Gamma = 10, CVODE.", "",
         "Window edges by Newton shooting (`harness.dynamics.maps.shooting.map_guided_windows`, bisection tolerance "
         f"{xtol if not isinstance(xtol, dict) else max(xtol.values()):g}): the FMU's derivatives (variational "
         "equations with saltation matrices; one run per period and Newton iteration) against central "
         "differences (restarts from perturbed states).", "",
         "| M | edges, exact derivatives | edges, differences | kinds |", "|---|---|---|---|"]
    meths = list(out)
    for M in out[meths[0]]["windows"]:
        cells = [str(out[m]["windows"][M]) for m in ("exact", "fd") if m in out]
        L.append(f"| {M} | " + " | ".join(cells + ["-"] * (2 - len(cells))) + f" | {out[meths[0]]['kinds'].get(M)} |")
    L += [""]
    runs = {m: out[m]["fmu_periods"] for m in out}
    if len(out) == 2:
        L += [f"One-period FMU runs: exact {runs['exact']:,}, differences {runs['fd']:,} "
              f"(ratio {runs['fd'] / runs['exact']:.1f}); wall time {out['exact']['wall_s']:.1f} s against "
              f"{out['fd']['wall_s']:.1f} s (machine shared with other jobs: the ratio, not the seconds); "
              f"largest edge difference {worst:.1e}"
              + (": one bisection bracket, at a flip, where the differences' error in the multiplier near -1 "
                 "turned a bisection decision" if worst > 0 else "") + ".", ""]
    L += ["Largest Lyapunov exponent of the stroboscopic map (QR method, per forcing period, +- standard error of 10 "
          "block means), and the check lambda_1 + lambda_2 = -nu + 2 log(r) impacts/period:", "",
          "| sigma | method | lambda_1 | lambda_2 | periods | sum - dissipation | wall s |", "|---|---|---|---|---|---|---|"]
    for (sigma, method), (r, wall, dev) in lyap.items():
        L.append(f"| {sigma:g} | {method} | {r.exponents[0]:+.6f} +- {r.uncertainty[0]:.1e} | "
                 f"{r.exponents[1]:+.4f} +- {r.uncertainty[1]:.1e} | {r.periods} | {dev:+.1e} | {wall:.1f} |")
    L += ["<!-- senspy:end -->"]
    path = Path(__file__).resolve().parents[1] / "BENCHMARKS.md"
    write_marked_section(path, "\n".join(L))
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
