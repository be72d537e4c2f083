"""bench/cosim_bench.py --quick: the benchmark runs and writes a well-formed marked section."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

pytest.importorskip("ecospy", reason="ecospy is a dev extra: pip install -e '.[dev]'")

pytestmark = pytest.mark.slow  # runs the co-simulation benchmark's quick mode
ROOT = Path(__file__).resolve().parents[2]


def test_cosim_bench_quick_writes_its_section(tmp_path: Path) -> None:
    spec = importlib.util.spec_from_file_location("cosim_bench", ROOT / "bench" / "cosim_bench.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    out = tmp_path / "B.md"
    out.write_text("# Benchmarks\n\n<!-- other:begin -->\nkept\n<!-- other:end -->\n")
    assert mod.main(["--quick", "--out", str(out)]) == 0
    text = out.read_text()
    assert "kept" in text and text.count(mod.BEGIN) == 1 and text.count(mod.END) == 1
    rows = [ln for ln in text.splitlines() if ln.startswith("| 0.001 |") or ln.startswith("| 1 |")]
    assert len(rows) == 2 and all("nan" not in r for r in rows)
    # a second run replaces the section instead of appending another
    assert mod.main(["--quick", "--out", str(out)]) == 0
    assert out.read_text().count(mod.BEGIN) == 1
