"""The API reference builds with the one documented command (`bash scripts/docs.sh`, README
"Documentation"): a page per module of harness and mapcheck, and the harness page groups the
entry points as a user looks for them."""
from __future__ import annotations

import os
import pkgutil
import subprocess
from pathlib import Path

import pytest

import harness
import mapcheck

pytestmark = pytest.mark.slow  # builds every API page with pdoc through scripts/docs.sh

ROOT = Path(__file__).resolve().parents[2]
GROUPS = ("FMU driving", "Sampling", "Sweeps", "Errors", "Basins of attraction", "Shooting", "Lyapunov exponents",
          "Jacobians", "Comparison with the maps", "Maps")


def test_docs_command_builds_every_module_page(tmp_path: Path) -> None:
    out = tmp_path / "docs"
    res = subprocess.run(["bash", "scripts/docs.sh", "--no-search"], cwd=ROOT, capture_output=True, text=True,
                         env={**os.environ, "DOCS_OUT": str(out), "IMPACT_DOCS_NO_SETUP": "1"}, timeout=600)
    assert res.returncode == 0, res.stderr[-3000:]
    assert "Traceback" not in res.stderr and "Error" not in res.stderr, res.stderr[-3000:]
    assert "Warn" not in res.stderr, res.stderr[-3000:]  # e.g. a module documented twice
    for pkg in (harness, mapcheck):
        names = [pkg.__name__] + [m.name for m in pkgutil.walk_packages(pkg.__path__, pkg.__name__ + ".")
                                  if not m.name.endswith("__main__")]
        for name in names:
            page = out / (name.replace(".", "/") + ".html")
            assert page.is_file() and page.stat().st_size > 0, name
    text = (out / "harness.html").read_text()
    for group in GROUPS:
        assert f">{group}</h" in text, group  # a heading of the grouped index


def test_the_overview_lists_every_public_name() -> None:
    """Every name importable from ``harness`` is introduced on the package's page."""
    missing = [n for n in harness.__all__ if n != "__version__" and f"`{n}`" not in harness.__doc__]
    assert not missing, missing
