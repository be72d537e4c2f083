"""valgrind (memcheck) on a short run of the release FMU binaries through a small C driver.

The driver (tests/fuzz/valgrind_driver.c) takes every life-cycle path of FMI 2.0 and 3.0
Co-Simulation and Model Exchange once, including FMU states and a corrupted one; any invalid
read/write, use of uninitialised memory or definite/indirect leak fails the test.
"""
from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from tests.fuzz.model import ROOT, describe

pytestmark = pytest.mark.skipif(shutil.which("valgrind") is None or shutil.which("cc") is None,
                                reason="valgrind or a C compiler missing (scripts/setup.sh installs them)")

VALGRIND = ["valgrind", "-q", "--error-exitcode=99", "--leak-check=full",
            "--errors-for-leak-kinds=definite,indirect", "--track-origins=yes"]


@pytest.fixture(scope="module")
def driver(tmp_path_factory: pytest.TempPathFactory) -> Path:
    exe = tmp_path_factory.mktemp("valgrind") / "driver"
    inc = ROOT / "fmu_src" / "include"
    subprocess.run(["cc", "-g", "-O0", "-Wall", "-I", str(inc / "fmi2"), "-I", str(inc / "fmi3"),
                    str(ROOT / "tests" / "fuzz" / "valgrind_driver.c"), "-o", str(exe), "-ldl"],
                   check=True)
    return exe


def _run(driver: Path, *extra: str) -> subprocess.CompletedProcess:
    build = ROOT / "build" / "fmu"
    d2, d3 = describe(build, 2), describe(build, 3)
    return subprocess.run([*VALGRIND, str(driver), str(d2.library), str(d3.library), d2.token,
                           *extra], capture_output=True, text=True, timeout=600)


def test_memcheck_clean(driver: Path) -> None:
    res = _run(driver)
    assert res.returncode == 0, f"valgrind/driver failed (rc {res.returncode}):\n{res.stderr[-4000:]}"
    assert "0 failures" in res.stdout


def test_memcheck_sees_a_leak(driver: Path) -> None:
    """The same run with one FMU state never freed: valgrind must report it (rc 99)."""
    res = _run(driver, "leak")
    assert res.returncode == 99, res.stderr[-2000:]
    assert "definitely lost" in res.stderr
