"""Basin scans: the batch kernel against the FMU path, over workers and grid sizes.

    .venv/bin/python bench/basins_bench.py          # measures, rewrites BENCHMARKS.md's section
    .venv/bin/python bench/basins_bench.py --quick  # smoke test: small grids, prints only

Figure 7's oscillator at sigma = 0.01 (nu = 0.196, Omega = 7.368, r = 0.9, compliant wall
Gamma = 1000; two coexisting period-3 orbits), starts u0 in [-1.2, 0] x v0 in [-8, 8] at
theta = 0, transient 150, samples 30 (the README's basins example).  Every scan runs in a fresh
child process (wall time of the scan itself, without the interpreter's start and the imports,
xarray's lazy import of dask included; peak resident memory of the child and of its own
children), one after the other:

1. the README's 60 x 60 grid (20 x 20 with --quick) through the FMU path (a fresh 2D sweep of
   the FMU via fmpy on the process pool, 2 workers) and through the batch kernel (2 threads): the
   ratio of their wall times;
2. the kernel on 300 x 300 starts with 1 and 2 threads in one process, and with 2 Dask workers
   (one thread each) on a local scheduler;
3. the kernel on 100^2, 300^2 and 1000^2 starts (2 threads): how the cost grows;
4. the 1000 x 1000 scan's labels against the FMU's on random starts (closed form and CVODE, no
   early stop), and its quantifiers.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

FMU = ROOT / "build" / "fmu" / "ImpactOscillator.fmu"
FIG7 = dict(nu=0.196, Omega=7.368, r=0.9, Gamma=1000.0, wall=1, sigma=0.01, solver=1)
BOX = (-1.2, 0.0, -8.0, 8.0)


def child(spec: dict) -> dict:
    """One scan in this (fresh) process, as ``spec`` says; returns its numbers."""
    import resource

    import numpy as np

    from harness import FmuModel, SamplingSpec
    from harness.runs.basins.kernel_scan import run_basins_kernel
    from harness.runs.basins.scan import run_basins

    import xarray as xr

    # xarray imports dask on its first Dataset (to tell dask arrays apart), 0.1 s: an import,
    # like the interpreter's start, not part of either path's scan
    xr.Dataset({"warm": ("i", np.zeros(1))}, coords={"i": [0.0]})
    model = FmuModel(FMU)
    s = SamplingSpec(theta=0.0, n_transient=150, n_samples=30)
    u0, v0 = np.linspace(BOX[0], BOX[1], spec["n"]), np.linspace(BOX[2], BOX[3], spec["n"])
    params = {**model.defaults(), **FIG7}
    cluster = None

    def cpu() -> float:  # this process and its finished children (pool workers, Dask workers)
        a, b = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
        return a.ru_utime + a.ru_stime + b.ru_utime + b.ru_stime

    t0, c0 = time.perf_counter(), cpu()
    if spec["path"] == "fmu":
        ds = run_basins(model, u0, v0, params, s, backend="processes", workers=spec["workers"], progress=False)
    else:
        backend = None
        if spec["path"] == "dask":
            from distributed import Client, LocalCluster

            cluster = LocalCluster(n_workers=spec["workers"], threads_per_worker=1, processes=True,
                                   dashboard_address=None)
            backend = Client(cluster)
            t0, c0 = time.perf_counter(), cpu()  # the scan, not the cluster's start
        ds = run_basins_kernel(model, u0, v0, params, s, backend=backend, workers=spec["workers"], progress=False)
    wall = time.perf_counter() - t0
    scan_cpu = cpu() - c0  # before the agreement checks below run the FMU
    out = {"wall_s": wall, "starts": int(u0.size * v0.size), "starts_per_s": u0.size * v0.size / wall,
           "fractions": [float(x) for x in np.bincount(ds["attractor"].values.ravel()[ds["attractor"].values.ravel()
                                                                                       >= 0]) / ds["attractor"].size]}
    if spec["path"] != "fmu":
        out["periods_mean"] = float(ds.attrs["basins.periods_run_mean"])
    if spec.get("measures"):
        out.update(_measures(model, ds, params, s, spec["check"]))
    if cluster is not None:
        backend.close()
        cluster.close()  # its workers' CPU is counted once they have exited
    out["cpu_s"] = cpu() - c0 if cluster is not None else scan_cpu
    self_kb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    kids_kb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    out["peak_rss_mb"] = max(self_kb, kids_kb) / 1024.0
    return out


def _measures(model, ds, params: dict, s, check: int) -> dict:
    """Quantifiers of the scan and its agreement with the FMU (both solvers)."""
    from harness.analysis.basins.agreement import fmu_agreement
    from harness.analysis.basins.summary import measure_lines, with_measures

    ds = with_measures(ds)
    names = json.loads(ds.attrs["basins.attractors"])
    agree = {"closed form": fmu_agreement(model, ds, params, s, check, seed=1),
             "CVODE": fmu_agreement(model, ds, {**params, "solver": 0}, s, max(1, check // 4), seed=2)}
    return {"lines": measure_lines(ds), "names": names, "agree": agree,
            "confirmed": [bool(x) for x in ds["attractor_confirmed"].values],
            "residual": [float(x) for x in ds["attractor_newton_residual"].values],
            "multiplier": [float(x) for x in ds["attractor_multiplier"].values]}


_RUNS: dict[str, dict] = {}


def run_child(spec: dict) -> dict:
    """``child(spec)`` in a fresh process; a spec measured already in this run is not run again
    (--quick's README grid is also its smallest grid, and its middle grid is the workers' one)."""
    key = json.dumps(spec, sort_keys=True)
    if key not in _RUNS:
        _RUNS[key] = _run_child(spec)
    return _RUNS[key]


def _run_child(spec: dict) -> dict:
    proc = subprocess.run([sys.executable, __file__, "--child", json.dumps(spec)], capture_output=True, text=True,
                          timeout=3600, cwd=ROOT, env={**os.environ, "PYTHONPATH": str(ROOT)})
    if proc.returncode != 0:
        raise RuntimeError(f"{spec}: {proc.stderr[-2000:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def measure(quick: bool) -> dict:
    small, mid, big = (20, 40, 60) if quick else (100, 300, 1000)
    # the README's 60 x 60 grid; --quick: 20 x 20 (the FMU path's 3,600 starts are most of its time)
    readme = 20 if quick else 60
    load0 = os.getloadavg()[0]
    res = {"readme": {k: run_child({"n": readme, "path": k, "workers": 2}) for k in ("fmu", "kernel")}}
    res["workers"] = {f"{k} x{w}": run_child({"n": mid, "path": k, "workers": w})
                      for k, w in (("kernel", 1), ("kernel", 2), ("dask", 2))}
    res["grid"] = {n: run_child({"n": n, "path": "kernel", "workers": 2, "measures": n == big,
                                 "check": 40 if quick else 1000}) for n in (small, mid, big)}
    res["load"] = (load0, os.getloadavg()[0])
    return res


def section(res: dict, quick: bool) -> str:
    r = res["readme"]
    ratio = r["fmu"]["wall_s"] / r["kernel"]["wall_s"]
    rn = round(r["fmu"]["starts"] ** 0.5)
    grid = f"README {rn} x {rn}" if rn == 60 else f"{rn} x {rn} (the README's is 60 x 60)"
    when = _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M")
    lines = ["<!-- basins:begin -->", "## Basin scans: the batch kernel", "",
             f"`python bench/basins_bench.py`{' --quick' if quick else ''} on {when} UTC, {platform.processor() or platform.machine()}, "
             f"{os.cpu_count()} cores, shared with other users (load average {res['load'][0]:.1f} at the start, "
             f"{res['load'][1]:.1f} at the end): wall times are what the scans got, not an idle machine's. "
             "Figure 7's oscillator at sigma = 0.01, u0 in [-1.2, 0] x v0 in [-8, 8] at theta = 0, transient 150, "
             "samples 30; each scan in a fresh process (the scan's wall time, imports done before it; peak RSS of the process and its children).",
             "", "| scan | starts | wall (s) | starts/s | CPU (s), all processes | periods per start | peak RSS (MB) |",
             "|---|---:|---:|---:|---:|---:|---:|"]

    def row(name: str, x: dict) -> str:
        per = f"{x['periods_mean']:.1f}" if "periods_mean" in x else "180"
        return (f"| {name} | {x['starts']:,} | {x['wall_s']:.2f} | {x['starts_per_s']:,.0f} | {x['cpu_s']:.2f} | {per} | "
                f"{x['peak_rss_mb']:.0f} |")

    lines.append(row(f"{grid}, FMU path (fmpy, process pool, 2 workers)", r["fmu"]))
    lines.append(row(f"{grid}, batch kernel (2 threads)", r["kernel"]))
    for k, x in res["workers"].items():
        kind, w = k.split(" x")
        lines.append(row(f"{round(x['starts'] ** 0.5)}^2, " + (
            f"batch kernel, {w} thread(s) in one process" if kind == "kernel" else f"batch kernel on Dask, {w} workers"), x))
    for n, x in res["grid"].items():
        lines.append(row(f"{n} x {n}, batch kernel (2 threads)", x))
    big = res["grid"][max(res["grid"], key=int)]
    lines += ["", f"- The {grid} scan: **{ratio:.0f}x faster** on the batch kernel than through the FMU "
              f"({r['fmu']['wall_s']:.1f} s against {r['kernel']['wall_s']:.2f} s; basin fractions "
              f"{', '.join(f'{x:.4f}' for x in r['fmu']['fractions'])} and "
              f"{', '.join(f'{x:.4f}' for x in r['kernel']['fractions'])}).",
              f"- {max(res['grid'], key=int)}^2 starts: {big['wall_s']:.0f} s, {big['starts_per_s']:,.0f} starts/s, peak "
              f"{big['peak_rss_mb']:.0f} MB; each start ran {big['periods_mean']:.1f} periods on average instead of "
              "180 (early stop)."]
    per_cpu = {k: x["starts"] / x["cpu_s"] for k, x in (("fmu", r["fmu"]), ("kernel", r["kernel"]), ("big", big))}
    w = res["workers"]
    lines += [f"- Per CPU second (all processes; what an idle machine would turn into wall time): the FMU path "
              f"{per_cpu['fmu']:,.0f} starts, the kernel {per_cpu['kernel']:,.0f} on the {rn} x {rn} grid "
              f"({per_cpu['kernel'] / per_cpu['fmu']:.0f}x: the seed, Newton's confirmation, the tolerance balls' check "
              f"and the Dataset weigh on {rn * rn:,} starts) and {per_cpu['big']:,.0f} on the largest grid ({per_cpu['big'] / per_cpu['fmu']:.0f}x the "
              f"FMU path's rate), i.e. {big['starts'] / per_cpu['big'] / 2:.0f} s of wall time on 2 idle cores.",
              "- Workers: " + ", ".join(f"{k.replace('kernel x', '').replace('dask x', 'Dask ')} "
                                        f"{'thread(s)' if k.startswith('kernel') else 'workers'}: "
                                        f"{x['cpu_s']:.1f} CPU s, {x['wall_s']:.1f} s wall" for k, x in w.items())
              + ": the same work however it is spread (threads cost nothing; Dask adds its workers' start-up and "
              "transfers); the wall times follow the other users' load more than the number of workers."]
    for solver, a in big["agree"].items():
        diff = "; ".join(f"({u:.4g}, {v:.4g}): {s} vs {f}" for u, v, s, f in a["differ"][:6]) or "none"
        lines.append(f"- Against the FMU ({solver}, every start run in full): {a['equal']} of {a['starts']} random "
                     f"starts labelled alike ({a['fraction']:.2%}); where they differ (u0, v0: kernel vs FMU label): {diff}.")
    lines.append(f"- Attractors: {', '.join(big['names'])}; confirmed by Newton shooting on the FMU: {big['confirmed']}, "
                 f"residuals {', '.join(f'{x:.1e}' for x in big['residual'])}, largest |multiplier| "
                 f"{', '.join(f'{x:.3f}' for x in big['multiplier'])}.")
    lines += ["- Quantifiers of the largest grid:", "", "```", *[x.strip() for x in big["lines"]], "```",
              "<!-- basins:end -->"]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="small grids, print only")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    ap.add_argument("--json", help="also write the numbers as JSON")
    ap.add_argument("--from-json", metavar="FILE", help="no measurement: the section from a --json file")
    args = ap.parse_args(argv)
    if args.child:
        print(json.dumps(child(json.loads(args.child))))
        return 0
    if args.from_json:
        res = json.loads(Path(args.from_json).read_text())
        res["grid"] = {int(k): v for k, v in res["grid"].items()}
    else:
        res = measure(args.quick)
    text = section(res, args.quick)
    if args.json and not args.from_json:
        Path(args.json).write_text(json.dumps(res, indent=1, default=str))
    if args.quick:
        print(text)
    else:
        from sections import write_section

        write_section(ROOT / "BENCHMARKS.md", text)
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
