"""Long-run accuracy of the C FMU: the one-period map error after 10 and after 10^6 periods.

The FMU keeps its time as an integer origin plus a local time so that the forcing phase stays
exact; this script shows that the error after a million periods is that of the first ones.
Usage: python bench/fmu_long_run.py [--periods 1000000]
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
from harness.fmu.fmi import FmuModel  # noqa: E402
from harness.fmu.simulator import FmuSimulator  # noqa: E402
from mapcheck.exact import ExactOscillator  # noqa: E402

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--periods", type=int, default=1_000_000)
    ap.add_argument("--sigma", type=float, default=0.5)
    args = ap.parse_args()
    theta, sigma = 0.5, args.sigma
    model = FmuModel(ROOT / "build" / "fmu" / "ImpactOscillator.fmu")
    params = {**model.defaults(), **FIG9, "sigma": sigma, "wall": 1}
    osc = ExactOscillator(FIG9["nu"], FIG9["Omega"], sigma)
    # a start on the wall-free orbit p(t) (eq (4)) hits the wall in the first period; from rest,
    # at Figure 9's slow eigenvalue 0.98 per period, it would take hundreds
    u0, v0 = osc.wall_free_orbit(theta)
    with FmuSimulator(model.source(), instance_name="long") as sim:
        sim.start(params, theta, (float(u0), float(v0)))
        t = theta

        def next_period_error() -> float:
            nonlocal t
            u, v, _ = sim.read()
            # The ODE is 1-periodic in t: the oracle runs on the local time t - floor(t), so that
            # its own time arithmetic does not lose digits at t = 10^6 (the FMU is under test).
            t_loc = t - np.floor(t)
            exact, _ = osc.strobe(u, v, [t_loc + 1.0], t0=t_loc)
            t += 1.0
            sim.advance(t)
            return float(np.max(np.abs(np.array(sim.read()[:2]) - exact[0])))

        t = theta + 10
        sim.advance(t)
        early = max(next_period_error() for _ in range(5))
        start = time.perf_counter()
        t_end = theta + args.periods
        while t < t_end:
            t = min(t_end, t + 1.0)
            sim.advance(t)
        cost = (time.perf_counter() - start) / (args.periods - 15)
        late = max(next_period_error() for _ in range(5))
        impacts = sim.read()[2]
    print(f"sigma = {sigma}: one-period map error after 10 periods {early:.2e}, "
          f"after {args.periods} periods {late:.2e}; {cost * 1e6:.1f} us/period "
          f"(fmpy doStep of 1 period + getReal); impacts {impacts}")


if __name__ == "__main__":
    main()
