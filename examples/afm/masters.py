"""The AFM loop in three co-simulation masters: ecos (ecospy), fmpy's SSP loop, fmpy's Container FMU.

Each ``run_*`` function takes the two FMUs, the parameters (``monolithic.Oscillator`` and
``monolithic.Controller``), the start state and the grid, and returns a ``Trace``: the values at
the communication points t_k (after the step that ends at t_k), k = 1..n.  All three masters
are Jacobi (every FMU steps from t_k with the inputs of t_k; the connections are updated
after all steps); ecos and the SSP loop compute t_{k+1} = t_k + h by summing, the Container
FMU gives its components t0 + k h (a few ulps apart: the FMU's results do not depend on it).

``feedback=False`` leaves the controller's u_wall unconnected (the wall stays at the FMU's
default u_wall = 0): the controller only measures.
"""
from __future__ import annotations

import math
import shutil
import tempfile
import zipfile
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from .monolithic import Controller, Oscillator

OSC = "cantilever"      # instance names in every master
CTRL = "controller"
RECORDED = [(OSC, "u"), (OSC, "v"), (CTRL, "u_wall"), (CTRL, "amplitude")]


@dataclass
class Trace:
    """Values at the communication points t_k, k = 1..n."""

    t: np.ndarray
    u: np.ndarray
    v: np.ndarray
    u_wall: np.ndarray
    amplitude: np.ndarray


def start_values(osc: Oscillator, ctrl: Controller, u0: float, v0: float) -> dict[str, float]:
    """Start values of both FMUs, keyed ``instance.variable``: the oscillator's compliant
    wall (wall = 1) and start state, the controller's parameters."""
    values: dict[str, float] = {f"{OSC}.{k}": float(x) for k, x in asdict(osc).items()}
    values.update({f"{OSC}.u0": float(u0), f"{OSC}.v0": float(v0)})
    values.update({f"{CTRL}.{k}": float(x) for k, x in asdict(ctrl).items()})
    return values


def connections(feedback: bool) -> list[tuple[str, str, str, str]]:
    """(from instance, output, to instance, input)."""
    c = [(OSC, "u", CTRL, "u")]
    if feedback:
        c.append((CTRL, "u_wall", OSC, "u_wall"))
    return c


# ------------------------------------------------------------------------------- SSP (fmpy)
_SSD = """<?xml version="1.0" encoding="UTF-8"?>
<ssd:SystemStructureDescription version="1.0" name="AFM"
  xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon"
  xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription">
  <ssd:System name="AFM" description="tapping-mode AFM: cantilever tapping a compliant sample, PI z-feedback">
    <ssd:Elements>
      <ssd:Component name="{osc}" source="resources/{osc_fmu}" type="application/x-fmu-sharedlibrary">
        <ssd:Connectors>
{osc_inputs}          <ssd:Connector name="u" kind="output"><ssc:Real/></ssd:Connector>
          <ssd:Connector name="v" kind="output"><ssc:Real/></ssd:Connector>
        </ssd:Connectors>
      </ssd:Component>
      <ssd:Component name="{ctrl}" source="resources/{ctrl_fmu}" type="application/x-fmu-sharedlibrary">
        <ssd:Connectors>
          <ssd:Connector name="u" kind="input"><ssc:Real/></ssd:Connector>
          <ssd:Connector name="u_wall" kind="output"><ssc:Real/></ssd:Connector>
          <ssd:Connector name="amplitude" kind="output"><ssc:Real/></ssd:Connector>
        </ssd:Connectors>
      </ssd:Component>
    </ssd:Elements>
    <ssd:Connections>
{connections}
    </ssd:Connections>
  </ssd:System>
  <ssd:DefaultExperiment startTime="0" stopTime="60"/>
</ssd:SystemStructureDescription>
"""


