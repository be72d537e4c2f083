"""Strobe one orbit and sweep sigma up and down on the FMU (harness/README.md's example).

Run from the repository root: ``.venv/bin/python examples/sweep.py``.  The sweep's worker
processes re-import this file, hence the ``if __name__ == "__main__":`` guard.
"""
import numpy as np

from harness import FmuModel, FmuSimulator, SamplingSpec, SweepSpec, classify_orbit, run_sweep, strobe

if __name__ == "__main__":
    model = FmuModel("build/fmu/ImpactOscillator.fmu")
    sim = FmuSimulator(model.source())
    params = {**model.defaults(), "sigma": 0.5}
    r = strobe(sim, params, (-1.0, 0.0), theta=0.0, n_transient=300, n_samples=40)
    print(classify_orbit(r.u, r.v, r.impacts).label)          # "P2, 1 impact"

    ds = run_sweep(model, SweepSpec("sigma", np.linspace(0.1, 1.0, 31), ("up", "down")),
                   sampling=SamplingSpec(n_transient=200, n_samples=24), workers=2)
    # backend="serial" | "processes" | a distributed.Client | scheduler="tcp://..."; checkpoint="dir"
    print(ds["period"].sel(direction="up").values)
