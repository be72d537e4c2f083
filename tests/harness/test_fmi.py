"""The harness's FMI layer on the real FMU: checks of the FMU, instance reuse, parameter changes."""
from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
import pytest

from harness import FmuModel, FmuSimulator, HarnessInputError, MappingSimulator, strobe
from harness.dynamics.maps.sampling import sample_periods
from mapcheck.exact import ExactOscillator
from tests.support.fmu import harness_params as _params

FMU = Path(__file__).resolve().parents[2] / "build" / "fmu" / "ImpactOscillator.fmu"


def _rewritten_fmu(tmp_path: Path, edit) -> Path:
    """A copy of the real FMU whose modelDescription.xml is changed by ``edit``."""
    out = tmp_path / "edited.fmu"
    with zipfile.ZipFile(FMU) as src, zipfile.ZipFile(out, "w") as dst:
        for item in src.infolist():
            data = src.read(item.filename)
            if item.filename == "modelDescription.xml":
                data = edit(data.decode()).encode()
            dst.writestr(item, data)
    return out


def test_model_description_is_read_not_hard_coded(model: FmuModel) -> None:
    from fmpy import read_model_description

    md = read_model_description(str(FMU))
    for v in md.modelVariables:
        assert model.variables[v.name].value_reference == v.valueReference
    assert model.fmi_version == "2.0" and model.model_identifier == "ImpactOscillator"
    assert model.variables["sigma"].tunable and not model.variables["Gamma"].tunable
    assert len(model.sha256) == 64


def test_model_exchange_only_fmu_is_rejected(tmp_path: Path) -> None:
    import re

    def to_me(xml: str) -> str:
        # the element is empty, or holds the <SourceFiles> list of the FMU's sources
        return re.sub(r"<CoSimulation[^>]*?(/>|>.*?</CoSimulation>)", '<ModelExchange modelIdentifier="ImpactOscillator"/>',
                      xml, flags=re.S)

    with pytest.raises(HarnessInputError, match="not a Co-Simulation FMU") as err:
        FmuModel(_rewritten_fmu(tmp_path, to_me), argument="--fmu")
    assert err.value.argument == "--fmu"


def test_fmu_without_the_oscillator_variables_is_rejected(tmp_path: Path) -> None:
    path = _rewritten_fmu(tmp_path, lambda xml: xml.replace('name="impacts"', 'name="hits"'))
    with pytest.raises(HarnessInputError, match="lacks the oscillator variable.*'impacts'"):
        FmuModel(path)


@pytest.mark.parametrize("content, reason", [(None, "no such file"), (b"not a zip", "not an FMU")])
def test_missing_or_non_fmu_file(tmp_path: Path, content, reason) -> None:
    path = tmp_path / "x.fmu"
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(HarnessInputError, match=reason):
        FmuModel(path)


def test_unknown_and_unsettable_variables(model: FmuModel) -> None:
    with pytest.raises(HarnessInputError, match="unknown FMU variable 'sigmaa'"):
        model.check_settable("sigmaa", "--param")
    with pytest.raises(HarnessInputError, match="calculatedParameter"):
        model.check_settable("F_g")
    with pytest.raises(HarnessInputError, match="not a valid Integer"):
        model.coerce("wall", "soft")
    assert model.coerce("wall", "rigid") == 2 and model.coerce("wall", 1.0) == 1


def test_one_instance_reused_with_reset_gives_identical_runs(model: FmuModel) -> None:
    """reset + re-initialization must leave no trace of the previous run (bit for bit)."""
    sim = FmuSimulator(model.source())
    a1 = strobe(sim, _params(model, sigma=0.5), (-1.0, 0.0), theta=0.3, n_transient=20, n_samples=10)
    strobe(sim, _params(model, sigma=0.18, Gamma=100.0), (0.0, 1.0), theta=0.7, n_transient=30, n_samples=5)
    a2 = strobe(sim, _params(model, sigma=0.5), (-1.0, 0.0), theta=0.3, n_transient=20, n_samples=10)
    fresh = FmuSimulator(model.source(), instance_name="fresh")
    a3 = strobe(fresh, _params(model, sigma=0.5), (-1.0, 0.0), theta=0.3, n_transient=20, n_samples=10)
    for other in (a2, a3):
        np.testing.assert_array_equal(a1.u, other.u)
        np.testing.assert_array_equal(a1.v, other.v)
        np.testing.assert_array_equal(a1.impacts, other.impacts)
    assert a1.impacts.sum() > 0


