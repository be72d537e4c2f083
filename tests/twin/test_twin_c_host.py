"""The pythonfmu twin in a non-Python importer: a C program that dlopens it runs without a
Python environment of its own and computes what fmpy gets in-process; a missing Python is an
FMI error; valgrind finds no use after free at the C host's exit.
"""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description

from mapcheck.exact import ExactOscillator
from tests.support.fmu import WALLS
from tests.support.twin import ROOT, Slave


# ---------------------------------------------------------------------------------------------
# a non-Python importer: the runtime needs stated in fmu_src/pytwin/README.md
# ---------------------------------------------------------------------------------------------
_C_IMPORTER = r"""
#include <dlfcn.h>
#include <stdio.h>
#include <stdarg.h>
#include <stdlib.h>
#include "fmi2Functions.h"
static void logger(fmi2ComponentEnvironment e, fmi2String name, fmi2Status s, fmi2String cat,
                   fmi2String msg, ...) {
    va_list ap;
    (void)e; (void)name; (void)cat;
    printf("log %d: ", (int)s);
    va_start(ap, msg);
    vprintf(msg, ap);
    va_end(ap);
    printf("\n");
}
#define LOAD(f) f##TYPE *f = (f##TYPE *)dlsym(h, #f); if (!f) return 2;
int main(int argc, char **argv) {
    (void)argc;
    void *h = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!h) { printf("dlopen: %s\n", dlerror()); return 1; }
    LOAD(fmi2Instantiate) LOAD(fmi2SetupExperiment) LOAD(fmi2EnterInitializationMode)
    LOAD(fmi2ExitInitializationMode) LOAD(fmi2DoStep) LOAD(fmi2GetReal) LOAD(fmi2SetReal)
    LOAD(fmi2GetInteger)
    LOAD(fmi2Terminate) LOAD(fmi2FreeInstance)
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("c", fmi2CoSimulation, argv[2], argv[3], &cb, fmi2False,
                                      fmi2True);
    if (!c) { printf("instantiate failed\n"); return 1; }
    fmi2SetupExperiment(c, fmi2False, 0.0, 0.5, fmi2False, 0.0);
    fmi2EnterInitializationMode(c);
    fmi2ValueReference vr[2] = {6, 7};  /* u0, v0 */
    fmi2Real x[2] = {-2.2, 0.0};
    fmi2SetReal(c, vr, 2, x);
    if (fmi2ExitInitializationMode(c) != fmi2OK) { printf("init failed\n"); return 1; }
    fmi2ValueReference out[2] = {13, 14};  /* u, v */
    fmi2ValueReference imp[1] = {15};  /* impacts */
    fmi2Real y[2];
    fmi2Integer n[1];
    for (int k = 0; k < 10; ++k) {
        if (fmi2DoStep(c, 0.5 + k, 1.0, fmi2True) != fmi2OK) { printf("step failed\n"); return 1; }
        fmi2GetReal(c, out, 2, y);
        fmi2GetInteger(c, imp, 1, n);
        printf("period %.17g %.17g %.17g %d\n", 1.5 + k, y[0], y[1], (int)n[0]);
    }
    fmi2GetReal(c, out, 2, y);
    printf("state %.17g %.17g\n", y[0], y[1]);
    fmi2Terminate(c);
    fmi2FreeInstance(c);
    return 0;
}
"""


def _c_importer(twin_fmu: Path, tmp_path: Path, cc: str) -> tuple[list[str], dict[str, str]]:
    """Compile the C importer and extract the twin: the command line that runs it, and the
    environment the README's old recipe gave a C host (libpython preloaded, PYTHONHOME,
    PYTHONPATH), which the twin no longer needs."""
    import sysconfig

    src, exe = tmp_path / "importer.c", tmp_path / "importer"
    src.write_text(_C_IMPORTER)
    subprocess.run([cc, "-O1", "-I", str(ROOT / "fmu_src" / "include" / "fmi2"), str(src),
                    "-o", str(exe), "-ldl"], check=True, capture_output=True)
    unzipdir = Path(extract(str(twin_fmu), unzipdir=str(tmp_path / "fmu")))
    guid = read_model_description(str(twin_fmu)).guid
    args = [str(exe), str(unzipdir / "binaries" / "linux64" / "ImpactOscillatorPy.so"), guid,
            (unzipdir / "resources").as_uri()]
    libpython = Path(sysconfig.get_config_var("LIBDIR")) / sysconfig.get_config_var("INSTSONAME")
    # PYTHONHOME: the embedded interpreter would otherwise look for its standard library next
    # to whichever "python3" comes first on PATH (here maybe a different installation).
    python_env = {"LD_PRELOAD": str(libpython), "PYTHONPATH": sysconfig.get_paths()["purelib"],
                  "PYTHONHOME": sys.base_prefix}
    return args, python_env


def _cc() -> str:
    import shutil

    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    return cc


