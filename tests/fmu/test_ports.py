"""The FMU's ports: inputs F_ext and u_wall, outputs F_contact, v_impact, t_impact, with the
ports constant.

Independent truths: the closed form with constant ports (mapcheck.exact.ExactOscillator(F_ext=,
u_wall=), an exact scaling of the port-free problem), the contact law itself for F_contact, and
the oracle's crossing times for t_impact.  Ramps given as input derivatives and a moving wall:
tests/fmu/test_ports_ramps.py; a wall that jumps between steps:
tests/fmu/test_ports_wall_jumps.py.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from mapcheck.exact import ExactOscillator, forcing_amplitude_phase
from tests.support.fmu import (FMU3_PATH, LoggedSlave, at_times, refused_and_restored,
                               simulate)
from tests.support.fmu import WALLS as WALL

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112)
UNDERDAMPED = dict(nu=0.196, Omega=7.368)


# (wall, linear part, sigma, Gamma, r, F_ext, u_wall, start): the ports shift the equilibrium
# (F_ext / Omega^2) and the wall; each case has wall contacts in the window.
CASES = [
    ("compliant", FIG9, 0.5, 10.0, 0.9, 0.02, -0.1, (-0.4, 0.0)),
    ("rigid", FIG9, 0.5, 10.0, 0.9, 0.02, -0.1, (-0.4, 0.0)),
    ("compliant", UNDERDAMPED, 0.1, 1000.0, 0.9, 5.0, 0.2, (-0.5, 1.0)),
    ("rigid", UNDERDAMPED, 0.1, 1000.0, 0.7, -3.0, 0.3, (-0.5, 1.0)),
    ("none", UNDERDAMPED, 0.1, 1000.0, 0.9, 2.5, 0.0, (-0.5, 1.0)),
]
IDS = [f"{c[0]}-{'fig9' if c[1] is FIG9 else 'under'}-F{c[5]}-w{c[6]}" for c in CASES]


def _start(fmu, wall, lin, sigma, Gamma, r, F, w, start, **extra):
    fmu.start(wall=WALL[wall], sigma=sigma, Gamma=Gamma, r=r, u0=start[0], v0=start[1],
              F_ext=F, u_wall=w, **lin, **extra)


@pytest.mark.parametrize("solver", [0, 1], ids=["cvode", "closed-form"])
@pytest.mark.parametrize("wall,lin,sigma,Gamma,r,F,w,start", CASES, ids=IDS)
def test_constant_ports_match_the_closed_form(fmu, wall, lin, sigma, Gamma, r, F, w, start,
                                              solver):
    """FMI 2.0 CS with constant F_ext, u_wall against the exact solution (the scaled oracle),
    20 periods, with either of the FMU's solvers (CVODE; its own closed form, which takes the
    ports as a shifted equilibrium and wall in its particular solution)."""
    if solver:
        lin = dict(lin, solver=solver)
    _start(fmu, wall, lin, sigma, Gamma, r, F, w, start)
    lin = {k: x for k, x in lin.items() if k != "solver"}
    ex = ExactOscillator(sigma=sigma, r=r, Gamma=Gamma, wall=wall, F_ext=F, u_wall=w, **lin)
    times = np.arange(1.0, 21.0)
    want, impacts = ex.strobe(start[0], start[1], times)
    got = []
    for t in times:
        fmu.step_to(t)
        got.append(fmu.state())
    err = np.max(np.abs(np.array(got) - want))
    assert err < (1e-11 if solver else 1e-8), err
    assert fmu.impacts() == impacts[-1]
    if wall != "none":
        assert impacts[-1] > 0  # the wall is exercised


@pytest.mark.parametrize("fmi_type", ["CoSimulation", "ModelExchange"])
@pytest.mark.parametrize("case", [CASES[0], CASES[3]], ids=[IDS[0], IDS[3]])
def test_fmi3_ports_match_the_closed_form(fmi_type, case):
    """FMI 3.0 (CS and ME through fmpy, inputs at their start values) against the oracle; ME is
    integrated by fmpy's own CVODE, hence its looser bound."""
    wall, lin, sigma, Gamma, r, F, w, start = case
    res = simulate(FMU3_PATH, fmi_type, 0.0, 10.0, 0.5, rtol=1e-10, wall=wall, sigma=sigma,
                   Gamma=Gamma, r=r, u0=start[0], v0=start[1], F_ext=F, u_wall=w, **lin)
    times = np.arange(1.0, 11.0)
    got, impacts = at_times(res, times)
    want, n = ExactOscillator(sigma=sigma, r=r, Gamma=Gamma, wall=wall, F_ext=F, u_wall=w,
                              **lin).strobe(start[0], start[1], times)
    tol = 1e-8 if fmi_type == "CoSimulation" else 1e-5
    assert np.max(np.abs(got - want)) < tol
    assert impacts[-1] == n[-1]


