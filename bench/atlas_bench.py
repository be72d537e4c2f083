"""The atlas: the batch kernel over a whole plane, and the same pixels through the FMU.

    .venv/bin/python bench/atlas_bench.py --full      # the 400 x 400 x 8 plane (minutes), then the subset
    .venv/bin/python bench/atlas_bench.py             # the subset only: kernel vs FMU on random pixels

Figure 9's oscillator (harness/experiments/fig9.toml: nu = 4.605, Omega = 0.306, r = 0.9, compliant
wall, theta = 0) over Gamma in [10, 1e4] (geometric) x sigma in [0.1, 1.2], 8 starts per pixel
(the atlas's defaults: at most 500 periods, M <= 12, tolerance 1e-8, the exponent over the last
200 periods of an aperiodic start).

1. ``--full``: ``impact-harness atlas --grid 400x400`` in a child process; its wall time and the CPU
   time of the child (user + system: what two idle cores would turn into wall time, halved);
2. the subset: ``--pixels`` random pixels of that plane (seeded), each start run by the kernel
   (one thread) and through the FMU (closed form and CVODE, one process, no early stop: every start
   runs its 500 periods); CPU seconds per start of each and their ratio, and the FMU's time for the
   whole plane extrapolated by that ratio; the labels compared.
"""
from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112, r=0.9, Gamma=10.0, wall=1)
P2 = np.geomspace(10.0, 1e4, 400)
SIGMA = np.linspace(0.1, 1.2, 400)


def full(out: str) -> None:
    cmd = [sys.executable, "-m", "harness", "atlas", "--config", "harness/experiments/fig9.toml", "--solver",
           "closed-form", "--param2", "Gamma", "--range", "10:1e4", "--log", "--sigma-range", "0.1:1.2", "--grid",
           "400x400", "--out", out, "--no-progress"]
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    subprocess.run(cmd, cwd=ROOT, check=True)
    wall = time.perf_counter() - t0
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = ru.ru_utime + ru.ru_stime
    print(f"full 400 x 400 x 8: wall {wall:.1f} s, CPU {cpu:.1f} s (user + system of the child; "
          f"{cpu / 2:.1f} s on 2 idle cores); load average {load0:.1f} at the start, {os.getloadavg()[0]:.1f} at the end")


def subset(n_pix: int, seed: int) -> None:
    from harness import FmuModel
    from harness.runs.atlas.plane import AtlasPlane
    from harness.runs.atlas.scan import run_atlas_plane

    rng = np.random.default_rng(seed)
    ij = rng.choice(400 * 400, n_pix, replace=False)
    model = FmuModel(ROOT / "build" / "fmu" / "ImpactOscillator.fmu")
    rows = []
    for k in ij:
        i, j = divmod(int(k), 400)
        rows.append((float(P2[i]), float(SIGMA[j])))
    per_start = {}
    labels = {}
    for name, params, route in (("kernel", {**FIG9, "solver": 1}, "kernel"), ("FMU, closed form", {**FIG9, "solver": 1}, "fmu"),
                                ("FMU, CVODE", {**FIG9, "solver": 0}, "fmu")):
        cpu, got = 0.0, []
        for g, s in rows:
            plane = AtlasPlane(params, "Gamma", np.array([g]), np.array([s]), starts=8, theta=0.0)
            c0 = time.process_time()
            d = run_atlas_plane(plane, route, model, backend="serial" if route == "fmu" else None, workers=1,
                                progress=False).data
            cpu += time.process_time() - c0
            got.append((d["kind"][0, 0], d["period"][0, 0], d["impacts"][0, 0]))
        per_start[name] = cpu / (8 * n_pix)
        labels[name] = got
    total = 400 * 400 * 8
    for name, c in per_start.items():
        print(f"{name}: {c * 1e3:.2f} ms CPU per start ({n_pix} pixels x 8 starts); x{c / per_start['kernel']:.0f} the "
              f"kernel; the whole plane ~{c * total / 3600:.1f} CPU hours ({c * total / 7200:.2f} h on 2 cores)")
    kinds = ("periodic", "sticking", "chaotic", "aperiodic", "escaped", "invalid", "failed")

    def text(lab) -> str:
        return ", ".join(f"{kinds[k]}" + (f" P{m}/{i}" if k in (0, 1) else "") for k, m, i in zip(*lab))

    for name in per_start:
        same = sum(np.array_equal(np.stack(a), np.stack(b)) for a, b in zip(labels[name], labels["kernel"]))
        print(f"{name}: {same} of {n_pix} pixels with every start's (kind, period, impacts) the kernel's")
        for (g, s), a, b in zip(rows, labels[name], labels["kernel"]):
            if not np.array_equal(np.stack(a), np.stack(b)):
                print(f"  Gamma {g:.6g}, sigma {s:.4f}: {text(a)}  |  kernel: {text(b)}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--full", action="store_true")
    ap.add_argument("--out", default="results/atlas-bench")
    ap.add_argument("--pixels", type=int, default=6)
    ap.add_argument("--seed", type=int, default=3)
    a = ap.parse_args()
    if a.full:
        full(a.out)
    subset(a.pixels, a.seed)


if __name__ == "__main__":
    main()
