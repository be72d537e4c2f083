"""The FMU's wall input u_wall set to a new value between steps (a jump): the rule of
model.c's model_input_jump in Co-Simulation, and the same rule as an event in Model Exchange.

Independent truth: the closed form (mapcheck.exact.ExactOscillator) run on from the state the
rule gives right after the jump, with the wall held at its new position.
"""
from __future__ import annotations

import numpy as np
import pytest

from mapcheck.exact import ExactOscillator
from tests.support.fmu import WALLS as WALL

UNDERDAMPED = dict(nu=0.196, Omega=7.368)


def _after_jump(fmu, wall: str, w: float, y: tuple[float, float], t: float, r: float = 0.9,
                Gamma: float = 1000.0, sigma: float = 0.1, lin: dict = UNDERDAMPED,
                T: float = 3.0, n0: int = 0) -> None:
    """From the state the rule gives right after a jump, the run to T against the closed form
    with the wall held at w: states every 0.01 to 1e-8, impact counts exact, the rigid wall
    never penetrated."""
    ex = ExactOscillator(sigma=sigma, r=r, Gamma=Gamma, wall=wall, u_wall=w, **lin)
    times = np.round(np.arange(t + 0.01, T + 1e-12, 0.01), 12)
    want, counts = ex.dense(y[0], y[1], times, t0=t)
    for x, c, tk in zip(want, counts, times):
        fmu.step_to(float(tk))
        got = fmu.state()
        assert np.max(np.abs(got - x)) < 1e-8, (tk, got, x)
        assert fmu.impacts() == n0 + c, tk
        if wall == "rigid":
            assert got[0] <= w
    assert counts[-1] > 0  # the wall is hit again after the jump


@pytest.mark.parametrize("t_jump", [0.01, 0.03, 0.05])
@pytest.mark.parametrize("depth", [0.01, 0.1, 0.3])
def test_rigid_wall_jumping_into_the_mass_places_it_on_the_wall_with_an_impact(fmu, t_jump, depth):
    """Documented rule (model.c, model_input_jump): the mass is put on the new wall position and
    the impact law acts on its velocity relative to the wall (v -> -r v, counted, with v_impact and
    t_impact). Jumps 0.01 .. 0.3 deep at three times while the mass moves towards the wall; the
    run after the jump against the closed form."""
    fmu.start(wall=WALL["rigid"], sigma=0.1, r=0.8, u0=-0.5, v0=1.0, **UNDERDAMPED)
    fmu.step_to(t_jump)
    u, v = fmu.state()
    assert v > 0.1  # the mass moves into the jumping wall: the impact rule must act
    w = u - depth
    fmu.set(u_wall=w)
    fmu.step_to(t_jump + 1e-9)
    u1, v1 = fmu.state()
    assert u1 <= w and u1 == pytest.approx(w, abs=1e-8)  # placed, then moved off
    assert fmu.impacts() == 1 and fmu.get("v_impact") == v
    assert fmu.get("t_impact") == t_jump
    assert v1 == pytest.approx(-0.8 * v, rel=1e-6)
    _after_jump(fmu, "rigid", w, (w, -0.8 * v), t_jump, r=0.8, n0=1)


@pytest.mark.parametrize("t_jump", [0.01, 0.05])
@pytest.mark.parametrize("depth", [0.01, 0.05, 0.2])
def test_rigid_wall_jump_onto_a_receding_mass_places_it_without_rebound(fmu, t_jump, depth):
    """The wall jumps past a mass that moves away from it: placed on the wall, no impact, its
    velocity kept; then against the closed form."""
    fmu.start(wall=WALL["rigid"], sigma=0.1, u0=-0.5, v0=-1.0, **UNDERDAMPED)
    fmu.step_to(t_jump)
    u, v = fmu.state()
    assert v < -0.1
    fmu.set(u_wall=u - depth)
    fmu.step_to(t_jump + 1e-9)
    assert fmu.impacts() == 0 and fmu.state()[0] <= u - depth
    _after_jump(fmu, "rigid", u - depth, (u - depth, v), t_jump)