def write_ssp(path: Path, osc_fmu: Path, ctrl_fmu: Path, feedback: bool = True) -> Path:
    """An SSP 1.0 archive: SystemStructure.ssd and both FMUs under resources/.

    The parameters are not bound in the SSD: fmpy's ``simulate_ssp`` ignores parameter
    bindings and takes a ``ParameterSet`` argument instead (``ssp_parameter_set``).
    """
    lines = "\n".join(
        f'      <ssd:Connection startElement="{a}" startConnector="{x}" endElement="{b}" '
        f'endConnector="{y}"/>' for a, x, b, y in connections(feedback))
    # fmpy's SSP loop needs every input connector connected: u_wall only with feedback
    osc_inputs = ('          <ssd:Connector name="u_wall" kind="input"><ssc:Real/></ssd:Connector>\n'
                  if feedback else "")
    ssd = _SSD.format(osc=OSC, ctrl=CTRL, osc_inputs=osc_inputs, osc_fmu=Path(osc_fmu).name,
                      ctrl_fmu=Path(ctrl_fmu).name, connections=lines)
    path = Path(path)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("SystemStructure.ssd", ssd)
        z.write(osc_fmu, f"resources/{Path(osc_fmu).name}")
        z.write(ctrl_fmu, f"resources/{Path(ctrl_fmu).name}")
    return path


def run_fmpy_ssp(ssp: Path, values: dict[str, float], t1: float, h: float) -> Trace:
    """fmpy.ssp.simulate_ssp on the grid t += h from 0.

    fmpy labels each row with the step's *start* time but stores the outputs after the step,
    so the row at time t holds the values at t + h (corrected here).  Before the first step
    fmpy sets every connected input to 0.0, not to the other FMU's initial output; the
    controller ignores its first partial window and the wall starts at 0 anyway.
    """
    from fmpy.ssp.simulation import simulate_ssp
    from fmpy.ssp.ssd import Parameter, ParameterSet

    params = ParameterSet(parameters=[Parameter(name=k, type="Real", value=x)
                                      for k, x in values.items() if not k.endswith(".wall")])
    res = simulate_ssp(str(ssp), stop_time=t1, step_size=h, parameter_set=params)
    # fmpy loops "while time < stop_time" with summed time: one extra step when the sum
    # falls short of t1 by rounding; keep the first n
    res = res[:int(round(t1 / h))]
    t = res["time"] + h  # see the docstring
    return Trace(t, res[f"{OSC}.u"], res[f"{OSC}.v"], res[f"{CTRL}.u_wall"],
                 res[f"{CTRL}.amplitude"])


# ------------------------------------------------------------------------------------- ecos
def run_ecos(osc_fmu: Path, ctrl_fmu: Path, values: dict[str, float], t1: float, h: float,
             feedback: bool = True) -> Trace:
    """ecos's fixed-step (Jacobi) algorithm through ecospy, one ``step()`` per sample."""
    from ecospy import EcosLib, EcosSimulation, EcosSimulationStructure

    EcosLib.set_log_level("warn")
    n = int(round(t1 / h))
    out = np.empty((n, 5))
    with EcosSimulationStructure() as ss:
        ss.add_model(OSC, str(osc_fmu))
        ss.add_model(CTRL, str(ctrl_fmu))
        for a, x, b, y in connections(feedback):
            ss.make_real_connection(f"{a}::{x}", f"{b}::{y}")
        ss.add_parameter_set("init", {k.replace(".", "::", 1): v for k, v in values.items()})
        with EcosSimulation(structure=ss, step_size=h) as sim:
            sim.init(parameter_set="init")
            for k in range(n):
                out[k, 0] = sim.step()
                out[k, 1:] = [sim.get_real(f"{i}::{name}") for i, name in RECORDED]
            sim.terminate()
    return Trace(*out.T)


# ---------------------------------------------------------------------- Container FMU (fmpy)
#: FMI 3.0 type names of a component's variables -> the FMI 2.0 container's
_FMI2_TYPE = {"Float64": "Real", "Int32": "Integer"}


