"""Smoke test of the benchmark script: ``bench/run.py --quick`` finishes and produces
its table with sane accuracy columns.  No timing is asserted (the machine is shared)."""
from __future__ import annotations

import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow  # runs the benchmark script

ROOT = Path(__file__).resolve().parents[2]
METHODS = ("harness", "c_driver", "twin", "dop853", "exact")


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    if shutil.which("cc") is None:
        pytest.skip("no system C compiler (cc) for the bare C driver")
    for fmu in ("ImpactOscillator.fmu", "ImpactOscillatorPy.fmu"):
        if not (ROOT / "build" / "fmu" / fmu).is_file():
            pytest.skip(f"build/fmu/{fmu} is not built")
    out = tmp_path_factory.mktemp("bench")
    md, js = out / "BENCHMARKS.md", out / "bench.json"
    proc = subprocess.run([sys.executable, str(ROOT / "bench" / "run.py"), "--quick", "--out", str(md),
                           "--json", str(js)], cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    return proc.stdout, md.read_text(), json.loads(js.read_text())


def test_table_is_printed_and_written(quick_run):
    stdout, md, _ = quick_run
    header = "| case | method | settings | us/period (CPU) | periods/s |"
    assert header in stdout and header in md
    rows = [line for line in md.splitlines() if line.startswith("| fig9 |") or line.startswith("| underdamped |")]
    assert len(rows) == 2 * len(METHODS)
    for row in rows:
        assert len(row.strip("|").split("|")) == 11
    for section in ("## Goals", "## Parallel efficiency", "## Long run", "## Map iterations", "## Rerun"):
        assert section in md


def test_accuracy_columns_are_sane(quick_run):
    _, _, res = quick_run
    assert [c["key"] for c in res["cases"]] == ["fig9", "underdamped"]
    for case in res["cases"]:
        assert case["same_orbit"], "the harness and the bare C driver must read the same orbit"
        assert set(case["methods"]) == set(METHODS)
        for key, m in case["methods"].items():
            assert math.isfinite(m["us_cpu"]) and m["us_cpu"] > 0, key
            assert m["periods_per_s"] > 0, key
            assert m["eval_periods"] >= 1, key
            assert m["contacts_exact"] >= 1, key  # both cases have contacts every few periods
            assert 0 <= m["map_error"] < 1e-6, (case["key"], key, m["map_error"])
            assert m["missed"] == 0 and m["invented"] == 0, (case["key"], key)
        assert case["methods"]["exact"]["map_error"] < 1e-10  # restart vs continue of the closed form


def test_other_sections(quick_run):
    _, _, res = quick_run
    lr = res["long_run"]
    assert lr["periods"] >= 1000 and lr["error_last"] < 1e-6 and lr["missed_last"] == 0
    assert res["map_speed"]["per_s"] > 0
    assert res["parallel"] and all(p["wall_1"] > 0 and p["wall_2"] > 0 for p in res["parallel"])
    assert all(isinstance(g["met"], bool) for g in res["goals"].values())


def test_continuation_bench_quick() -> None:
    """``bench/continuation_bench.py --quick`` runs both solver modes and prints its section."""
    proc = subprocess.run([sys.executable, str(ROOT / "bench" / "continuation_bench.py"), "--quick"],
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "<!-- continuation:begin -->" in proc.stdout and "| closed form | 21 |" in proc.stdout


def test_basins_bench_quick() -> None:
    """``bench/basins_bench.py --quick`` runs the FMU path, the kernel on threads and on Dask, and
    the check against the FMU, and prints its section (nothing written)."""
    proc = subprocess.run([sys.executable, str(ROOT / "bench" / "basins_bench.py"), "--quick"],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    out = proc.stdout
    assert "<!-- basins:begin -->" in out and "batch kernel on Dask, 2 workers" in out
    assert "40 of 40 random starts labelled alike (100.00%)" in out
