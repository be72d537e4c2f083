"""Figure 9's window edges by Newton shooting on the FMU: the FMU's exact derivatives against
central differences (issue 11).  Prints the edges, the edge kinds and the one-period FMU runs
each needed, and the largest edge difference in units of the bisection tolerance.

    .venv/bin/python bench/shooting_derivatives.py [--quick]

Needs an FMU with sensitivity outputs for the exact column (else only the differences run).
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from harness.fmi import FmuModel
from harness.reproduce.fig9 import problem, settings
from harness.reproduce.windows import predicted_windows
from harness.shooting import StroboscopicMap, map_guided_windows
from harness.simulator import FmuSimulator


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="Figure 9 --quick tolerances (xtol 1e-4, else 1e-5)")
    ap.add_argument("--fmu", default="build/fmu/ImpactOscillator.fmu")
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


if __name__ == "__main__":
    main()
