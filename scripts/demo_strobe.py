"""Main job until the harness's `reproduce` exists: strobe the built FMU at the paper's Figure 9
parameters over a sigma sweep and draw the stroboscopic bifurcation diagram.

Writes results/demo/strobe.png and prints the detected period at each sigma.
"""
from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi2 import FMU2Slave  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def strobe(slave: FMU2Slave, vr: dict[str, int], sigma: float, transient: int, keep: int) -> np.ndarray:
    """Return u at t = n for `keep` periods after `transient` periods, starting at rest."""
    slave.reset()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.setReal([vr["sigma"]], [sigma])
    slave.exitInitializationMode()
    out = np.empty(keep)
    for n in range(transient + keep):
        slave.doStep(float(n), 1.0)
        if n >= transient:
            out[n - transient] = slave.getReal([vr["u"]])[0]
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--fmu", default=str(ROOT / "build/fmu/ImpactOscillator.fmu"))
    ap.add_argument("--out", default=str(ROOT / "results/demo"))
    ap.add_argument("--points", type=int, default=60)
    args = ap.parse_args()

    md = read_model_description(args.fmu)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(args.fmu),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="demo")
    slave.instantiate()
    sigmas = np.linspace(0.1, 0.9, args.points)
    fig, ax = plt.subplots(figsize=(7, 4))
    for s in sigmas:
        u = strobe(slave, vr, float(s), transient=150, keep=24)
        period = next((m for m in range(1, 9) if np.allclose(u[m:], u[:-m], atol=1e-6)), None)
        print(f"sigma = {s:.4f}  period = {period if period else 'not periodic'}")
        ax.plot(np.full_like(u, s), u, ",k")
    slave.terminate()
    slave.freeInstance()
    ax.set_xlabel("sigma")
    ax.set_ylabel("u(t = n)")
    ax.set_title("ImpactOscillator FMU, Figure 9 parameters (compliant wall, Gamma = 10)")
    Path(args.out).mkdir(parents=True, exist_ok=True)
    fig.savefig(Path(args.out) / "strobe.png", dpi=150)
    print(f"wrote {Path(args.out) / 'strobe.png'}")


if __name__ == "__main__":
    main()
