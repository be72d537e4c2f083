"""Parallel efficiency and memory of the process-pool backend: wall and CPU seconds of a run on
1 and 2 workers, the peak RSS of its process tree (bench/run.py's "Parallel efficiency" section)."""
from __future__ import annotations

import os
import shlex
import subprocess
import sys
import threading
import time
from pathlib import Path

from methods import CASES  # bench/methods.py, next to this module

ROOT = Path(__file__).resolve().parents[1]
PYTHON = sys.executable


def _tree_cpu(pid: int, seen: dict) -> int:
    """Update ``seen[pid] = CPU seconds`` for the process tree of ``pid``; return its summed RSS."""
    import psutil

    try:
        p = psutil.Process(pid)
        procs = [p] + p.children(recursive=True)
    except psutil.Error:
        return 0
    total = 0
    for q in procs:
        try:
            with q.oneshot():
                total += q.memory_info().rss
                t = q.cpu_times()
                seen[q.pid] = t.user + t.system
        except psutil.Error:
            pass
    return total


def timed_command(cmd: list[str]) -> dict:
    """Wall seconds of a command, the peak of the summed RSS of its process tree, and the CPU
    seconds of each of its processes (polled every 50 ms)."""
    peak = [0]
    seen: dict[int, float] = {}
    w0 = time.perf_counter()
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    done = threading.Event()

    def poll():
        while not done.is_set():
            peak[0] = max(peak[0], _tree_cpu(proc.pid, seen))
            done.wait(0.05)

    th = threading.Thread(target=poll, daemon=True)
    th.start()
    out, _ = proc.communicate()
    wall = time.perf_counter() - w0
    done.set()
    th.join()
    if proc.returncode != 0:
        raise RuntimeError(f"{shlex.join(cmd)} failed ({proc.returncode}):\n{out[-2000:]}")
    main_cpu = seen.pop(proc.pid, 0.0)
    others = sorted(seen.values(), reverse=True)
    return dict(wall_s=wall, peak_rss_mb=peak[0] / 2**20, cpu_main=main_cpu, cpu_children=others,
                cpu_total=main_cpu + sum(others), cpu_critical=main_cpu + (others[0] if others else 0.0))


def parallel_runs(quick: bool, repeat: int, workdir: Path) -> list[dict]:
    """Wall time on 1 and 2 workers of the Figure 9 reproduction (full mode only) and of a
    fresh-start sigma sweep at Figure 9's parameters (process-pool backend)."""
    jobs = []
    if not quick:
        jobs.append(("reproduce fig9 --quick",
                     lambda w: [PYTHON, "-m", "harness", "reproduce", "fig9", "--quick", "--workers", str(w),
                                "--no-progress", "--out", str(workdir / f"fig9_w{w}")]))
    n, tr, sa = (8, 60, 12) if quick else (91, 300, 40)
    f9 = CASES[0].params
    sweep_args = ["--set", f"nu={f9['nu']!r}", "--set", f"Omega={f9['Omega']!r}", "--set", "Gamma=10",
                  "--set", "r=0.9", "--start", "0.15", "--stop", "1.0", "--num", str(n), "--mode", "fresh",
                  "--transient", str(tr), "--samples", str(sa), "--no-plot", "--no-progress",
                  "--backend", "processes"]
    jobs.append((f"sweep fig9 fresh, {n} sigma x {tr + sa} periods",
                 lambda w: [PYTHON, "-m", "harness", "sweep", *sweep_args, "--workers", str(w),
                            "--out", str(workdir / f"sweep_w{w}.nc")]))
    rows = []
    for name, make in jobs:
        res = {1: [], 2: []}
        for _ in range(repeat):
            for w in (1, 2):  # interleaved: load changes on the shared machine hit both
                load = os.getloadavg()[0]
                r = timed_command(make(w))
                r["load_before"] = load
                res[w].append(r)
        b1 = min(res[1], key=lambda r: r["wall_s"])
        b2 = min(res[2], key=lambda r: r["wall_s"])
        c1 = min(r["cpu_total"] for r in res[1])
        c2 = min(r["cpu_critical"] for r in res[2])
        rows.append(dict(job=name, command=shlex.join(make(2)).replace(str(workdir), "$TMP").replace(PYTHON, "python"),
                         wall_1=b1["wall_s"], wall_2=b2["wall_s"], efficiency=b1["wall_s"] / (2 * b2["wall_s"]),
                         cpu_total_1=c1, cpu_critical_2=c2, efficiency_cpu=c1 / (2 * c2),
                         cpu_main_2=min(r["cpu_main"] for r in res[2]),
                         cpu_workers_2=min(res[2], key=lambda r: r["cpu_critical"])["cpu_children"][:2],
                         cpu_total_2=min(r["cpu_total"] for r in res[2]),
                         peak_rss_mb_1=max(r["peak_rss_mb"] for r in res[1]),
                         peak_rss_mb_2=max(r["peak_rss_mb"] for r in res[2]),
                         all_walls_1=[r["wall_s"] for r in res[1]], all_walls_2=[r["wall_s"] for r in res[2]],
                         loads=[r["load_before"] for w in (1, 2) for r in res[w]]))
    return rows