@pytest.mark.parametrize("t_jump", [0.02, 0.05, 0.1])
@pytest.mark.parametrize("depth", [0.001, 0.01, 0.05])
def test_compliant_wall_jumping_into_the_mass_starts_a_contact_without_a_jump(fmu, t_jump, depth):
    """The mass is inside the compliant wall after the jump, as after a start inside it: no
    entry jump, no impact; F_contact answers the new wall at once (direct feedthrough); the run
    on against the closed form started inside the wall."""
    fmu.start(wall=WALL["compliant"], sigma=0.1, Gamma=1000.0, u0=-0.5, v0=1.0, **UNDERDAMPED)
    fmu.step_to(t_jump)
    u, v = fmu.state()
    fmu.set(u_wall=u - depth)
    k2 = 1000.0 * UNDERDAMPED["Omega"] ** 2
    assert fmu.get("F_contact") == pytest.approx(k2 * depth, rel=1e-9)
    fmu.step_to(t_jump + 1e-14)  # the spring changes v by ~ kappa^2 depth 1e-14 < 3e-11 here
    assert fmu.in_contact() and fmu.impacts() == 0
    assert fmu.state() == pytest.approx([u, v], abs=1e-10)  # no jump in the state
    _after_jump(fmu, "compliant", u - depth, (u, v), t_jump)


def test_sticking_mass_follows_a_wall_pushed_into_it_and_is_freed_when_it_recedes(fmu):
    lin = UNDERDAMPED
    fmu.start(wall=WALL["rigid"], sigma=10.0, r=0.0, u0=-0.03, v0=0.0, **lin)
    for k in range(1, 200):
        fmu.step_to(0.005 * k)
        if fmu.in_contact():
            break
    assert fmu.in_contact() and fmu.state()[0] == 0.0
    fmu.set(u_wall=-0.01)  # pushed along
    fmu.step_to(fmu.t + 1e-9)
    assert fmu.state()[0] == -0.01
    fmu.set(u_wall=0.5)  # the wall leaves: the mass flies on with its velocity (0, the wall's)
    t = fmu.t
    fmu.step_to(t + 1e-9)
    assert not fmu.in_contact()
    _after_jump(fmu, "rigid", 0.5, (-0.01, 0.0), t, r=0.0, sigma=10.0, T=t + 2.0,
                n0=fmu.impacts())


def test_model_exchange_wall_jump_is_an_event_with_the_same_rule():
    """ME: the importer sets u_wall beyond the mass (rigid wall) and handles the event the
    indicator's sign change asks for: the mass is put on the wall, v reflected relative to it."""
    import ctypes

    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Model

    from tests.support.fmu import FMU_PATH
    md = read_model_description(str(FMU_PATH))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    me = FMU2Model(guid=md.guid, unzipDirectory=extract(str(FMU_PATH)),
                   modelIdentifier=md.modelExchange.modelIdentifier, instanceName="mej")
    me.instantiate()
    try:
        me.setupExperiment(startTime=0.0)
        me.enterInitializationMode()
        me.setInteger([vr["wall"]], [2])
        me.setReal([vr["u0"], vr["v0"], vr["r"]], [-0.5, 1.0, 0.8])
        me.exitInitializationMode()
        me.newDiscreteStates()
        me.enterContinuousTimeMode()
        g = (ctypes.c_double * 1)()
        me.getEventIndicators(g, 1)
        assert g[0] == -0.5
        me.setReal([vr["u_wall"]], [-0.6])  # the wall jumps 0.1 into the mass
        me.getEventIndicators(g, 1)
        assert g[0] == pytest.approx(0.1)  # sign change: the importer enters event mode
        me.enterEventMode()
        info = me.newDiscreteStates()
        assert info[3]  # valuesOfContinuousStatesChanged
        x = (ctypes.c_double * 2)()
        me.getContinuousStates(x, 2)
        assert x[0] <= -0.6 and x[0] == pytest.approx(-0.6, abs=1e-15)
        assert x[1] == pytest.approx(-0.8 * 1.0)
        assert me.getInteger([vr["impacts"]])[0] == 1
        assert me.getReal([vr["v_impact"]])[0] == 1.0
    finally:
        me.terminate()
        me.freeInstance()
