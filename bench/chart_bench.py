"""Benchmark of ``impact-harness chart``: the soft-to-hard chart of Figure 9's family
(windows M = 1..5 over (sigma, Gamma), Gamma = 10 .. 1e6 on a log axis) in closed-form mode, and
the same per-value cost in CVODE mode, measured in one run.  Writes the chart into
docs/img/soft_to_hard.png (with chart.json beside it in OUT) and its section of BENCHMARKS.md.

    .venv/bin/python bench/chart_bench.py [--num 30] [--cvode-num 4] [--workers 2] [--out results/chart-bench]
"""
from __future__ import annotations

import argparse
import json
import platform
import shutil
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bench.sections import write_section  # noqa: E402


def _run(args: list[str]) -> tuple[float, dict]:
    from harness.cli.main import main

    t0 = time.perf_counter()
    assert main(args) == 0
    wall = time.perf_counter() - t0
    out = Path(args[args.index("--out") + 1])
    return wall, json.loads((out / "chart.json").read_text())


def _checked(res: dict) -> str:
    n = sum(c["checked"] for c in res["edge_check"].values())
    ok = sum(c["confirmed"] for c in res["edge_check"].values())
    return f"{ok} of {n} confirmed"


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--num", type=int, default=30)
    ap.add_argument("--cvode-num", type=int, default=4)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default="results/chart-bench")
    a = ap.parse_args()
    common = ["chart", "--config", str(ROOT / "harness/experiments/fig9.toml"), "--param2", "Gamma", "--log",
              "--M-max", "5", "--workers", str(a.workers)]
    cf_out, cv_out = Path(a.out) / "closed-form", Path(a.out) / "cvode"
    t_cf, cf = _run(common + ["--range", "10:1e6", "--num", str(a.num), "--solver", "closed-form",
                              "--out", str(cf_out)])
    # CVODE: fewer values and M <= 2 (the continuation alone takes minutes in this mode)
    t_cv, cv = _run([*common[:-4], "--M-max", "2", *common[-2:], "--range", "10:1e6", "--num", str(a.cvode_num),
                     "--solver", "cvode", "--out", str(cv_out)])
    (ROOT / "docs/img").mkdir(parents=True, exist_ok=True)
    shutil.copy(cf_out / "chart.png", ROOT / "docs/img/soft_to_hard.png")
    per_cf = sum(cf["task_seconds"]) / len(cf["task_seconds"])
    per_cv = sum(cv["task_seconds"]) / len(cv["task_seconds"])
    closes = cf["closes"]

    def fmt(c: dict) -> str:
        return "null" if c["closes"] is None else f"{c['closes']:.10g}"

    cv_closes = ", ".join(f"M = {M}: {fmt(c)} (closed form {fmt(cf['closes'][M])})" for M, c in cv["closes"].items())
    text = f"""<!-- chart:begin -->
## Soft-to-hard chart: `impact-harness chart`

Figure 9's family (harness/experiments/fig9.toml), windows M = 1..5 over (sigma, Gamma), Gamma = 10 .. 1e6
(log), sigma scanned over [{cf['parameters']['sigma_grid'][0]:g}, {cf['parameters']['sigma_grid'][1]:g}]
({cf['parameters']['sigma_grid'][2]} points), {a.workers} worker processes; {platform.processor() or platform.machine()},
Python {platform.python_version()}. Measured by `bench/chart_bench.py` in one run:

| mode | M | Gamma values scanned | wall time | mean time per value (in a worker) | two-parameter continuation of the edges |
|---|---|---|---|---|---|
| closed form | 1..5 | {a.num} | {t_cf:.1f} s | {per_cf:.2f} s | {cf['continuation_seconds']:.1f} s |
| CVODE | 1..2 | {a.cvode_num} | {t_cv:.1f} s | {per_cv:.2f} s | {cv['continuation_seconds']:.1f} s |

CVODE / closed form per scanned value: {per_cv / per_cf:.1f}x. Goal: the {a.num}-value chart in closed-form mode under
10 minutes on 2 cores ({'met' if t_cf < 600 else 'NOT met'}: {t_cf / 60:.1f} min). Where each window closes
(two-parameter continuation of its edges; null: not closing in the range, see chart.json):

{chr(10).join(f'- M = {M}: ' + ('null, ' + (c.get('note') or 'searched to the end of the range') if c['closes'] is None else f"Gamma = {c['closes']:.6g} at sigma = {c['sigma']:.5g}: {c['how']}") for M, c in closes.items())}

The same with CVODE (M <= 2): {cv_closes}.
Every point of every edge curve checked across itself (`edge_check`): closed form {_checked(cf)}; CVODE {_checked(cv)}.
Picture: docs/img/soft_to_hard.png.
<!-- chart:end -->"""
    write_section(ROOT / "BENCHMARKS.md", text)
    print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
