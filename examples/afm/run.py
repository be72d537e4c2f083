"""Run the AFM example in one command: ``.venv/bin/python examples/afm/run.py [--quick]``.

1. Loop settling: the cantilever (ImpactOscillator FMU) tapping a soft sample (compliant wall,
   Gamma = 10) under the PI z-feedback (AmplitudeController FMU), from the wall-free orbit with
   the surface at 0, in three masters (ecos, fmpy's SSP loop, fmpy's Container FMU) and in the
   monolithic reference (``monolithic.py``); the error of each master at every communication
   point against the reference.
2. Set-point sweep through the grazing bifurcation, on a stiff sample (Gamma = 1000) in ecos:
   A_set stepped down from above the free amplitude; the amplitude the loop reaches at each
   set-point, over the open-loop amplitude-versus-surface curve (the FMU alone, quasi-static).

Writes ``results/afm/`` (or ``--out``): ``settle.png``, ``sweep.png``, ``afm.json`` (all
numbers) and ``report.md``.  Needs the FMUs of ``bash scripts/setup.sh``.
"""
from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:  # run as a script: make "examples" importable
    sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from examples.afm import masters as M  # noqa: E402
from examples.afm.monolithic import Controller, Oscillator, simulate  # noqa: E402

OSC_FMU = ROOT / "build" / "fmu" / "ImpactOscillator.fmu"
CTRL_FMU = ROOT / "build" / "afm" / "AmplitudeController.fmu"
H = 0.01


def settle(t1: float, work: Path) -> dict:
    """The loop in every master and the reference; errors at the communication points."""
    osc, ctrl = Oscillator(), Controller()
    u0, v0 = osc.sigma, 0.0
    t = time.perf_counter()
    ref = simulate(osc, ctrl, 0.0, t1, H, u0, v0)
    out = {"reference_seconds": time.perf_counter() - t, "masters": {}}
    values = M.start_values(osc, ctrl, u0, v0)
    runs = {
        "ecos": lambda: M.run_ecos(OSC_FMU, CTRL_FMU, values, t1, H),
        "fmpy SSP": lambda: M.run_fmpy_ssp(M.write_ssp(work / "afm.ssp", OSC_FMU, CTRL_FMU),
                                           values, t1, H),
        "fmpy Container FMU": lambda: M.run_container(
            M.build_container(work / "afm_container.fmu", OSC_FMU, CTRL_FMU, values, H), t1, H),
    }
    traces = {}
    for name, run in runs.items():
        t = time.perf_counter()
        tr = run()
        traces[name] = tr
        out["masters"][name] = {
            "seconds": time.perf_counter() - t,
            **{k: float(np.max(np.abs(getattr(tr, k) - getattr(ref, k)[1:])))
               for k in ("u", "v", "u_wall", "amplitude")}}
    out["updates"] = [list(map(float, x)) for x in ref.updates]
    out["parameters"] = {"oscillator": vars(osc), "controller": vars(ctrl), "h": H, "t1": t1,
                         "u0": u0, "v0": v0}
    out["_ref"], out["_traces"] = ref, traces
    return out