def test_non_tunable_change_restarts_from_the_current_state(model: FmuModel) -> None:
    """Gamma is fixed in the FMU: the harness restarts from the carried state; the result is
    the oracle's continuation with the new Gamma, and the impact counter keeps counting."""
    sim = FmuSimulator(model.source())
    p = _params(model, sigma=0.5)
    sim.start(p, 0.4, (-0.2, 0.5))
    first = sample_periods(sim, 0, 6)
    sim.set_parameter("Gamma", 100.0)
    second = sample_periods(sim, 0, 6)
    assert sim.restarts == 1
    _, _, total = sim.read()
    assert total == first.impacts.sum() + second.impacts.sum() and second.impacts.sum() > 0
    oracle = ExactOscillator(p["nu"], p["Omega"], 0.5, r=p["r"], Gamma=100.0, wall="compliant")
    states, _ = oracle.strobe(first.u[-1], first.v[-1], second.t, t0=first.t[-1])
    np.testing.assert_allclose(second.u, states[:, 0], atol=1e-8)
    np.testing.assert_allclose(second.v, states[:, 1], atol=1e-8)


def test_mapping_simulator_runs_a_user_map() -> None:
    def halve(u, v, t, params):
        return params["a"] * u, v, int(u > 0)

    sim = MappingSimulator(halve, {"a": 0.5})
    r = strobe(sim, {}, (8.0, 1.0), theta=0.0, n_transient=1, n_samples=3)
    np.testing.assert_array_equal(r.u, [2.0, 1.0, 0.5])
    np.testing.assert_array_equal(r.impacts, [1, 1, 1])
    with pytest.raises(HarnessInputError, match="whole periods"):
        sim.advance(sim.time + 0.5)


OTHER_BUILDS = {
    "fmi3": FMU.with_name("ImpactOscillator_fmi3.fmu"),   # FMI 3.0 build of the same C model
    "pythonfmu-twin": FMU.with_name("ImpactOscillatorPy.fmu"),  # the same model in Python
}


@pytest.mark.parametrize("build", sorted(OTHER_BUILDS))
def test_other_builds_with_the_same_variables_give_the_same_map(model: FmuModel, build: str) -> None:
    """Any Co-Simulation FMU with the oscillator's variable names is driven the same way: the
    FMI version is read from the modelDescription and the matching slave class is used."""
    path = OTHER_BUILDS[build]
    if not path.is_file():
        pytest.skip(f"{path.name} not built (scripts/setup.sh builds it when its sources exist)")
    other = FmuModel(path)
    n = 3 if build == "pythonfmu-twin" else 20  # the Python twin takes ~0.1 s per period
    runs = []
    for m in (model, other):
        sim = FmuSimulator(m.source(), instance_name=build)
        runs.append(strobe(sim, _params(m, sigma=0.5), (-1.0, 0.3), theta=0.37, n_transient=0, n_samples=n))
        again = strobe(sim, _params(m, sigma=0.5), (-1.0, 0.3), theta=0.37, n_transient=0, n_samples=n)
        np.testing.assert_array_equal(runs[-1].u, again.u)  # reset between runs, on every build
    np.testing.assert_allclose(runs[1].u, runs[0].u, atol=1e-8)
    np.testing.assert_allclose(runs[1].v, runs[0].v, atol=1e-8)
    np.testing.assert_array_equal(runs[1].impacts, runs[0].impacts)
    assert runs[0].impacts.sum() > 0


def test_benchmark_runs_the_bare_loop_and_the_harness_on_the_same_orbit() -> None:
    from harness.runs.benchmark import measure

    r = measure(str(FMU), periods=40, repeat=1)
    assert r["bare_s_per_period"] > 0 and r["harness_s_per_period"] > 0
    # the comparison is fair only if both loops compute the very same thing
    assert r["same_orbit"] is True


def test_rejected_initialization_is_reported_and_the_instance_recovers(model: FmuModel) -> None:
    """A start inside the rigid wall is refused by the FMU: the error quotes the FMU's own log
    message, and the same instance then runs the next (valid) start normally."""
    from harness.errors import FmuRejectedInput

    sim = FmuSimulator(model.source())
    with pytest.raises(FmuRejectedInput, match="rigid wall"):
        strobe(sim, _params(model, wall=2), (0.01, 0.0), theta=0.0, n_transient=0, n_samples=2)
    good = strobe(sim, _params(model, wall=2, sigma=8.0), (-1.0, 0.3), theta=0.37, n_transient=0, n_samples=5)
    fresh = strobe(FmuSimulator(model.source(), instance_name="other"), _params(model, wall=2, sigma=8.0),
                   (-1.0, 0.3), theta=0.37, n_transient=0, n_samples=5)
    np.testing.assert_array_equal(good.u, fresh.u)


def test_one_reused_instance_per_worker_thread(model: FmuModel) -> None:
    """Sweep tasks get this thread's instance (created once, then only reset); another
    thread gets its own (an FMI instance must not be shared between threads)."""
    import threading

    from harness.fmu.simulator import simulator_for

    first = simulator_for(model.source())
    assert simulator_for(model.source()) is first
    box: list = []
    t = threading.Thread(target=lambda: box.append(simulator_for(model.source())))
    t.start()
    t.join()
    assert box and box[0] is not first
