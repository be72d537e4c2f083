"""CPU time of the exact closed-form flow (mapcheck.exact, the tests' oracle) on its typical workloads,
and its outputs for a before/after comparison.

Usage (from the repository root)::

    .venv/bin/python bench/exact_speed.py --out /tmp/new.npz
    git worktree add /tmp/old <older commit>
    .venv/bin/python bench/exact_speed.py --root /tmp/old --out /tmp/old.npz --compare /tmp/new.npz

``--root`` imports mapcheck (and harness) from another checkout; ``--compare`` says which outputs
differ from a saved run and by how much (bit for bit, relative).  Workloads (default: all but the
slow ``windows_m2``): ``flow_compliant``/``flow_rigid`` (ExactFlow: 30 periods, Newton, multipliers),
``strobe_compliant``/``strobe_rigid`` (300 periods), ``windows`` (fig9_maps.ode_windows, M_max 1,
xtol 1e-5), ``windows_m2`` (M_max 2, xtol 1e-6), ``random`` (60 random oscillators: strobes, dense
output, events, pre-impact maps; rigid and compliant, light and heavy damping, r near 1, ports,
grazing starts).  CPU time: best of 3 (1 for the window searches); say the load (uptime) with it.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def _flow(wall: str, sigma: float, r: float) -> dict:
    from mapcheck.exact_flow import ExactFlow
    fl = ExactFlow(0.8, 2.5, r, 10.0, wall)
    o = fl.settle(sigma, 1, n=30)
    return dict(z=o.z, mult=o.multipliers, m=fl.multipliers(sigma, o.z[0], 1))


def _strobe(wall: str) -> dict:
    from mapcheck.exact import ExactOscillator
    ex = (ExactOscillator(0.3, 1.7, 0.2, r=0.8, Gamma=100.0, wall="compliant") if wall == "compliant"
          else ExactOscillator(0.8, 2.5, 0.3, r=0.7, wall="rigid"))
    s, c = ex.strobe(-0.5, 1.0, np.arange(1, 301) * 1.0)
    return dict(s=s, c=c)


def _windows(M_max: int, xtol: float) -> dict:
    from harness.reproduce.fig9_maps import ode_windows
    return {f"w{k}": np.array(v, dtype=float) for k, v in ode_windows(Gamma=10.0, M_max=M_max, xtol=xtol).items()}


def _random() -> dict:
    from mapcheck.exact import ExactOscillator
    rng, res, kinds = np.random.default_rng(123), {}, ["enter", "exit", "impact", "stick", "release"]
    for k in range(60):
        nu = float(10.0 ** rng.uniform(-1.3, -0.3 if k % 2 == 0 else 0.8))
        Omega = float(rng.uniform(0.3, 4.0))
        r = float(rng.uniform(0.95, 0.999) if k % 3 == 0 else rng.uniform(0.0, 0.95))
        wall = "rigid" if k % 4 < 2 else "compliant"
        sigma = float(rng.uniform(-0.5, 1.5)) if k % 5 else 1e-7
        ports = dict(F_ext=float(rng.uniform(-0.5, 0.5)), u_wall=float(rng.uniform(-0.2, 0.2))) if k % 7 == 0 else {}
        osc = ExactOscillator(nu, Omega, sigma, r=r, Gamma=float(10.0 ** rng.uniform(1, 4)), wall=wall, **ports)
        u0, v0, t0 = float(rng.uniform(-2.5, -0.05)), float(rng.uniform(-6, 6)), float(rng.uniform(0, 3))
        if k % 5 == 0:  # on the wall-free orbit, 1e-7 from grazing
            u0, v0, t0 = -2.0 - sigma, 0.0, 0.5
        res[f"{k}/strobe"], res[f"{k}/count"] = osc.strobe(u0, v0, t0 + np.arange(1, 41) * 1.0, t0)
        res[f"{k}/dense"], _ = osc.dense(u0, v0, np.linspace(t0, t0 + 5, 2001), t0)
        ev = osc.crossings(u0, v0, t0, t0 + 40)
        res[f"{k}/event_t"] = np.array([t for t, _ in ev])
        res[f"{k}/event_kind"] = np.array([kinds.index(kind) for _, kind in ev], dtype=int)
        if not ports:
            pu, pv, pc = osc.pre_impact_map(np.linspace(-0.3, 0.0, 5), np.linspace(-1, 1, 5), n=k % 3)
            res[f"{k}/pre_impact"] = np.concatenate([pu, pv, pc])
    return res


WORKLOADS = {
    "flow_compliant": lambda: _flow("compliant", 0.15, 0.9), "flow_rigid": lambda: _flow("rigid", 0.1, 0.95),
    "strobe_compliant": lambda: _strobe("compliant"), "strobe_rigid": lambda: _strobe("rigid"),
    "windows": lambda: _windows(1, 1e-5), "windows_m2": lambda: _windows(2, 1e-6), "random": _random,
}


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("workloads", nargs="*", help=f"any of {', '.join(WORKLOADS)}")
    ap.add_argument("--root", default=str(ROOT), help="checkout to import mapcheck and harness from")
    ap.add_argument("--out", help="save the outputs (.npz)")
    ap.add_argument("--compare", help="a saved run (.npz) to compare the outputs with")
    a = ap.parse_args(argv)
    unknown = [w for w in a.workloads if w not in WORKLOADS]
    if unknown:
        ap.error(f"workloads: unknown {', '.join(unknown)} (choose from {', '.join(WORKLOADS)})")
    sys.path.insert(0, str(Path(a.root).resolve()))
    import mapcheck
    print(f"mapcheck from {Path(mapcheck.__file__).parent}")
    res = {}
    for name in a.workloads or [w for w in WORKLOADS if w != "windows_m2"]:
        cpu = []
        for _ in range(1 if name.startswith("windows") else 3):
            t0 = time.process_time()
            out = WORKLOADS[name]()
            cpu.append(time.process_time() - t0)
        print(f"{name:18s} CPU {min(cpu):8.3f} s (runs: {' '.join(f'{c:.3f}' for c in cpu)})", flush=True)
        res.update({f"{name}/{k}": np.asarray(v) for k, v in out.items()})
    if a.out:
        np.savez(a.out, **res)
    if a.compare:
        other = np.load(a.compare)
        common = [k for k in res if k in other.files]
        diff = {k: float(np.max(np.abs(res[k] - other[k]) / (1.0 + np.abs(other[k]))) if res[k].shape == other[k].shape
                         else np.inf) for k in common if not np.array_equal(res[k], other[k])}
        print(f"compared {len(common)} outputs: {len(common) - len(diff)} identical bit for bit")
        for k, d in diff.items():
            print(f"  {k}: max relative difference {d:.3g}")


if __name__ == "__main__":
    main()
