"""The FMI 2.0 FMU in libcosim (PyPI ``libcosimpy``, the Open Simulation Platform's master), an
importer no one here wrote, against the closed form once per forcing period.

- alone: libcosim's fixed-step algorithm at h = 0.01 (steps in integer nanoseconds), over- and
  underdamped, compliant and rigid walls;
- in an SSP loaded by libcosim's own SSP loader: the AFM loop of examples/afm (SSP 1.0 written
  by ``masters.write_ssp``), where the C controller FMU (build/afm/AmplitudeController.fmu) is
  the source that drives the oscillator's ``u_wall`` input. The oscillator is compared with the
  closed form under the wall positions it was given (observed on its input, held over each
  step), and the controller's output with the project's exact loop reference.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description

from examples.afm import masters as M
from examples.afm.monolithic import Controller, Oscillator, simulate
from tests.support.fmu import FMU_PATH, ROOT
from tests.support.importers import (CS_TOL, Case, PeriodCheck, compare_per_period,
                                    merge_holds)
from tests.importers.test_fmusim import CASES

pytest.importorskip("libcosimpy", reason="libcosimpy is a dev extra: pip install -e '.[dev]'")
from libcosimpy.CosimExecution import CosimExecution  # noqa: E402
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level  # noqa: E402
from libcosimpy.CosimObserver import CosimObserver  # noqa: E402
from libcosimpy.CosimSlave import CosimLocalSlave  # noqa: E402

CTRL_FMU = ROOT / "build" / "afm" / "AmplitudeController.fmu"
NS = 10 ** 9  # libcosim's time unit is the nanosecond
H_NS = 10_000_000  # h = 0.01
STEPS_PER_PERIOD = NS // H_NS
SSP_PERIODS = 12
log_output_level(CosimLogLevel.WARNING)


def _refs(fmu: Path) -> dict[str, tuple[int, str]]:
    return {v.name: (v.valueReference, v.type)
            for v in read_model_description(str(fmu)).modelVariables}


def _set_start(ex: CosimExecution, index: int, refs: dict, values: dict[str, float]) -> None:
    for name, x in values.items():
        vr, kind = refs[name]
        if kind == "Integer":
            ex.integer_initial_value(index, vr, int(x))
        else:
            ex.real_initial_value(index, vr, float(x))


class _Recorder:
    """The oscillator's u, v, impacts, t_impact (and its u_wall input) after each step."""

    def __init__(self, ex: CosimExecution, index: int, refs: dict):
        self.obs = CosimObserver.create_last_value()
        ex.add_observer(self.obs)
        self.ex, self.i = ex, index
        self.real = [refs[k][0] for k in ("u", "v", "t_impact", "u_wall")]
        self.int = [refs["impacts"][0]]
        self.rows: list[tuple[float, ...]] = []

    def step(self, n: int = 1) -> None:
        self.ex.step(n)
        t = self.ex.status().current_time / NS
        self.rows.append((t, *self.obs.last_real_values(self.i, self.real),
                          *self.obs.last_integer_values(self.i, self.int)))

    def columns(self) -> dict[str, np.ndarray]:
        a = np.array(self.rows)
        return dict(zip(("time", "u", "v", "t_impact", "u_wall", "impacts"), a.T))


def run_alone(case: Case) -> PeriodCheck:
    """The FMU alone in libcosim for 10 periods, compared per period."""
    ex = CosimExecution.from_step_size(H_NS)
    refs = _refs(FMU_PATH)
    i = ex.add_local_slave(CosimLocalSlave(fmu_path=str(FMU_PATH), instance_name="osc"))
    _set_start(ex, i, refs, case.start_values())
    rec = _Recorder(ex, i, refs)
    for _ in range(10):
        rec.step(STEPS_PER_PERIOD)
    r = rec.columns()
    return compare_per_period(r["time"], r["u"], r["v"], r["impacts"], r["t_impact"], case,
                              [(0.0, 0.0, 0.0)], 10)


@pytest.mark.parametrize("name", CASES)
def test_fmu_alone_per_period(name: str) -> None:
    case: Case = CASES[name]
    chk = run_alone(case)
    assert chk.err_u <= CS_TOL and chk.err_v <= CS_TOL * max(1.0, case.Omega), chk
    assert chk.impacts == chk.impacts_exact > 0


def run_ssp(tmp_path: Path) -> tuple[PeriodCheck, dict[str, np.ndarray], list]:
    """The closed loop of examples/afm from libcosim's SSP loader, 12 periods at h = 0.01:
    the per-period check, the recorded columns, the wall holds."""
    osc, ctrl, periods = Oscillator(), Controller(), SSP_PERIODS
    ssp = M.write_ssp(tmp_path / "afm.ssp", FMU_PATH, CTRL_FMU, feedback=True)
    ex = CosimExecution.from_ssp_file(str(ssp), step_size=H_NS)
    refs = {M.OSC: _refs(FMU_PATH), M.CTRL: _refs(CTRL_FMU)}
    index = {inst: ex.slave_index_from_instance_name(inst) for inst in refs}
    values = M.start_values(osc, ctrl, osc.sigma, 0.0)
    for inst in refs:
        _set_start(ex, index[inst], refs[inst],
                   {k.split(".", 1)[1]: x for k, x in values.items() if k.startswith(inst + ".")})
    rec = _Recorder(ex, index[M.OSC], refs[M.OSC])
    for _ in range(periods * STEPS_PER_PERIOD):
        rec.step()
    r = rec.columns()
    # the wall the oscillator was given over each step (its input, seen after the step)
    starts = np.concatenate([[0.0], r["time"][:-1]])
    holds = merge_holds([(float(t), 0.0, float(w)) for t, w in zip(starts, r["u_wall"])])
    case = Case(nu=osc.nu, Omega=osc.Omega, sigma=osc.sigma, wall="compliant",
                Gamma=osc.Gamma, r=osc.r, u0=osc.sigma, v0=0.0)
    chk = compare_per_period(r["time"], r["u"], r["v"], r["impacts"], r["t_impact"], case,
                             holds, periods)
    return chk, r, holds


def test_ssp_with_a_source_fmu_driving_the_wall(tmp_path: Path) -> None:
    osc, ctrl, periods = Oscillator(), Controller(), SSP_PERIODS
    chk, r, holds = run_ssp(tmp_path)
    assert len(holds) >= 5  # the controller moved the wall at several window ends
    assert chk.err_u <= CS_TOL and chk.err_v <= CS_TOL * osc.Omega, chk
    assert chk.impacts == chk.impacts_exact > 0
    # the source's law: the wall positions are the exact loop reference's (Jacobi schedule)
    ref = simulate(osc, ctrl, 0.0, float(periods), 0.01, osc.sigma, 0.0, feedback=True)
    np.testing.assert_allclose(r["u_wall"], ref.u_wall[:-1], rtol=0, atol=1e-10)
