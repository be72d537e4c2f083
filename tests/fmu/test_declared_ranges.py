"""The ranges and start values the modelDescription files declare are the ones the FMU enforces.

The FMU checks its values against a table in C (fmu_src/fmu_vars.c); the importer reads
min/max/start from modelDescription.xml (FMI 2.0) and modelDescription3.xml (FMI 3.0).  All three,
and the C defaults, are generated from one spec (fmu_src/variables.py; tests/fmu/test_generated.py
checks that they are up to date).  This test is the independent check of the result: it asks
the built binary, not the generator -- both files declare the same, every declared start is the
FMU's default, each bound is accepted and the next double (integer) beyond it is refused -- the
one documented exception is sigma's open lower bound, -1.
"""
from __future__ import annotations

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException

from tests.support.fmu import FMU3_PATH, FMU_PATH, LoggedSlave

MD2 = read_model_description(str(FMU_PATH))
MD3 = read_model_description(str(FMU3_PATH))
#: the settable variables with a declared range: parameters and inputs, Real or Integer
RANGED = [v for v in MD2.modelVariables
          if v.causality in ("parameter", "input") and v.type in ("Real", "Integer")
          and v.min is not None and v.max is not None]
#: bounds the FMU refuses although declared (an XML min/max cannot say "open"): README's table
OPEN_BOUNDS = {("sigma", "min")}


def _num(x: str | float | None) -> float | None:
    return None if x is None else float(x)


def test_fmi2_and_fmi3_declare_the_same_ranges_and_starts() -> None:
    three = {v.valueReference: v for v in MD3.modelVariables}
    assert len(RANGED) >= 16  # nu ... solver, the ports and the work bounds
    for v in MD2.modelVariables:
        w = three[v.valueReference]
        assert w.name == v.name and w.causality == v.causality, v.name
        for attr in ("min", "max", "start"):
            a, b = getattr(v, attr), getattr(w, attr)
            if v.type == "Boolean" and attr == "start":
                continue  # "false" in both, spelt by each standard's type
            assert _num(a) == _num(b), (v.name, attr, a, b)


@pytest.fixture(scope="module")
def fmu(module_fmu: LoggedSlave) -> LoggedSlave:
    return module_fmu


def _initializing(fmu: LoggedSlave) -> None:
    fmu.slave.reset()
    fmu.slave.setupExperiment(startTime=0.0)
    fmu.slave.enterInitializationMode()


def _value(fmu: LoggedSlave, v) -> float:
    if v.type == "Integer":
        return float(fmu.slave.getInteger([v.valueReference])[0])
    return fmu.get(v.name)


@pytest.mark.parametrize("v", RANGED, ids=[v.name for v in RANGED])
def test_declared_start_is_the_default_and_the_bounds_are_enforced(fmu, v) -> None:
    _initializing(fmu)
    assert _value(fmu, v) == float(v.start), "the declared start is not the FMU's default"
    integer = v.type == "Integer"
    for side, bound, outward in (("min", float(v.min), -np.inf), ("max", float(v.max), np.inf)):
        beyond = bound + (1 if outward > 0 else -1) if integer else float(np.nextafter(bound, outward))
        for x, accepted in ((bound, (v.name, side) not in OPEN_BOUNDS), (beyond, False)):
            _initializing(fmu)
            try:
                fmu.set(**{v.name: int(x) if integer else x})
                ok = True
            except FMICallException:
                ok = False
            assert ok == accepted, (v.name, side, x, fmu.errors()[-1:] if not ok else "accepted")
            if not ok:
                assert v.name in fmu.errors()[-1] and "rejected" in fmu.errors()[-1]
                assert _value(fmu, v) == float(v.start), "a refused value must leave the old one"
