"""Model Exchange keeps the importer's state (FMI 2 and 3, through fmpy).

At an event, a state within the event tolerance of the wall (1e-6 max(1, |u_wall|), docs/fmu.md)
is the crossing the importer located: it is placed on the wall and the wall's jump applied (the
entry's v -> r v, the rigid impact's v -> -r v), as the exact flow's event law says. Any other
state keeps its values, bit for bit, and the instance takes the contact mode that the state is in;
a state far inside the rigid wall, which no mode holds, is refused with a message. The truth is
the law written here: the restitution r and the side of the wall.
"""
from __future__ import annotations

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from tests.support.derivatives import Instance

TOL = 1e-6
R = 0.8
ME = ["fmi2-me", "fmi3-me"]
COMPLIANT = dict(wall=1, Gamma=10.0, r=R)
RIGID = dict(wall=2, r=R)


def _event(x: Instance, u: float, v: float) -> tuple[np.ndarray, bool]:
    """Set (u, v) in Continuous-Time Mode, run the event iteration; the state after it and
    valuesOfContinuousStatesChanged."""
    x.set_states(u, v)
    x.enter_event_mode()
    changed = x.event_update()
    x.fmu.enterContinuousTimeMode()
    return x.states(), changed


@pytest.mark.parametrize("interface", ME)
@pytest.mark.parametrize("wall_at", [0.0, 2.5])
@pytest.mark.parametrize("state,inside", [((-1.5, -2.0), True), ((-0.2, 0.0), True),
                                          ((0.5, 1.0), False), ((3e-6, 0.4), False)])
def test_a_state_far_from_the_compliant_wall_is_kept_and_takes_its_mode(interface, wall_at,
                                                                       state, inside):
    """The audit's cases: (-1.5, -2.0) set while in contact came back as (-1e-300, -2.0), and
    (0.5, 1.0) set in flight as (1e-300, 0.9)."""
    u0 = wall_at + (0.3 if inside else -0.5)
    x = Instance(interface, u0=u0, v0=0.0, u_wall=wall_at, **COMPLIANT)
    try:
        assert x.integer("in_contact") == int(inside)
        u, v = state[0] + wall_at, state[1]
        after, changed = _event(x, u, v)
        assert after.tolist() == [u, v]  # bit for bit
        assert x.integer("in_contact") == int(not inside)  # the mode the state is in
        assert x.integer("impacts") == 0
        assert changed  # the right-hand side changed: an integrator restarts
    finally:
        x.close()


@pytest.mark.parametrize("interface", ME)
@pytest.mark.parametrize("wall_at", [0.0, 2.5])
def test_a_crossing_within_the_tolerance_is_placed_on_the_wall_with_its_jump(interface,
                                                                          wall_at):
    tol = TOL * max(1.0, abs(wall_at))
    x = Instance(interface, u0=wall_at - 0.5, v0=0.0, u_wall=wall_at, **COMPLIANT)
    try:
        after, changed = _event(x, wall_at + 0.5 * tol, 1.0)
        assert 0 < after[0] - wall_at <= 1e-15 * max(1.0, wall_at)  # beside the wall, inside
        assert after[1] == pytest.approx(R * 1.0, rel=1e-15)  # the linear wall's entry jump
        assert x.integer("in_contact") == 1 and x.integer("impacts") == 1 and changed
        after, _ = _event(x, wall_at - 0.5 * tol, -0.7)  # leaving, within the tolerance
        assert -1e-15 * max(1.0, wall_at) <= after[0] - wall_at < 0 and after[1] == -0.7
        assert x.integer("in_contact") == 0
        after, _ = _event(x, wall_at + 2 * tol, 1.0)  # just beyond the tolerance: kept
        assert after.tolist() == [wall_at + 2 * tol, 1.0] and x.integer("impacts") == 1
    finally:
        x.close()


@pytest.mark.parametrize("interface", ME)
def test_the_rigid_wall_impact_within_the_tolerance_and_a_state_far_inside_refused(interface):
    x = Instance(interface, u0=-0.5, v0=0.0, **RIGID)
    try:
        after, _ = _event(x, 0.5 * TOL, 1.0)
        assert after[0] <= 0 and after[0] == pytest.approx(0.0, abs=1e-15)
        assert after[1] == pytest.approx(-R, rel=1e-15) and x.integer("impacts") == 1
        after, changed = _event(x, -0.3, 0.2)  # on its own side: nothing happens
        assert after.tolist() == [-0.3, 0.2] and not changed
        x.set_states(0.5, 1.0)
        x.enter_event_mode()
        with pytest.raises(FMICallException):
            x.event_update()  # far inside the rigid wall: no mode holds it
    finally:
        x.fmu.freeInstance()


@pytest.mark.parametrize("interface", ME)
def test_a_state_on_its_own_side_is_left_alone(interface):
    for u0, state in ((-0.5, (-0.3, 0.4)), (0.3, (0.2, -0.4))):
        x = Instance(interface, u0=u0, v0=0.0, **COMPLIANT)
        try:
            mode = x.integer("in_contact")
            after, changed = _event(x, *state)
            assert after.tolist() == list(state) and not changed
            assert x.integer("in_contact") == mode
        finally:
            x.close()


@pytest.mark.parametrize("interface", ME)
def test_a_sticking_mass_set_off_the_wall_flies_from_where_it_was_set(interface):
    """Sticking: a state the importer moves off the wall beyond the tolerance is in flight,
    kept; one moved into the rigid wall is refused."""
    import math

    from mapcheck.exact import forcing_amplitude_phase
    nu, Omega = 4.605170185988091, 0.3059238689620112
    t0 = (-forcing_amplitude_phase(nu, Omega)[1] / (2 * math.pi)) % 1.0  # the drive's maximum
    for state, refused in (((-0.5, 0.3), False), ((0.5, 0.0), True)):
        x = Instance(interface, t0=t0, nu=nu, Omega=Omega, u0=0.0, v0=0.0, **RIGID)
        try:
            assert x.integer("in_contact") == 1, "meant to stick"
            if refused:
                x.set_states(*state)
                x.enter_event_mode()
                with pytest.raises(FMICallException):
                    x.event_update()
                continue
            after, changed = _event(x, *state)
            assert after.tolist() == list(state) and changed
            assert x.integer("in_contact") == 0
            assert x.derivatives()[0] == state[1]  # in flight: der(u) = v
        finally:
            x.fmu.freeInstance()
