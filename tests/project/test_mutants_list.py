"""The mutation run (scripts/mutants.py, on demand; its last result in TESTING.md) stays usable:
every mutant's snippet occurs exactly once in the code it mutates, and the machinery really runs
the tests against the mutated copy (a mutant the suite is known to kill is killed)."""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _mutants():
    spec = importlib.util.spec_from_file_location("mutants", ROOT / "scripts" / "mutants.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("mutants", module)  # dataclasses look their module up by name
    spec.loader.exec_module(module)
    return module


def test_every_mutant_applies_to_the_current_code() -> None:
    mod = _mutants()
    assert len(mod.MUTANTS) >= 40
    assert mod.check_list() == []
    assert {m.path.split("/")[0] for m in mod.MUTANTS} >= {"fmu_src", "harness", "mapcheck"}


def test_a_planted_bug_is_run_against_the_copy_and_killed() -> None:
    """M42 changes (64)'s upper edge; if the copy's tests imported the checkout's mapcheck instead
    of the mutated copy, the mutant would survive."""
    mod = _mutants()
    m42 = next(m for m in mod.MUTANTS if m.id == "M42")
    status, detail, _ = mod.run_one(m42, timeout=600)
    assert status == "killed", (status, detail)
    assert detail.startswith("tests/mapcheck/test_windows.py::")