def open_loop_curve(osc: Oscillator, walls: np.ndarray, periods: int) -> np.ndarray:
    """Amplitude (max - min of u at the samples, per period) against a fixed surface position,
    the FMU alone through fmpy, stepping the wall quasi-statically (each from the previous
    orbit): the last 5 periods' amplitudes per position, a bifurcation diagram."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(OSC_FMU))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(OSC_FMU)),
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="curve")
    s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    for k, x in {**vars(osc), "u0": osc.sigma, "v0": 0.0}.items():
        s.setReal([vr[k]], [float(x)])
    s.exitInitializationMode()
    n, t, amps, last = int(round(1 / H)), 0.0, [], []
    for w in walls:
        s.setReal([vr["u_wall"]], [float(w)])
        for _ in range(periods):
            us = np.empty(n)
            for k in range(n):
                us[k] = s.getReal([vr["u"]])[0]
                s.doStep(t, H)
                t += H
            last.append(float(np.ptp(us)))
        amps.append(last[-5:])  # the last 5 periods: one value if period-1, a spread if not
        last = []
    s.terminate()
    s.freeInstance()
    return np.array(amps)


def sweep(set_points: np.ndarray, periods: int) -> dict:
    """ecos: the loop on a stiff sample, A_set stepped down; per set-point the amplitudes of
    the last 5 windows and the surface position during each."""
    from ecospy import EcosLib, EcosSimulation, EcosSimulationStructure

    osc, ctrl = Oscillator(Gamma=1000.0), Controller(A_set=float(set_points[0]), u_wall_start=0.6)
    values = M.start_values(osc, ctrl, osc.sigma, 0.0)
    EcosLib.set_log_level("warn")
    n = int(round(periods / H))
    rows = []
    with EcosSimulationStructure() as ss:
        ss.add_model(M.OSC, str(OSC_FMU))
        ss.add_model(M.CTRL, str(CTRL_FMU))
        for a, x, b, y in M.connections(True):
            ss.make_real_connection(f"{a}::{x}", f"{b}::{y}")
        ss.add_parameter_set("init", {k.replace(".", "::", 1): v for k, v in values.items()})
        with EcosSimulation(structure=ss, step_size=H) as sim:
            sim.init(parameter_set="init")
            for A_set in set_points:
                sim.set_real(f"{M.CTRL}::A_set", float(A_set))
                amps, walls = [], []
                for k in range(n):
                    sim.step()
                    if (k + 1) % int(round(1 / H)) == 0:
                        amps.append(sim.get_real(f"{M.CTRL}::amplitude"))
                        walls.append(sim.get_real(f"{M.CTRL}::u_wall"))
                # each amplitude with the surface position held while it was measured: the
                # output before that window's update
                rows.append({"A_set": float(A_set), "amplitude": amps[-5:],
                             "u_wall": walls[-6:-1]})
            sim.terminate()
    return {"oscillator": vars(osc), "controller": vars(ctrl), "periods": periods, "rows": rows}


def plot(res: dict, sw: dict, curve: tuple, out: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ref = res["_ref"]
    fig, ax = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    ax[0].plot(ref.t, ref.u, lw=0.5, label="tip u (monolithic)")
    ax[0].plot(ref.t, ref.u_wall, lw=1.5, label="surface u_wall")
    for name, tr in res["_traces"].items():
        ax[0].plot(tr.t[::50], tr.u_wall[::50], ".", ms=3, label=f"u_wall, {name}")
    ax[0].set_ylabel("position")
    ax[0].legend(fontsize=7, loc="lower right")
    up = np.array(res["updates"])
    ax[1].plot(up[:, 0], up[:, 1], "o-", ms=3, label="measured amplitude per window")
    ax[1].axhline(res["parameters"]["controller"]["A_set"], color="k", ls="--", lw=0.8,
                  label="set-point")
    ax[1].set_xlabel("t (forcing periods)")
    ax[1].set_ylabel("amplitude")
    ax[1].legend(fontsize=7)
    fig.suptitle("AFM z-feedback settling (soft sample, Gamma = 10)")
    fig.tight_layout()
    fig.savefig(out / "settle.png", dpi=120)
    plt.close(fig)

    walls, amps = curve
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    for i in range(amps.shape[1]):
        ax[0].plot(walls, amps[:, i], ".", color="C0", ms=3,
                   label="open loop (FMU alone), last 5 periods" if i == 0 else None)
    for r in sw["rows"]:
        ax[0].plot(r["u_wall"], r["amplitude"], "x", color="C3", ms=4)
    ax[0].plot([], [], "x", color="C3", label="closed loop (ecos), last 5 windows")
    ax[0].axvline(sw["oscillator"]["sigma"], color="k", ls=":", lw=0.8, label="grazing")
    ax[0].set_xlabel("surface position u_wall")
    ax[0].set_ylabel("amplitude")
    ax[0].legend(fontsize=7)
    A_set = [r["A_set"] for r in sw["rows"]]
    for r in sw["rows"]:
        ax[1].plot([r["A_set"]] * len(r["amplitude"]), r["amplitude"], "x", color="C3", ms=4)
    ax[1].plot(A_set, A_set, "k--", lw=0.8, label="amplitude = set-point")
    ax[1].set_xlabel("set-point A_set (swept down)")
    ax[1].set_ylabel("amplitude reached")
    ax[1].legend(fontsize=7)
    fig.suptitle("Set-point swept through grazing (stiff sample, Gamma = 1000)")
    fig.tight_layout()
    fig.savefig(out / "sweep.png", dpi=120)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "results" / "afm")
    ap.add_argument("--quick", action="store_true", help="short horizons (the tests' run)")
    args = ap.parse_args(argv)
    for f in (OSC_FMU, CTRL_FMU):
        if not f.is_file():
            print(f"{f} missing: run bash scripts/setup.sh", file=sys.stderr)
            return 2
    args.out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as work:
        res = settle(12.0 if args.quick else 60.0, Path(work))
    set_points = np.round(np.arange(3.04, 2.86 if args.quick else 2.80, -0.02), 4)
    sw = sweep(set_points, 8 if args.quick else 25)
    walls = np.linspace(0.56, 0.30, 14 if args.quick else 53)
    curve = (walls, open_loop_curve(Oscillator(Gamma=1000.0), walls, 6 if args.quick else 20))
    plot(res, sw, curve, args.out)
    data = {k: v for k, v in res.items() if not k.startswith("_")}
    data["sweep"] = sw
    data["open_loop"] = {"u_wall": walls.tolist(), "amplitude": curve[1].tolist()}
    (args.out / "afm.json").write_text(json.dumps(data, indent=1))
    lines = ["# AFM example: PI z-feedback on the impact oscillator", "",
             f"Loop settling, h = {H}, t = 0..{res['parameters']['t1']:g}: largest difference "
             "from the monolithic reference at any communication point", "",
             "| master | u | v | u_wall | amplitude | seconds |", "|---|---|---|---|---|---|"]
    for name, e in res["masters"].items():
        lines.append(f"| {name} | {e['u']:.1e} | {e['v']:.1e} | {e['u_wall']:.1e} | "
                     f"{e['amplitude']:.1e} | {e['seconds']:.2f} |")
    last = res["updates"][-1]
    lines += ["", f"Last window (t = {last[0]:.2f}): amplitude {last[1]:.6f}, surface at "
              f"{last[2]:.6f} (set-point {res['parameters']['controller']['A_set']}).", "",
              "Set-point sweep (ecos, Gamma = 1000): A_set, the last 5 windows' amplitudes and the surface position during each",
              "", "| A_set | amplitude (last 5 windows) | u_wall during them |", "|---|---|---|"]
    for r in sw["rows"]:
        lines.append(f"| {r['A_set']:.2f} | {' '.join(f'{a:.3f}' for a in r['amplitude'])} | "
                     f"{' '.join(f'{w:.3f}' for w in r['u_wall'])} |")
    (args.out / "report.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    worst = max(max(e[k] for k in ("u", "v")) for e in res["masters"].values())
    return 0 if worst <= 1e-6 else 1


if __name__ == "__main__":
    sys.exit(main())