def build_container(path: Path, osc_fmu: Path, ctrl_fmu: Path, values: dict[str, float],
                    h: float, feedback: bool = True) -> Path:
    """An FMI 2.0 Container FMU (fmpy.container_fmu) holding both FMUs, fixed step h.

    Every start value becomes a container parameter mapped to its FMU's variable; the
    recorded variables become container outputs.
    """
    from fmpy import read_model_description
    from fmpy.container_fmu.cli import create_container_fmu
    from fmpy.container_fmu.config import Component, Configuration, Connection
    from fmpy.model_description import CoSimulation, DefaultExperiment, ModelDescription, ModelVariable

    comps, mvars = {}, {}
    for name, fmu in ((OSC, osc_fmu), (CTRL, ctrl_fmu)):
        md = read_model_description(str(fmu))
        comps[name] = Component(name=name, filename=Path(fmu), modelDescription=md)
        mvars[name] = {v.name: v for v in md.modelVariables}
    variables = [ModelVariable(type="Real", variability="continuous", causality="independent",
                               name="time")]
    mappings = {}
    for key, x in values.items():
        inst, name = key.split(".", 1)
        inner = mvars[inst][name]
        typ = _FMI2_TYPE.get(inner.type, inner.type)  # the container is FMI 2.0
        mv = ModelVariable(type=typ, variability=inner.variability, causality="parameter",
                           initial="exact", name=key,
                           start=str(int(x)) if typ == "Integer" else repr(float(x)))
        variables.append(mv)
        mappings[mv] = [(comps[inst], inner)]
    for inst, name in RECORDED:
        mv = ModelVariable(type="Real", variability="continuous" if inst == OSC else "discrete",
                           causality="output", initial="calculated", name=f"{inst}.{name}")
        variables.append(mv)
        mappings[mv] = [(comps[inst], mvars[inst][name])]
    md = ModelDescription(fmiVersion="2.0", modelName="AFM", instantiationToken="",
                          defaultExperiment=DefaultExperiment(stopTime="60", stepSize=str(h)),
                          coSimulation=CoSimulation(fixedInternalStepSize=h),
                          modelVariables=variables)
    conns = [Connection(comps[a], [mvars[a][x]], comps[b], [mvars[b][y]])
             for a, x, b, y in connections(feedback)]
    config = Configuration(parallelDoStep=False, modelDescription=md,
                           components=list(comps.values()), connections=conns,
                           variableMappings=mappings)
    work = Path(tempfile.mkdtemp(prefix="afm_container_"))
    try:
        (work / "unzip").mkdir()  # create_container_fmu empties it first
        create_container_fmu(config, work / "unzip", work / "AFM.fmu")
        _fix_connection_types(work / "AFM.fmu", Path(path))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return Path(path)


def _fix_connection_types(src: Path, dst: Path) -> None:
    """Copy the Container FMU, writing FMI 3 type names into its connections.

    fmpy 0.3.32's ``write_configuration`` maps the *variables'* FMI 2 type "Real" to "Float64"
    but writes the *connections'* type as the FMI 2 name, which the container binary rejects
    at instantiation ("unknown variant `Real`").  (It also packs a stray Container.zip into
    the FMU; dropped here.)
    """
    import json

    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as zout:
        for item in zin.infolist():
            if item.filename == "Container.zip":
                continue
            data = zin.read(item.filename)
            if item.filename == "resources/container.json":
                conf = json.loads(data)
                for c in conf["connections"]:
                    c["variableType"] = {"Real": "Float64", "Integer": "Int32"}.get(
                        c["variableType"], c["variableType"])
                data = json.dumps(conf, indent=1).encode()
            zout.writestr(item, data)


def run_container(container: Path, t1: float, h: float) -> Trace:
    """fmpy.simulate_fmu on the Container FMU, one output row per container step."""
    from fmpy import simulate_fmu

    names = [f"{i}.{n}" for i, n in RECORDED]
    res = simulate_fmu(str(container), stop_time=t1, step_size=h, output_interval=h,
                       output=names)
    res = res[1:]  # the first row is the start time
    return Trace(res["time"], *(res[n] for n in names))
