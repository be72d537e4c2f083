"""docs/fmi-state-machine.md is fmu_states.c's STATE_TABLE, and that table is the standards' one.

The page is generated (scripts/state_table_doc.py, run by scripts/docs.sh); this test fails when
the C table changed without the page. It also compares the C table, row by row, with
tests/support/fmi_standard.py (written from the standards' text): the conformance suite checks the
FMU's behaviour, this the table itself, so a disagreement names the row.
"""
from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

from tests.support import fmi_standard as std

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "scripts" / "state_table_doc.py"
NAMES = {"I": "Instantiated", "N": "Init", "S": "Step", "E": "Event", "C": "Continuous",
         "T": "Terminated", "X": "Error"}


def _doc_module():
    spec = importlib.util.spec_from_file_location("state_table_doc", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_the_page_is_the_c_table() -> None:
    r = subprocess.run([sys.executable, str(SCRIPT), "--check"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


def test_the_c_table_is_the_standard_table() -> None:
    mod = _doc_module()
    rows = mod.parse(mod.CORE.read_text())
    seen = set()
    for fn, cs, me, cse in rows:
        def states(mask: str) -> frozenset[str]:
            return frozenset(NAMES[x] for x in mod.letters(mask).split() if x in NAMES)
        seen.add(fn)
        if fn.startswith("fmi2"):
            assert states(cs) == std.allowed("fmi2-cs", fn), fn
            assert states(me) == std.allowed("fmi2-me", fn), fn
        else:
            assert states(cs) == std.allowed("fmi3-cs", fn), fn
            assert states(cse) == std.allowed("fmi3-cs-event", fn), fn
            assert states(me) == std.allowed("fmi3-me", fn), fn
    assert seen == set(std.FMI2) | set(std.FMI3)
