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

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from mapcheck.exact import ExactOscillator  # noqa: E402
from tests.support.fmu import LoggedSlave, on_orbit  # noqa: E402

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--periods", type=int, default=1_000_000)
    ap.add_argument("--sigma", type=float, default=0.5)
    args = ap.parse_args()
    theta, sigma = 0.5, args.sigma
    fmu = LoggedSlave(name="long")
    fmu.start(t0=theta, sigma=sigma, **on_orbit(sigma, theta))
    osc = ExactOscillator(FIG9["nu"], FIG9["Omega"], sigma)

    def next_period_error() -> float:
        x, t = fmu.state(), fmu.t
        # The ODE is 1-periodic in t: the oracle runs on the local time t - floor(t), so that its
        # own time arithmetic does not lose digits at t = 10^6 (the FMU is the one under test).
        t_loc = t - np.floor(t)
        exact, _ = osc.strobe(x[0], x[1], [t_loc + 1.0], t0=t_loc)
        fmu.step_to(t + 1.0)
        return float(np.max(np.abs(fmu.state() - exact[0])))

    fmu.step_to(theta + 10)
    early = max(next_period_error() for _ in range(5))
    start = time.perf_counter()
    t_end = theta + args.periods
    while fmu.t < t_end:
        fmu.step_to(min(t_end, fmu.t + 1.0))
    cost = (time.perf_counter() - start) / (args.periods - 15)
    late = max(next_period_error() for _ in range(5))
    print(f"sigma = {sigma}: one-period map error after 10 periods {early:.2e}, "
          f"after {args.periods} periods {late:.2e}; {cost * 1e6:.1f} us/period "
          f"(fmpy doStep of 1 period + getReal); impacts {fmu.impacts()}")


if __name__ == "__main__":
    main()
