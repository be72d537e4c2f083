"""The FMUs' sources: FMI 3.0 sources/ with buildDescription.xml, FMI 2.0 <SourceFiles>,
CVODE's needed files and its license inside. Rebuilt from the archive alone -- with fmpy's
build_platform_binary (only `-I sources` and the listed files) and with a plain
`cmake -S sources` -- the Linux binary gives, through the C host, the same states one period on
as the shipped binary (same compiler and flags class: equal to 1e-12, not bit for bit, since fmpy
builds without -O2's exact flags)."""
from __future__ import annotations

import shutil
import sys
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.build import build_platform_binary

from tests.support.fmu import FMU3_PATH, FMU_PATH
from tests.support.platforms import NATIVE, host_input, require_cross_build, run_host, unpack

pytestmark = pytest.mark.slow  # rebuilds the FMUs from their shipped sources

CASE = dict(nu=4.605170185988091, Omega=0.3059238689620112, r=0.9, Gamma=10.0, sigma=0.5,
            wall="compliant")
STARTS = np.array([[k, -1.0 + 0.3 * k, 0.2 - 0.1 * k] for k in range(5)], dtype=float)
FMUS = [(FMU_PATH, "fmi2"), (FMU3_PATH, "fmi3")]


def _shipped_and(rebuild, tmp_path: Path, fmu: Path, fmi: str) -> tuple[np.ndarray, np.ndarray]:
    shipped = unpack(fmu, tmp_path / "shipped")
    rebuilt = unpack(fmu, tmp_path / "rebuilt")
    target = rebuilt / NATIVE.binary(fmi)
    target.unlink()
    shutil.rmtree(rebuilt / "binaries" / "win64", ignore_errors=True)
    rebuild(rebuilt, target)
    assert target.exists()
    text = host_input([(CASE, STARTS)])
    return (run_host(NATIVE, shipped, fmi, "cs", text), run_host(NATIVE, rebuilt, fmi, "cs", text))


@pytest.mark.parametrize("fmu,fmi", FMUS, ids=["fmi2", "fmi3"])
def test_sources_are_declared_and_licensed(fmu, fmi):
    require_cross_build()
    names = set(zipfile.ZipFile(fmu).namelist())
    md = read_model_description(str(fmu))
    files = md.buildConfigurations[0].sourceFileSets[0].sourceFiles
    assert {"fmu_core.c", "cvode/cvode.c", "nvector/nvector_serial.c"} <= set(files)
    assert all(f"sources/{f}" in names for f in files)
    assert "documentation/licenses/SUNDIALS-LICENSE.txt" in names
    assert ("sources/buildDescription.xml" in names) == (fmi == "fmi3")


@pytest.mark.parametrize("fmu,fmi", FMUS, ids=["fmi2", "fmi3"])
def test_fmpy_rebuilds_the_linux_binary(tmp_path, fmu, fmi):
    require_cross_build()

    def rebuild(unzipdir: Path, target: Path) -> None:
        (tmp_path / "fmpy-build").mkdir()
        build_platform_binary(unzipdir, build_dir=tmp_path / "fmpy-build")

    shipped, rebuilt = _shipped_and(rebuild, tmp_path, fmu, fmi)
    assert np.isfinite(rebuilt).all()
    assert np.abs(rebuilt - shipped).max() <= 1e-12


@pytest.mark.parametrize("fmu,fmi", FMUS[1:], ids=["fmi3"])  # sources/CMakeLists.txt is one template
def test_plain_cmake_rebuilds_from_sources_alone(tmp_path, fmu, fmi):
    require_cross_build()

    def rebuild(unzipdir: Path, target: Path) -> None:
        alone = tmp_path / "sources"
        shutil.copytree(unzipdir / "sources", alone)  # nothing else of the FMU or the repository
        bld = tmp_path / "cmake-build"
        for cmd in (["cmake", "-S", str(alone), "-B", str(bld)], ["cmake", "--build", str(bld), "-j", "2"]):
            subprocess.run(cmd, check=True, capture_output=True)
        shutil.copy(bld / "ImpactOscillator.so", target)

    shipped, rebuilt = _shipped_and(rebuild, tmp_path, fmu, fmi)
    assert np.isfinite(rebuilt).all()
    assert np.abs(rebuilt - shipped).max() <= 1e-12


@pytest.mark.parametrize("fmu,fmi", FMUS[1:], ids=["fmi3"])  # buildDescription.xml: FMI 3.0 only
def test_fmi_bd2cmake_builds_the_binary_from_the_build_description(tmp_path, fmu, fmi):
    """An independent toolchain: the PyPI package fmi-bd2cmake reads sources/buildDescription.xml
    and writes its own CMake project (not the one shipped in sources/); the binary it builds runs
    the same orbit as the shipped one."""
    require_cross_build()
    tool = Path(sys.executable).with_name("fmi-bd2cmake")
    assert tool.exists(), "fmi-bd2cmake missing: pip install fmi-bd2cmake (pyproject.toml)"

    def rebuild(unzipdir: Path, target: Path) -> None:
        project = tmp_path / "bd2cmake"
        shutil.copytree(unzipdir / "sources", project / "sources")
        (project / "sources" / "CMakeLists.txt").unlink()  # only the generated project is used
        subprocess.run([str(tool), "-i", "sources/buildDescription.xml", "-o", "CMakeLists.txt"],
                       cwd=project, check=True, capture_output=True)
        headers = project / "sources" / "fmi-headers"
        for cmd in (["cmake", "-S", ".", "-B", "build", f"-DFMI_HEADERS_DIR={headers}"],
                    ["cmake", "--build", "build", "-j", "2"]):
            subprocess.run(cmd, cwd=project, check=True, capture_output=True)
        shutil.copy(project / "build" / NATIVE.binary(fmi), target)

    shipped, rebuilt = _shipped_and(rebuild, tmp_path, fmu, fmi)
    assert np.isfinite(rebuilt).all()
    assert np.abs(rebuilt - shipped).max() <= 1e-12
