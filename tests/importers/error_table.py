"""The table of docs/importers.md: per-period error against the closed form, importer x FMU
variant, measured by running the importer tests' own runs (tests/importers/test_fmusim.py,
tests/importers/test_libcosim.py).

Usage: .venv/bin/python -m tests.importers.error_table   (needs build/tools/fmusim, libcosimpy)
Prints a Markdown table: the largest per-period error in u and v over the tests' four
parameter cases (over-/underdamped, compliant/rigid wall), and impacts counted / exact.
"""
from __future__ import annotations

import tempfile
from pathlib import Path

from tests.importers import test_fmusim as F
from tests.importers import test_libcosim as L
from tests.support.importers import compare_per_period, run_fmusim, write_input_csv


def _row(label: str, checks: list) -> str:
    eu = max(c.err_u for c in checks)
    ev = max(c.err_v for c in checks)
    n, m = sum(c.impacts for c in checks), sum(c.impacts_exact for c in checks)
    return f"| {label} | {eu:.1e} | {ev:.1e} | {n} / {m} |"


def main() -> None:
    tmp = Path(tempfile.mkdtemp(prefix="importer-errors-"))
    rows = []
    for version, fmu in F.FMUS.items():
        for h in (1.0, 0.1, 0.01):
            rows.append(_row(f"fmusim | {version} CS, h = {h:g}",
                             [F.cs_check(fmu, c, tmp, h)[1] for c in F.CASES.values()]))
    for h in (1.0, 0.1):
        flags = ("--early-return-allowed", "--event-mode-used")
        rows.append(_row(f"fmusim | fmi3 CS early return + event mode, h = {h:g}",
                         [F.cs_check(F.FMU3_PATH, c, tmp, h, flags=flags)[1]
                          for c in F.CASES.values()]))
    compliant = [F.CASES["over-compliant"], F.CASES["under-compliant"]]
    for version, fmu in F.FMUS.items():
        for name, inputs, h in (("stairs", F.STAIRS, 0.01), ("ramps", F.RAMPS, 0.1)):
            rows.append(_row(f"fmusim | {version} CS, input file {name}, h = {h:g}",
                             [F.cs_check(fmu, c, tmp, h, inputs=F.scaled(inputs, c))[1]
                              for c in compliant]))
    for version, fmu in F.FMUS.items():
        rows.append(_row(f"fmusim | {version} ME, CVODE rtol 1e-10",
                         [F.me_check(fmu, c, tmp) for c in F.CASES.values()]))
    for version, fmu in F.FMUS.items():
        case = F.CASES["over-compliant"]
        csv = write_input_csv(tmp / "into.csv", F.INTO_THE_MASS)
        res = run_fmusim(fmu, tmp, case, interface="me", stop=F.PERIODS, h=0.1,
                           flags=("--solver", "cvode"), tolerance=F.ME_RTOL, input_csv=csv)
        rows.append(_row(f"fmusim | {version} ME, u_wall steps behind the mass",
                         [compare_per_period(res["time"], res["u"], res["v"], res["impacts"],
                                               res["t_impact"], case, F.ME_HOLDS, F.PERIODS,
                                               t_impact_tol=F.ME_TOL)]))
    try:
        rows.append(_row("fmusim | pythonfmu twin, fmi2 CS, h = 1 and 0.1",
                         [F.cs_check(F.TWIN_FMU, F.CASES[c], tmp, h)[1]
                          for c, h in (("over-compliant", 1.0), ("under-rigid", 0.1))]))
    except AssertionError as e:  # fmusim's non-zero exit: the twin does not load in a C host
        rows.append(f"| fmusim | pythonfmu twin, fmi2 CS | does not run: {str(e).splitlines()[0]} | | |")
    rows.append(_row("libcosim | fmi2 CS alone, h = 0.01",
                     [L.run_alone(c) for c in F.CASES.values()]))
    rows.append(_row("libcosim | fmi2 CS in SSP, controller FMU drives u_wall, h = 0.01",
                     [L.run_ssp(tmp)[0]]))
    print("| importer | FMU variant | max error u | max error v | impacts (run / exact) |")
    print("|---|---|---|---|---|")
    print("\n".join(rows))


if __name__ == "__main__":
    main()