def test_c_host_needs_no_python_environment(twin_fmu: Path, tmp_path: Path) -> None:
    """A C program that dlopens the twin, with no LD_PRELOAD, PYTHONHOME or PYTHONPATH and a
    PATH without the project's Python, runs it (the FMU's front loads the libpython and
    site-packages recorded at build time) and computes what fmpy gets in-process; the old
    recipe of the README (preload and both variables) still works."""
    args, python_env = _c_importer(twin_fmu, tmp_path, _cc())
    env = {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path)}
    states, outputs = [], []
    for extra in ({}, python_env):
        run = subprocess.run(args, env={**env, **extra}, capture_output=True, text=True,
                             timeout=120)
        assert run.returncode == 0, run.stdout + run.stderr
        assert "log 3" not in run.stdout and "log 4" not in run.stdout
        states.append([float(x) for x in run.stdout.split("state")[1].split()])
        outputs.append(run.stdout)

    s = Slave(twin_fmu)
    try:
        s.start(t0=0.5, u0=-2.2, v0=0.0)
        for k in range(10):  # the same communication points (CVODE stops at each)
            s.step_to(1.5 + k)
        for got in states:
            np.testing.assert_allclose(got, s.state(), rtol=0, atol=1e-12)
    finally:
        s.close()

    # per period against the closed form, at the FMU's default parameters
    start = {v.name: v.start for v in read_model_description(str(twin_fmu)).modelVariables}
    wall = {v: k for k, v in WALLS.items()}[int(start["wall"])]
    osc = ExactOscillator(float(start["nu"]), float(start["Omega"]), float(start["sigma"]),
                          r=float(start["r"]), Gamma=float(start["Gamma"]), wall=wall)
    rows = np.array([[float(x) for x in line.split()[1:]]
                     for line in outputs[0].splitlines() if line.startswith("period ")])
    exact, counts = osc.strobe(-2.2, 0.0, rows[:, 0], 0.5)
    assert counts[-1] > 0  # the run hits the wall
    np.testing.assert_array_equal(rows[:, 3], counts)
    np.testing.assert_allclose(rows[:, 1:3], exact, rtol=0, atol=1e-8)
    print("C driver vs closed form per period: u", np.abs(rows[:, 1] - exact[:, 0]).max(),
          "v", np.abs(rows[:, 2] - exact[:, 1]).max(), "impacts", int(counts[-1]))


@pytest.mark.parametrize(
    "key, value, expect",
    [
        ("libpython", "/nonexistent/libpython3.11.so.1.0", "cannot load the Python library"),
        ("site", "/nonexistent/site-packages", "No module named"),
    ],
)
def test_c_host_missing_python_is_an_fmi_error(twin_fmu: Path, tmp_path: Path, key: str,
                                               value: str, expect: str) -> None:
    """Without the recorded libpython, or without the packages, the C host gets fmi2Error
    (or a NULL instance) with the reason through its logger, and exits normally."""
    args, _ = _c_importer(twin_fmu, tmp_path, _cc())
    record = tmp_path / "fmu" / "resources" / "python_runtime.txt"
    lines = [f"{key}={value}" if line.startswith(key + "=") else line
             for line in record.read_text().splitlines()]
    record.write_text("\n".join(lines) + "\n")
    # no site-packages of the caller's either: an empty user base, no PYTHONPATH
    env = {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), "PYTHONNOUSERSITE": "1"}
    run = subprocess.run(args, env=env, capture_output=True, text=True, timeout=120)
    assert run.returncode == 1, run.stdout + run.stderr  # refused, not aborted or crashed
    errors = [line for line in run.stdout.splitlines() if line.startswith("log 3: ")]
    assert any(expect in line for line in errors), run.stdout + run.stderr
    assert "log 4" not in run.stdout


@pytest.mark.skipif(os.environ.get("IMPACT_VALGRIND") != "1",
                    reason="about 70 s under valgrind: set IMPACT_VALGRIND=1")
def test_c_importer_exit_has_no_use_after_free(twin_fmu: Path, tmp_path: Path) -> None:
    """pythonfmu 0.7's library destructor reads the freed PyState at exit in a C host too (an
    abort in about one fmusim run in sixty).  The twin registers pythonfmu's
    finalizePythonInterpreter as a C exit handler there (ImpactOscillatorPy
    ._guard_pythonfmu_exit); valgrind must show no invalid access in it.  (Python's own
    teardown under valgrind reports a read in scipy's _uarray module dealloc and the dynamic
    loader's rpath strncmp, both outside pythonfmu; they are not asserted on.)"""
    import shutil

    cc, vg = shutil.which("cc") or shutil.which("gcc"), shutil.which("valgrind")
    if cc is None or vg is None:
        pytest.skip("needs a C compiler and valgrind")
    args, python_env = _c_importer(twin_fmu, tmp_path, cc)
    env = {"PATH": "/usr/bin:/bin", "HOME": str(tmp_path), **python_env, "PYTHONMALLOC": "malloc"}
    run = subprocess.run([vg, "-q", *args], env=env, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0 and "state" in run.stdout, run.stdout[-2000:] + run.stderr[-2000:]
    blocks = run.stderr.split("==\n")
    bad = [b for b in blocks if "Invalid" in b and "finalizePythonInterpreter" in b]
    assert not bad, bad[0]
