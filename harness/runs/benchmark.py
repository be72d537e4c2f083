"""Overhead of the harness over a bare fmpy loop, per forcing period.

    python -m harness.runs.benchmark [--fmu PATH] [--periods N] [--repeat R]

The bare loop is what a user would write by hand: one FMU2Slave, ``doStep(t, 1)`` and a
``getReal``/``getInteger`` of (u, v, impacts) per period.  The harness loop is
:func:`harness.dynamics.maps.sampling.strobe` on :class:`harness.fmu.simulator.FmuSimulator`, which does the
same FMI calls plus its bookkeeping.  Both run the same parameters from the same state;
the best of ``repeat`` runs is reported (the machine may be shared).
"""
from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np

from ..config import default_fmu_path
from ..fmu.bare_loop import bare_loop
from ..fmu.fmi import FmuModel
from ..dynamics.maps.sampling import strobe
from ..fmu.simulator import FmuSimulator


def harness_loop(model: FmuModel, params: dict[str, Any], state0: tuple[float, float],
                 periods: int) -> tuple[float, np.ndarray]:
    """Seconds for ``periods`` sampled periods through :func:`harness.dynamics.maps.sampling.strobe`, and
    the samples (u, v, cumulative impacts)."""
    sim = FmuSimulator(model.source(), instance_name="bench")
    t0 = time.perf_counter()
    r = strobe(sim, params, state0, theta=0.0, n_transient=0, n_samples=periods)
    elapsed = time.perf_counter() - t0
    sim.close()
    return elapsed, np.column_stack([r.u, r.v, np.cumsum(r.impacts)])


def measure(fmu: str | None = None, periods: int = 2000, repeat: int = 5, sigma: float = 0.5) -> dict[str, Any]:
    """Best-of-``repeat`` seconds per period, bare and through the harness, and the overhead;
    ``same_orbit`` says whether both loops read identical values (they must)."""
    model = FmuModel(fmu or default_fmu_path())
    params = model.defaults()
    params.pop("u0", None)
    params.pop("v0", None)
    params["sigma"] = sigma
    state0 = (-1.0, 0.0)
    bare_runs, our_runs = [], []
    same = True
    for _ in range(repeat):  # interleaved, so that load changes on a shared machine hit both
        t_bare, x_bare = bare_loop(model, params, state0, periods)
        t_ours, x_ours = harness_loop(model, params, state0, periods)
        bare_runs.append(t_bare)
        our_runs.append(t_ours)
        same = same and bool(np.array_equal(x_bare, x_ours))
    bare = min(bare_runs) / periods
    ours = min(our_runs) / periods
    return {"bare_s_per_period": bare, "harness_s_per_period": ours, "overhead_s_per_period": ours - bare,
            "overhead_fraction": (ours - bare) / bare, "same_orbit": same}


def main(argv: list[str] | None = None) -> int:
    """Command line of ``python -m harness.runs.benchmark``."""
    p = argparse.ArgumentParser(prog="python -m harness.runs.benchmark", description=__doc__.split("\n\n")[0])
    p.add_argument("--fmu", help="FMU (default: build/fmu/ImpactOscillator.fmu)")
    p.add_argument("--periods", type=int, default=2000)
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--sigma", type=float, default=0.5)
    args = p.parse_args(argv)
    r = measure(args.fmu, args.periods, args.repeat, args.sigma)
    print(f"bare FMU2Slave loop : {r['bare_s_per_period'] * 1e6:8.1f} us/period")
    print(f"harness strobe      : {r['harness_s_per_period'] * 1e6:8.1f} us/period")
    print(f"overhead            : {r['overhead_s_per_period'] * 1e6:8.1f} us/period ({100 * r['overhead_fraction']:.1f} %)")
    print(f"same orbit          : {r['same_orbit']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
