"""The files generated from the FMU's variable spec (fmu_src/variables.py) are up to date.

They are committed, so that the FMU builds with CMake alone; the generator
(fmu_src/generate_variables.py) runs here into a temporary folder, and every file it writes must
equal the committed one.  A failure names the stale file and the command that regenerates it.
"""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
GENERATOR = ROOT / "fmu_src" / "generate_variables.py"
COMMAND = "python fmu_src/generate_variables.py"
#: every file the generator writes, relative to the repository root
GENERATED = (
    "fmu_src/variables.h",
    "fmu_src/variables_table.inc",
    "fmu_src/model_defaults.inc",
    "fmu_src/model_params.inc",
    "fmu_src/modelDescription.xml",
    "fmu_src/modelDescription3.xml",
    "docs/fmu.md",
    "fmu_src/pytwin/twin_variables.py",
)


@pytest.fixture(scope="module")
def generated(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("generated")
    subprocess.run([sys.executable, str(GENERATOR), "--out", str(out)], check=True, cwd=ROOT)
    return out


def test_the_generator_writes_exactly_the_listed_files(generated: Path) -> None:
    written = sorted(str(p.relative_to(generated)) for p in generated.rglob("*") if p.is_file())
    assert written == sorted(GENERATED)


@pytest.mark.parametrize("rel", GENERATED)
def test_committed_file_is_up_to_date(generated: Path, rel: str) -> None:
    fresh = (generated / rel).read_bytes()
    committed = (ROOT / rel).read_bytes()
    assert committed == fresh, (
        f"{rel} is stale: it differs from what fmu_src/variables.py generates; run `{COMMAND}` "
        "from the repository root and commit the result")
