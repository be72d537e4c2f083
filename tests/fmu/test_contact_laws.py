"""Nonlinear contact laws of the compliant wall (parameter `contact`): Hertz kappa^2 u^{3/2}
and Hunt-Crossley kappa^2 u^{3/2} (1 + alpha_hc v). Neither has a closed form, so they are
checked by the energy balance through contacts and by convergence under tightened tolerances.

Energy tests switch the drive and the damping off (nu = 0, sigma = -1 + 1e-15: forcing ~1e-14),
so that E = v^2/2 + Omega^2 (u+1)^2/2 + (2/5) kappa^2 u^{5/2} [u > 0] changes only through the
contact's dissipation."""
from __future__ import annotations

import numpy as np
import pytest

from tests.support.fmu import FMU_PATH, LoggedSlave, expect_error, on_orbit

FREE = dict(nu=0.0, Omega=3.0, sigma=-1.0 + 1e-15, Gamma=10.0, wall="compliant",
            u0=-1.0, v0=6.0)  # amplitude 2 about u = -1: into the wall once per free period


@pytest.fixture(scope="module")
def fmu(module_fmu: LoggedSlave) -> LoggedSlave:
    return module_fmu


def energy(x: np.ndarray, Omega: float, Gamma: float) -> np.ndarray:
    u, v = x[:, 0], x[:, 1]
    k2 = Gamma * Omega**2
    return 0.5 * v**2 + 0.5 * Omega**2 * (u + 1) ** 2 + 0.4 * k2 * np.maximum(u, 0.0) ** 2.5


def run(fmu, times, t0=0.0, **params):
    fmu.start(t0=t0, **params)
    xs, contact, impacts = [], [], []
    for t in times:
        fmu.step_to(float(t))
        xs.append(fmu.state())
        contact.append(fmu.in_contact())
        impacts.append(fmu.impacts())
    return np.array(xs), np.array(contact), np.array(impacts)


def test_defaults_keep_the_paper_linear_law():
    from fmpy import read_model_description
    md = read_model_description(str(FMU_PATH))
    v = {x.name: x for x in md.modelVariables}
    assert v["contact"].start == "0" and v["contact"].valueReference == 17
    assert v["alpha_hc"].valueReference == 18 and v["alpha_hc"].causality == "parameter"


def test_bad_contact_parameters_are_rejected(fmu):
    fmu.slave.reset()
    expect_error(fmu.slave.setInteger, [fmu.vr["contact"]], [3])
    expect_error(fmu.slave.setReal, [fmu.vr["alpha_hc"]], [-0.1])


def test_hertz_without_damping_conserves_energy_through_contacts(fmu):
    times = np.arange(1, 301) * 0.05  # 15 time units: 7 free periods, 7 contacts
    x, contact, impacts = run(fmu, times, contact=1, **FREE)
    E = energy(x, FREE["Omega"], FREE["Gamma"])
    E0 = energy(np.array([[FREE["u0"], FREE["v0"]]]), FREE["Omega"], FREE["Gamma"])[0]
    assert impacts[-1] >= 6 and contact.any()
    drift = np.abs(E - E0).max() / E0
    print(f"Hertz: {impacts[-1]} contacts, max relative energy error {drift:.2e}")
    assert drift < 1e-8


def test_hunt_crossley_never_gains_energy_and_loses_it_only_in_contact(fmu):
    times = np.arange(1, 301) * 0.05
    x, contact, impacts = run(fmu, times, contact=2, alpha_hc=0.1, **FREE)
    E = energy(x, FREE["Omega"], FREE["Gamma"])
    E0 = energy(np.array([[FREE["u0"], FREE["v0"]]]), FREE["Omega"], FREE["Gamma"])[0]
    E = np.r_[E0, E]
    dE = np.diff(E)
    assert dE.max() <= 1e-10 * E0, f"energy gained: {dE.max():.2e}"
    free_steps = ~contact & ~np.r_[False, contact[:-1]]  # free at both ends of the step
    free_steps[0] = not contact[0]
    assert np.abs(dE[free_steps]).max() <= 1e-10 * E0
    print(f"Hunt-Crossley: {impacts[-1]} contacts, energy {E0:.4f} -> {E[-1]:.4f}")
    assert impacts[-1] >= 4 and E[-1] < 0.9 * E0


def test_hunt_crossley_first_contact_restitution(fmu):
    """One contact: exit speed / entry speed, with alpha_hc -> 0 approaching Hertz (r = 1)."""
    rs = []
    for alpha in (0.0, 0.01, 0.05):
        fmu.start(t0=0.0, contact=2, alpha_hc=alpha, **FREE)
        t, seen = 0.0, False
        while t < 3.0:  # first contact is near t = 0.6 (quarter period + path to u = 0)
            t += 0.002
            fmu.step_to(t)
            c = fmu.in_contact()
            if c:
                seen = True
            if seen and not c:
                break
        # just after the exit (u ~ 0): speed squared = 2 E - Omega^2 (u+1)^2
        x = fmu.state()
        e_after = energy(x[None, :], FREE["Omega"], FREE["Gamma"])[0]
        rs.append(np.sqrt(e_after / 18.0))  # E0 = 36/2 + 0 = 18
    print("Hunt-Crossley energy ratio^(1/2) through one contact:", rs)
    assert abs(rs[0] - 1.0) < 1e-8
    assert 1.0 > rs[1] > rs[2] > 0.5


@pytest.mark.parametrize("law", [1, 2])
def test_converges_under_tightened_tolerances(fmu, law):
    """Driven, damped (Figure 9's nu, Omega), hitting the wall every period: the error against
    a rtol = 1e-13 reference falls with rtol, and the impact counts agree."""
    lin = dict(nu=4.605170185988091, Omega=0.3059238689620112)
    sigma, t0 = 0.5, 0.5
    times = t0 + np.arange(1, 11, dtype=float)
    params = dict(contact=law, wall="compliant", sigma=sigma, Gamma=10.0,
                  **on_orbit(sigma, t0), **lin)
    ref, _, k_ref = run(fmu, times, t0=t0, rtol=1e-13, atol=1e-15, **params)
    assert k_ref[-1] >= 5
    errs = []
    for rtol in (1e-6, 1e-8, 1e-10):
        x, _, k = run(fmu, times, t0=t0, rtol=rtol, atol=rtol * 1e-2, **params)
        errs.append(np.abs(x - ref).max())
        assert list(k) == list(k_ref)
    print(f"contact law {law}: errors at rtol 1e-6, 1e-8, 1e-10 =", errs)
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 1e-7
