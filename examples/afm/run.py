"""Run the AFM example in one command: ``.venv/bin/python examples/afm/run.py [--quick]``.

Options set the loop (``--A-set``, ``--Kp``, ``--Ki``), the sample (``--Gamma``, ``--sweep-Gamma``),
the communication step ``--h`` and the master(s) of the settling run (``--master ecos`` ...);
``--no-sweep`` runs the settling part only.  ``--help`` lists them with their defaults.

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
#: ``--master`` choices and the names the results use.
MASTERS = {"ecos": "ecos", "fmpy-ssp": "fmpy SSP", "fmpy-container": "fmpy Container FMU"}


def settle(t1: float, work: Path, osc: Oscillator | None = None, ctrl: Controller | None = None,
           h: float = H, masters: tuple[str, ...] = tuple(MASTERS)) -> dict:
    """The loop in the chosen masters and the reference; errors at the communication points."""
    osc, ctrl = osc or Oscillator(), ctrl or Controller()
    u0, v0 = osc.sigma, 0.0
    t = time.perf_counter()
    ref = simulate(osc, ctrl, 0.0, t1, h, u0, v0)
    out = {"reference_seconds": time.perf_counter() - t, "masters": {}}
    values = M.start_values(osc, ctrl, u0, v0)
    runs = {
        "ecos": lambda: M.run_ecos(OSC_FMU, CTRL_FMU, values, t1, h),
        "fmpy SSP": lambda: M.run_fmpy_ssp(M.write_ssp(work / "afm.ssp", OSC_FMU, CTRL_FMU),
                                           values, t1, h),
        "fmpy Container FMU": lambda: M.run_container(
            M.build_container(work / "afm_container.fmu", OSC_FMU, CTRL_FMU, values, h), t1, h),
    }
    runs = {name: run for name, run in runs.items() if name in {MASTERS[m] for m in masters}}
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
    out["parameters"] = {"oscillator": vars(osc), "controller": vars(ctrl), "h": h, "t1": t1,
                         "u0": u0, "v0": v0}
    out["_ref"], out["_traces"] = ref, traces
    return out


def open_loop_curve(osc: Oscillator, walls: np.ndarray, periods: int, h: float = H) -> np.ndarray:
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
    n, t, amps, last = int(round(1 / h)), 0.0, [], []
    for w in walls:
        s.setReal([vr["u_wall"]], [float(w)])
        for _ in range(periods):
            us = np.empty(n)
            for k in range(n):
                us[k] = s.getReal([vr["u"]])[0]
                s.doStep(t, h)
                t += h
            last.append(float(np.ptp(us)))
        amps.append(last[-5:])  # the last 5 periods: one value if period-1, a spread if not
        last = []
    s.terminate()
    s.freeInstance()
    return np.array(amps)


def sweep(set_points: np.ndarray, periods: int, osc: Oscillator | None = None, ctrl: Controller | None = None,
          h: float = H) -> dict:
    """ecos: the loop on a stiff sample, A_set stepped down; per set-point the amplitudes of
    the last 5 windows and the surface position during each."""
    from ecospy import EcosLib, EcosSimulation, EcosSimulationStructure

    osc = osc or Oscillator(Gamma=1000.0)
    ctrl = replace(ctrl or Controller(), A_set=float(set_points[0]), u_wall_start=0.6)
    values = M.start_values(osc, ctrl, osc.sigma, 0.0)
    EcosLib.set_log_level("warn")
    n = int(round(periods / h))
    rows = []
    with EcosSimulationStructure() as ss:
        ss.add_model(M.OSC, str(OSC_FMU))
        ss.add_model(M.CTRL, str(CTRL_FMU))
        for a, x, b, y in M.connections(True):
            ss.make_real_connection(f"{a}::{x}", f"{b}::{y}")
        ss.add_parameter_set("init", {k.replace(".", "::", 1): v for k, v in values.items()})
        with EcosSimulation(structure=ss, step_size=h) as sim:
            sim.init(parameter_set="init")
            for A_set in set_points:
                sim.set_real(f"{M.CTRL}::A_set", float(A_set))
                amps, walls = [], []
                for k in range(n):
                    sim.step()
                    if (k + 1) % int(round(1 / h)) == 0:
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
    p = res["parameters"]
    c = p["controller"]
    fig.suptitle(f"AFM z-feedback settling (Gamma = {p['oscillator']['Gamma']:g}; A_set = {c['A_set']:g}, "
                 f"Kp = {c['Kp']:g}, Ki = {c['Ki']:g}, h = {p['h']:g})")
    fig.tight_layout()
    fig.savefig(out / "settle.png", dpi=120)
    plt.close(fig)
    if sw is None:
        return

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
    fig.suptitle(f"Set-point swept through grazing (stiff sample, Gamma = {sw['oscillator']['Gamma']:g})")
    fig.tight_layout()
    fig.savefig(out / "sweep.png", dpi=120)
    plt.close(fig)


def _positive(text: str) -> float:
    value = float(text)
    if not (np.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a finite number > 0, got {text}")
    return value


def _gain(text: str) -> float:
    value = float(text)
    if not (np.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"must be a finite number >= 0, got {text}")
    return value


def _step(text: str) -> float:
    """h: positive and dividing the forcing period 1 (the controller's windows are whole periods)."""
    value = _positive(text)
    n = round(1.0 / value)
    if n < 1 or abs(n * value - 1.0) > 1e-9:
        raise argparse.ArgumentTypeError(f"must divide the forcing period 1 (1/h an integer), got {text}")
    return value


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """The example's options (defaults: the documented run)."""
    ctrl = Controller()
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    ap.add_argument("--out", type=Path, default=ROOT / "results" / "afm", help="output folder")
    ap.add_argument("--quick", action="store_true", help="short horizons (the tests' run)")
    ap.add_argument("--A-set", dest="A_set", type=_positive, default=ctrl.A_set,
                    help="amplitude set-point of the settling run")
    ap.add_argument("--Kp", type=_gain, default=ctrl.Kp, help="proportional gain of the z-feedback")
    ap.add_argument("--Ki", type=_gain, default=ctrl.Ki, help="integral gain of the z-feedback")
    ap.add_argument("--Gamma", type=_positive, default=Oscillator().Gamma,
                    help="sample (wall) stiffness of the settling run")
    ap.add_argument("--sweep-Gamma", dest="sweep_Gamma", type=_positive, default=1000.0,
                    help="sample stiffness of the set-point sweep")
    ap.add_argument("--h", type=_step, default=H, help="communication step (1/h an integer)")
    ap.add_argument("--master", action="append", choices=tuple(MASTERS),
                    help="master(s) of the settling run, repeatable (default: all three)")
    ap.add_argument("--no-sweep", action="store_true", help="the settling run only")
    return ap.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    for f in (OSC_FMU, CTRL_FMU):
        if not f.is_file():
            print(f"{f} missing: run bash scripts/setup.sh", file=sys.stderr)
            return 2
    args.out.mkdir(parents=True, exist_ok=True)
    ctrl = Controller(A_set=args.A_set, Kp=args.Kp, Ki=args.Ki)
    masters = tuple(dict.fromkeys(args.master or MASTERS))
    with tempfile.TemporaryDirectory() as work:
        res = settle(12.0 if args.quick else 60.0, Path(work), Oscillator(Gamma=args.Gamma), ctrl, args.h, masters)
    sw, curve = None, None
    if not args.no_sweep:
        set_points = np.round(np.arange(3.04, 2.86 if args.quick else 2.80, -0.02), 4)
        stiff = Oscillator(Gamma=args.sweep_Gamma)
        sw = sweep(set_points, 8 if args.quick else 25, stiff, replace(ctrl), args.h)
        walls = np.linspace(0.56, 0.30, 14 if args.quick else 53)
        curve = (walls, open_loop_curve(stiff, walls, 6 if args.quick else 20, args.h))
    plot(res, sw, curve, args.out)
    data = {k: v for k, v in res.items() if not k.startswith("_")}
    if sw is not None:
        data["sweep"] = sw
        data["open_loop"] = {"u_wall": curve[0].tolist(), "amplitude": curve[1].tolist()}
    (args.out / "afm.json").write_text(json.dumps(data, indent=1))
    lines = ["# AFM example: PI z-feedback on the impact oscillator", "",
             f"Loop settling, h = {args.h:g}, Gamma = {args.Gamma:g}, A_set = {args.A_set:g}, Kp = {args.Kp:g}, "
             f"Ki = {args.Ki:g}, t = 0..{res['parameters']['t1']:g}: largest difference "
             "from the monolithic reference at any communication point", "",
             "| master | u | v | u_wall | amplitude | seconds |", "|---|---|---|---|---|---|"]
    for name, e in res["masters"].items():
        lines.append(f"| {name} | {e['u']:.1e} | {e['v']:.1e} | {e['u_wall']:.1e} | "
                     f"{e['amplitude']:.1e} | {e['seconds']:.2f} |")
    last = res["updates"][-1]
    lines += ["", f"Last window (t = {last[0]:.2f}): amplitude {last[1]:.6f}, surface at "
              f"{last[2]:.6f} (set-point {res['parameters']['controller']['A_set']})."]
    if sw is not None:
        lines += ["", f"Set-point sweep (ecos, Gamma = {args.sweep_Gamma:g}): A_set, the last 5 windows' "
                  "amplitudes and the surface position during each",
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
