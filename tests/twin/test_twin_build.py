"""The pythonfmu twin (build/fmu/ImpactOscillatorPy.fmu): its build, its interface, and its
answer to bad input.

* Build and interface: the one build command writes an FMU that ``fmpy validate`` accepts and
  whose variables (names, value references, types, causality, variability, initial, start,
  bounds) are exactly the C FMU's, so the harness drives either unchanged.
* Bad parameters: rejected with a message naming the variable, and the instance stays usable
  (pythonfmu reports any Python exception as fmi2Fatal; the twin keeps the instance alive).
* A Python importer's exit: the guard against pythonfmu's use after free.

Against the C FMU through the harness: tests/twin/test_twin_cross_check.py; against the closed
form: tests/twin/test_twin_closed_form.py; from a C host: tests/twin/test_twin_c_host.py.
"""
from __future__ import annotations

import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from tests.support.twin import FIG9, ROOT, TWIN_SRC, Slave


# ---------------------------------------------------------------------------------------------
# build and interface
# ---------------------------------------------------------------------------------------------
def test_build_command_writes_a_valid_fmu(tmp_path: Path) -> None:
    """The README's build command, run as the set-up script runs it, gives an FMU that fmpy's
    validator accepts (pythonfmu alone would leave InitialUnknowns empty and fail it)."""
    out = tmp_path / "ImpactOscillatorPy.fmu"
    proc = subprocess.run([sys.executable, str(TWIN_SRC / "build.py"), "--out", str(out)],
                          cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert validate_fmu(str(out)) == []
    with zipfile.ZipFile(out) as z:
        names = set(z.namelist())
        md = ET.fromstring(z.read("modelDescription.xml"))
    assert {"binaries/linux64/ImpactOscillatorPy.so", "resources/ImpactOscillatorPy.py",
            "resources/impact_twin_model.py", "resources/slavemodule.txt"} <= names
    assert len(md.findall("ModelStructure/InitialUnknowns/Unknown")) == 7


#: The variables of the oscillator FMU, in value-reference order.
ISSUE_VARIABLES = ["nu", "Omega", "sigma", "r", "Gamma", "wall", "u0", "v0", "rtol", "atol",
                   "F_g", "phi", "kappa", "u", "v", "impacts", "in_contact"]


def _variables(path: Path) -> dict[str, dict]:
    md = read_model_description(str(path))
    return {
        v.name: dict(vr=v.valueReference, type=v.type, causality=v.causality,
                     variability=v.variability, initial=v.initial,
                     start=None if v.start is None or v.type == "Boolean" else float(v.start),
                     min=v.min, max=v.max, unit=v.unit)
        for v in md.modelVariables
    }


def test_interface_is_the_c_fmus(twin_fmu: Path, c_fmu: Path) -> None:
    """The twin's variables are the oscillator's, each with the C FMU's value reference, type,
    causality, variability, initial, start value, bounds and unit: the harness sees no
    difference.  (Descriptions are documentation and may differ where the C FMU documents
    features the twin does not have.)  Variables the C FMU has beyond these (it grows: Model
    Exchange, other contact laws) are not required of the twin."""
    twin_vars, c_vars = _variables(twin_fmu), _variables(c_fmu)
    assert list(twin_vars) == ISSUE_VARIABLES
    for name in ISSUE_VARIABLES:
        assert twin_vars[name] == c_vars[name], name
    # the InitialUnknowns of these variables, with their dependencies, too
    deps = []
    for path in (twin_fmu, c_fmu):
        md = read_model_description(str(path))
        # (dependencies on the C FMU's ports, which the twin lacks, are left out)
        deps.append({u.variable.name: sorted(d.name for d in (u.dependencies or [])
                                             if d.name in ISSUE_VARIABLES)
                     for u in md.initialUnknowns if u.variable.name in ISSUE_VARIABLES})
    assert deps[0] == deps[1]


# ---------------------------------------------------------------------------------------------
# bad input
# ---------------------------------------------------------------------------------------------
BAD = [
    (dict(r=1.5), "r"),
    (dict(r=-0.1), "r"),
    (dict(wall="compliant", Gamma=0.0), "Gamma"),
    (dict(Omega=0.0), "Omega"),
    (dict(nu=-1.0), "nu"),
    (dict(sigma=float("nan")), "sigma"),
    (dict(u0=float("inf")), "u0"),
    (dict(wall=3), "wall"),
    (dict(wall="rigid", u0=0.1), "u0"),
]


@pytest.mark.parametrize("params,name", BAD, ids=[b[1] + str(i) for i, b in enumerate(BAD)])
def test_bad_parameters_are_rejected_and_the_instance_survives(twin_fmu, c_fmu, params,
                                                              name) -> None:
    """A bad value stops initialisation with the C FMU's message, naming the variable.
    pythonfmu maps any Python exception to fmi2Fatal (it cannot return fmi2Error), and the same
    instance must still run a good case after fmi2Reset, as the harness reuses instances."""
    messages = {}
    for path in (twin_fmu, c_fmu):
        s = Slave(path, logging=True)
        try:
            with pytest.raises(FMICallException) as info:
                s.start(**params)
            assert info.value.status >= 3  # fmi2Error (C) or fmi2Fatal (pythonfmu)
            messages[path] = [m for st, cat, m in s.messages
                              if st >= 3 and cat == "logStatusError"]
            s.start(t0=0.0, sigma=0.5, **FIG9)
            s.step_to(1.0)
            assert np.all(np.isfinite(s.state()))
        finally:
            s.close()
    assert messages[twin_fmu] and messages[twin_fmu][0].split(": ", 1)[1].startswith(name)
    assert messages[twin_fmu][0] == messages[c_fmu][0]


def test_only_sigma_is_tunable_after_initialisation(twin_fmu, c_fmu) -> None:
    """After initialisation sigma may change, a fixed parameter may not: the same message as
    the C FMU's, with fmi2Error (not Fatal), and up to the refusal the same run."""
    messages, states, statuses = {}, {}, {}
    for path in (twin_fmu, c_fmu):
        s = Slave(path, logging=True)
        try:
            s.start(t0=0.0, **FIG9)
            s.step_to(1.0)
            s.set(sigma=0.3)  # tunable: accepted
            s.step_to(2.0)
            states[path] = s.state()
            with pytest.raises(FMICallException) as refused:
                s.set(r=0.5)
            statuses[path] = refused.value.status
            messages[path] = [m for st, _, m in s.messages if st >= 3][:1]
        finally:
            s.close()
    assert "only sigma is tunable" in messages[twin_fmu][0]
    assert messages[twin_fmu] == messages[c_fmu]
    assert statuses[twin_fmu] == statuses[c_fmu] == 3  # fmi2Error
    np.testing.assert_array_equal(states[twin_fmu], states[c_fmu])


def test_exit_guard_against_pythonfmu_use_after_free(twin_fmu: Path, tmp_path: Path) -> None:
    """pythonfmu 0.7's binary writes into freed memory at process exit (see
    ImpactOscillatorPy._guard_pythonfmu_exit; found with valgrind, an abort in about one pytest
    process in twenty).  In a Python importer the twin must register one atexit handler per
    loaded copy of its binary, and the process must exit cleanly."""
    script = f"""
import atexit, sys
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
md = read_model_description({str(twin_fmu)!r})
before = atexit._ncallbacks()
for copy in range(2):  # two extractions: two loaded copies of the binary
    d = extract({str(twin_fmu)!r})
    for _ in range(2):  # two instances of one copy: one handler for that copy
        s = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier="ImpactOscillatorPy",
                      instanceName="exit")
        s.instantiate()
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        s.exitInitializationMode()
        s.doStep(0.0, 1.0)
        s.terminate()
        s.fmi2FreeInstance(s.component)  # the library stays loaded, as in a harness worker
print("guarded", len(sys.modules["ImpactOscillatorPy"]._EXIT_GUARDED),
      "handlers", atexit._ncallbacks() - before)
"""
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=120, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr[-2000:]
    guarded, handlers = (int(x) for x in proc.stdout.split()[1::2])
    assert guarded == 2 and handlers >= 2, proc.stdout
