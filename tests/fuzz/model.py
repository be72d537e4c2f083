"""Where the FMU binaries are and what variables they have (read from modelDescription.xml)."""
from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import fmpy

ROOT = Path(__file__).resolve().parents[2]


@dataclass(frozen=True)
class Variable:
    """One model variable: value reference, FMI type class, causality and start value."""

    name: str
    vr: int
    kind: str  # "real", "int" or "bool"
    causality: str
    variability: str
    start: float | None


@dataclass(frozen=True)
class Description:
    """What the fuzzer needs of one FMU: its binary, token and variables."""

    version: int  # 2 or 3
    library: Path
    token: str
    variables: tuple[Variable, ...]
    n_states: int
    n_indicators: int

    def of_kind(self, kind: str) -> list[Variable]:
        return [v for v in self.variables if v.kind == kind]


_KINDS = {"Real": "real", "Float64": "real", "Integer": "int", "Int32": "int", "Boolean": "bool"}


def _parse(xml: Path, version: int, library: Path) -> Description:
    root = ET.parse(xml).getroot()
    variables = []
    if version == 2:
        token = root.get("guid", "")
        for sv in root.iter("ScalarVariable"):
            child = next((c for c in sv if c.tag in _KINDS), None)
            if child is None:
                continue
            start = child.get("start")
            variables.append(Variable(sv.get("name", ""), int(sv.get("valueReference", "0")),
                                      _KINDS[child.tag], sv.get("causality", "local"),
                                      sv.get("variability", "continuous"),
                                      float(start) if start not in (None, "true", "false") else None))
        n_ind = int(root.get("numberOfEventIndicators", "0"))
        der = root.find("ModelStructure/Derivatives")
        n_states = 0 if der is None else len(list(der))
    else:
        token = root.get("instantiationToken", "")
        mv = root.find("ModelVariables")
        for el in [] if mv is None else mv:
            if el.tag not in _KINDS:
                continue
            start = el.get("start")
            variables.append(Variable(el.get("name", ""), int(el.get("valueReference", "0")),
                                      _KINDS[el.tag], el.get("causality", "local"),
                                      el.get("variability", "continuous"),
                                      float(start) if start not in (None, "true", "false") else None))
        ms = root.find("ModelStructure")
        n_states = 0 if ms is None else len(ms.findall("ContinuousStateDerivative"))
        n_ind = 0 if ms is None else len(ms.findall("EventIndicator"))
    return Description(version, library, token, tuple(variables), n_states, n_ind)


def describe(build: Path, version: int) -> Description:
    """The FMI 2.0 (`version` 2) or 3.0 binary of a CMake build directory such as build/asan."""
    sub = build / ("fmu" if version == 2 else "fmu3")
    # the build machine's own binary (build/fmu also holds the other platforms' for packaging)
    own = fmpy.platform if version == 2 else fmpy.platform_tuple
    libs = sorted((sub / "binaries").glob(f"{own}/*.so")) or sorted((sub / "binaries").glob("*/*.so"))
    if not libs:
        raise FileNotFoundError(f"no FMU binary under {sub}/binaries (build it first)")
    src = ROOT / "fmu_src" / ("modelDescription.xml" if version == 2 else "modelDescription3.xml")
    xml = sub / "modelDescription.xml"
    return _parse(xml if xml.is_file() else src, version, libs[0])
