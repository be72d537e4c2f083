"""Renders docs/fmi-state-machine.md from the state table in fmu_src/fmu_states.c.

``python scripts/state_table_doc.py`` rewrites the file; ``--check`` exits 1 if it differs from
what the C table gives (tests/fmu/test_fmi_state_doc.py runs that check, scripts/docs.sh the
rewrite), so the documented table cannot drift from the one the FMU enforces.
"""
from __future__ import annotations

import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CORE = ROOT / "fmu_src" / "fmu_states.c"
DOC = ROOT / "docs" / "fmi-state-machine.md"

LETTERS = {"I": "Instantiated", "N": "Initialization Mode", "S": "Step Mode",
           "E": "Event Mode", "C": "Continuous-Time Mode", "T": "Terminated", "X": "Error"}
ORDER = "INSECTX"
_ROW = re.compile(r'^\s*\{"(fmi[23]\w+)",\s*([^,]+),\s*([^,]+),\s*([^}]+)\},\s*$')

INTRO = """# The FMI state machine of the C FMU

Every FMI function of the C FMU (fmu_src/) checks, before anything else, that its instance is
not NULL and that the call is allowed in the instance's state; the states in which each function
is allowed are one table, `STATE_TABLE` in fmu_src/fmu_states.c, taken from FMI 2.0.4 sections
3.2.3 and 4.2.4 and FMI 3.0 sections 3.2 and 4.2. The pythonfmu twin's C front
(fmu_src/pytwin/twin_export.c) checks its calls against the same table, its FMI 2.0
Co-Simulation column. This page is generated from that table
(`python scripts/state_table_doc.py`; a test fails when they differ), and
tests/fmu/test_fmi_conformance.py checks every (state, function) pair of the built FMUs against a
second table written from the standards' text (tests/support/fmi_standard.py).

**After an error.** Any call that returns Error (a call in the wrong state, a bad argument, a
failed step) leaves the instance in the standard's error state:

* FMI 2.0 (section 2.1.3): **Error**. Allowed there: getters (for debugging),
  `fmi2GetFMUstate`/`fmi2SetFMUstate` (restoring a state saved before continues the
  simulation), the other FMU-state functions, `fmi2Reset`, `fmi2FreeInstance`,
  `fmi2SetDebugLogging`. `fmi2Terminate` is not allowed in Error.
* FMI 3.0 (section 2.2.3): **Terminated**, with the same ways out (`fmi3SetFMUState`,
  `fmi3Reset`, `fmi3FreeInstance`).

No function of this FMU returns Fatal. **Intermediate Update Mode** (FMI 3.0 Co-Simulation,
inside the importer's `intermediateUpdate` callback) allows reading or writing only variables
declared with `intermediateUpdate="true"`; this FMU declares none, so every call made from the
callback is refused, the instance goes to Terminated and the enclosing `fmi3DoStep` returns
Error. `fmi3FreeInstance` from the callback is refused (the instance is not freed).

Other rules the table does not show: `DoStep` needs h > 0 (h = 0 and h = -0.0 are refused);
tunable `sigma` may change in Step Mode (FMI 2.0 CS), Event Mode (FMI 2.0 ME), Step or Event
Mode (FMI 3.0), never in Continuous-Time Mode, where only the continuous inputs `F_ext`,
`u_wall` and `v_wall` may be set; `SetDebugLogging` accepts only the declared categories (`logStatusError`,
`logStatusWarning`, `logEvents`); with logging off only errors are logged.

**Where the two versions differ, and which text decides.**

* `fmi3EnterEventMode` (Model Exchange) is allowed in Continuous-Time Mode only: FMI 3.0
  section 3.2 draws the transition into Event Mode from Continuous-Time Mode (and, in
  Co-Simulation with `eventModeUsed`, section 4.2 from Step Mode), none from Event Mode itself;
  the Reference FMUs' mask is the same. FMI 2.0.4's table (section 3.2.3) marks
  `fmi2EnterEventMode` in Event Mode too, and the FMI 2.0 FMU accepts it there.
* `fmi2GetDerivatives` and `fmi2GetNominalsOfContinuousStates` are refused in Initialization
  Mode: FMI 2.0.4 section 3.2.3, the table of the functions allowed per state, marks neither in
  its Initialization Mode column (fmusdk's masks agree). The derivatives are InitialUnknowns of
  the ModelStructure there and `fmi2GetReal` on `der(u)`, `der(v)` answers; FMI 3.0 (section 3.2)
  allows `fmi3GetContinuousStateDerivatives` and `fmi3GetNominalsOfContinuousStates` in
  Initialization Mode, and the FMI 3.0 FMU answers them.
* `fmi2GetRealStatus(fmi2LastSuccessfulTime)` (FMI 2.0.4 section 4.2.3) answers after a
  completed step and after `fmi2Terminate` (the table of 4.2.4: stepComplete and terminated),
  on the C FMU and on the twin: the end of the last completed step, the start time before the
  first. The other status kinds are not provided (the twin: Discard; the C FMU: Error).

Letters: I Instantiated, N Initialization Mode, S Step Mode (FMI 2.0: stepComplete), E Event
Mode, C Continuous-Time Mode, T Terminated, X Error. A dash: allowed in no state (the FMU does
not declare what it needs: clocks, structural parameters, `providesEvaluateDiscreteStates`,
Scheduled Execution; or, as for `fmi2CancelStep`, its state is never entered).
"""


def parse(text: str) -> list[tuple[str, str, str, str]]:
    """The rows of STATE_TABLE: (function, Co-Simulation, Model Exchange, CS with event mode)."""
    body = text.split("/* STATE_TABLE_BEGIN */", 1)[1].split("/* STATE_TABLE_END */", 1)[0]
    rows = []
    for line in body.splitlines():
        m = _ROW.match(line)
        if m:
            rows.append(tuple(g.strip() for g in m.groups()))
    if not rows:
        raise SystemExit("no STATE_TABLE rows found in fmu_states.c")
    return rows


def letters(mask: str) -> str:
    """'I|N|S' -> 'I N S' in the fixed order; '0' -> '-'."""
    if mask == "0":
        return "-"
    got = set(mask.replace(" ", "").split("|"))
    unknown = got - set(LETTERS)
    if unknown:
        raise SystemExit(f"unknown state letters {unknown} in STATE_TABLE")
    return " ".join(x for x in ORDER if x in got)


def render(rows: list[tuple[str, str, str, str]]) -> str:
    """The markdown page for the table's rows."""
    out = [INTRO, "## FMI 2.0\n", "| function | Co-Simulation | Model Exchange |", "|---|---|---|"]
    for fn, cs, me, _ in rows:
        if fn.startswith("fmi2"):
            out.append(f"| `{fn}` | {letters(cs)} | {letters(me)} |")
    out += ["", "## FMI 3.0\n",
            "| function | Co-Simulation | Co-Simulation, eventModeUsed | Model Exchange |",
            "|---|---|---|---|"]
    for fn, cs, me, cse in rows:
        if fn.startswith("fmi3"):
            out.append(f"| `{fn}` | {letters(cs)} | {letters(cse)} | {letters(me)} |")
    return "\n".join(out) + "\n"


def main(argv: list[str]) -> int:
    page = render(parse(CORE.read_text()))
    if "--check" in argv:
        if not DOC.is_file() or DOC.read_text() != page:
            print(f"{DOC.relative_to(ROOT)} differs from fmu_states.c's STATE_TABLE: run "
                  "python scripts/state_table_doc.py", file=sys.stderr)
            return 1
        return 0
    DOC.write_text(page)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