def test_zero_inputs_set_every_step_change_nothing_bit_for_bit():
    """A master that writes F_ext = u_wall = 0 before every step gets the port-free run to the
    last bit (unchanged inputs do not restart CVODE)."""
    runs = []
    for write in (False, True):
        s = LoggedSlave(name=f"zero{write}")
        try:
            s.start(wall=WALL["rigid"], sigma=0.05, r=0.9, u0=-0.5, v0=1.0, **UNDERDAMPED)
            out = []
            for k in range(1, 200):
                if write:
                    s.set(F_ext=0.0, u_wall=0.0)
                s.step_to(0.1 * k)
                out.append(np.append(s.state(), [s.impacts(), s.get("F_contact")]))
            runs.append(np.array(out))
        finally:
            s.close()
    assert runs[0][-1, 2] > 0
    assert np.array_equal(runs[0], runs[1])

# -- outputs -------------------------------------------------------------------------------------

def test_contact_force_is_the_spring_in_the_wall_and_zero_in_flight(fmu):
    """Compliant linear wall: F_contact = kappa^2 (u - u_wall) inside, 0 outside, at every
    sampled point of a run with many contacts."""
    _start(fmu, "compliant", FIG9, 0.5, 10.0, 0.9, 0.02, -0.1, (-0.4, 0.0))
    k2 = 10.0 * FIG9["Omega"] ** 2
    inside = 0
    for k in range(1, 1500):
        fmu.step_to(0.0137 * k)
        u, F = fmu.state()[0], fmu.get("F_contact")
        if fmu.in_contact():
            inside += 1
            assert F == pytest.approx(k2 * (u + 0.1), rel=1e-12, abs=1e-300)
        else:
            assert F == 0.0
    assert inside >= 5


def test_contact_force_while_sticking_is_the_holding_force(fmu):
    """Rigid wall, chatter into sticking (r = 0): on the wall F_contact is the net force the
    wall holds back, F(t) + F_ext - Omega^2 (u_wall + 1) > 0."""
    lin = UNDERDAMPED
    F_g, phi = forcing_amplitude_phase(**lin)
    fmu.start(wall=WALL["rigid"], sigma=10.0, r=0.0, u0=-0.03, v0=0.0, F_ext=1.0, u_wall=0.05,
              **lin)
    stuck = 0
    for k in range(1, 200):
        t = 0.005 * k
        fmu.step_to(t)
        if fmu.in_contact():
            stuck += 1
            want = 11.0 * F_g * math.cos(2 * math.pi * t + phi) + 1.0 - lin["Omega"] ** 2 * 1.05
            assert fmu.get("F_contact") == pytest.approx(want, rel=1e-9)
            assert fmu.get("F_contact") > 0.0
            assert fmu.state()[0] == 0.05  # on the wall, exactly
    assert stuck > 5


@pytest.mark.parametrize("case", [c for c in CASES if c[0] != "none"],
                         ids=[i for c, i in zip(CASES, IDS) if c[0] != "none"])
def test_impact_time_and_velocity(fmu, case):
    """t_impact is the oracle's last entry time and v_impact the relative velocity just before it
    (the closed form's state 1e-10 before the entry; the wall is at rest), at every one of 1000
    communication points over 20 periods, with the impact count equal to the oracle's at each (no chatter here:
    the smallest entry velocity is asserted well above the sticking threshold)."""
    wall, lin, sigma, Gamma, r, F, w, start = case
    _start(fmu, wall, lin, sigma, Gamma, r, F, w, start)
    ex = ExactOscillator(sigma=sigma, r=r, Gamma=Gamma, wall=wall, F_ext=F, u_wall=w, **lin)
    kind = "impact" if wall == "rigid" else "enter"
    entries = [t for t, k in ex.crossings(start[0], start[1], 0.0, 20.0) if k == kind]
    assert entries
    before, _ = ex.strobe(start[0], start[1], [t - 1e-10 for t in entries])
    v_in = before[:, 1]
    assert np.all(v_in > 1e-3)
    for k in range(1, 1001):
        fmu.step_to(0.02 * k)
        n = sum(1 for t in entries if t <= fmu.t)
        assert fmu.impacts() == n, (fmu.t, fmu.impacts(), n)
        if n:
            assert abs(fmu.get("t_impact") - entries[n - 1]) < 1e-9
            assert fmu.get("v_impact") == pytest.approx(v_in[n - 1], rel=1e-7)
        else:
            assert (fmu.get("t_impact"), fmu.get("v_impact")) == (0.0, 0.0)

def test_inputs_are_validated_where_they_enter(fmu):
    fmu.start()
    for name, bad in (("F_ext", float("nan")), ("F_ext", 1e300), ("u_wall", float("inf")),
                      ("u_wall", 2e6)):
        refused_and_restored(fmu, lambda: fmu.set(**{name: bad}))
        assert name in fmu.errors()[-1]
    assert fmu.get("F_ext") == 0.0 and fmu.get("u_wall") == 0.0
    fmu.step_to(1.0)


def test_model_structure_declares_outputs_on_inputs():
    from fmpy import read_model_description

    from tests.support.fmu import FMU_PATH
    for path in (FMU_PATH, FMU3_PATH):
        md = read_model_description(str(path))
        deps = {o.variable.name: sorted(d.name for d in (o.dependencies or []))
                for o in md.outputs}
        assert deps["F_contact"] == ["F_ext", "u", "u_wall", "v", "v_wall"], (path, deps)
        assert set(deps) >= {"u", "v", "impacts", "in_contact", "v_impact", "t_impact"}
