"""The closed-form solver mode of the FMU (solver = 1): exact propagation on each
side of the wall with a certified crossing search. Checked against the FMU's CVODE mode (per
period, within the error budget 1e-8), against mapcheck.exact (the independent closed form in
Python), on contacts down to 1e-14 deep, with sticking on the rigid wall, in FMI 2.0 and 3.0;
the nonlinear contact laws are refused.
"""
from __future__ import annotations

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from tests.support.fmu import FMU3_PATH, on_orbit
from tests.support.sensitivities import FIG9, UNDERDAMPED, Fmu, one_period, oracle

CASES = {
    "fig9_compliant": dict(FIG9, wall=1),
    "fig9_sigma0.2": dict(FIG9, sigma=0.2, wall=1),
    "underdamped_compliant": dict(UNDERDAMPED, wall=1),
    "underdamped_rigid": dict(UNDERDAMPED, wall=2),
    "soft_r1": dict(UNDERDAMPED, sigma=0.05, r=1.0, Gamma=10.0, wall=1),
    "rigid_heavy_damping": dict(nu=100.0, Omega=2 ** 0.5, sigma=0.1, r=0.5, wall=2),
    "no_wall": dict(UNDERDAMPED, sigma=0.3, wall=0),
}


@pytest.fixture(scope="module")
def fmu2():
    f = Fmu(2)
    yield f
    f.close()


def orbit(f: Fmu, params: dict, n: int, t0: float = 0.5, solver: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """n periods (one doStep each) from the wall-free orbit at t0: states and impact counts."""
    f.start(t0, **params, **on_orbit(params["sigma"], t0), solver=solver)
    xs, ns = [], []
    for k in range(1, n + 1):
        f.step(t0 + k)
        xs.append(f.state())
        ns.append(f.impacts())
    return np.array(xs), np.array(ns)


@pytest.mark.parametrize("case", sorted(CASES))
def test_closed_form_mode_agrees_with_cvode_mode_per_period(fmu2, case):
    p = CASES[case]
    xs, ns = orbit(fmu2, p, 12)
    assert p["wall"] == 0 or ns[-1] > 0
    for k in range(len(xs) - 1):
        t0 = 0.5 + k + 1
        a, _, _ = one_period(fmu2, p, xs[k], t0, sens=False, solver=0)
        n0 = fmu2.impacts()
        b, _, _ = one_period(fmu2, p, xs[k], t0, sens=False, solver=1)
        assert fmu2.impacts() == n0
        assert np.max(np.abs(a - b)) <= 1e-8, (case, k, a, b)


@pytest.mark.parametrize("case", sorted(CASES))
def test_closed_form_mode_matches_mapcheck_exact(fmu2, case):
    p = CASES[case]
    xs, ns = orbit(fmu2, p, 12)
    osc = oracle(p)
    for k in range(len(xs) - 1):
        t0 = 0.5 + k + 1
        u, v, c = osc.state_at(xs[k][0], xs[k][1], t0, t0 + 1.0)
        assert np.max(np.abs(xs[k + 1] - (u, v))) <= 1e-10, (case, k)
        assert ns[k + 1] - ns[k] == c


@pytest.mark.parametrize("depth", [1e-6, 1e-10, 1e-14])
@pytest.mark.parametrize("wall", [1, 2])
def test_shallow_contacts_are_never_missed(fmu2, depth, wall):
    """At sigma = x the wall-free orbit peaks at u = x at t = 1: a contact x deep, lasting
    ~sqrt(x) of a period. At sigma = -x the orbit misses the wall by x: no contact."""
    p = dict(UNDERDAMPED, wall=wall, Gamma=100.0)
    for sigma, expected in ((depth, 1), (-depth, 0)):
        q = dict(p, sigma=sigma)
        fmu2.start(0.5, **q, **on_orbit(sigma, 0.5), solver=1)
        fmu2.step(1.5)
        assert fmu2.impacts() == expected, (sigma, wall)
        st = on_orbit(sigma, 0.5)
        u, v, c = oracle(q).state_at(st["u0"], st["v0"], 0.5, 1.5)
        assert c == expected
        # the state after a contact x deep is ill-conditioned: an error e in u at the turning
        # point moves the crossing velocity ~sqrt(2 a x) by a e / sqrt(2 a x); the oracle's own
        # e ~ 1e-13 (mapcheck.exact in double precision) sets the tolerance
        assert np.max(np.abs(fmu2.state() - (u, v))) <= max(1e-12, 1e-13 / np.sqrt(depth))


def test_sticking_on_the_rigid_wall_matches_the_oracle(fmu2):
    """Strong damping and r = 0.5: chatter ends in sticking (Zeno truncation) and release at
    the closed-form time when the wall force changes sign."""
    p = dict(nu=100.0, Omega=2 ** 0.5, sigma=0.5, r=0.5, wall=2)
    xs, ns = orbit(fmu2, p, 6)
    ref, _ = oracle(p).strobe(*on_orbit(p["sigma"], 0.5).values(), np.arange(1, 7) + 0.5, t0=0.5)
    assert ns[-1] > 20  # chatter
    assert np.max(np.abs(xs - ref)) <= 1e-10


@pytest.mark.parametrize("contact", [1, 2])
def test_nonlinear_contact_laws_are_refused(fmu2, contact, capsys):
    """Refused at fmi2ExitInitializationMode through plain fmpy, whose default logger prints the
    message, whatever loggers other tests handed to fmpy's logger proxy and let be collected
    (harness/fmu/fmi2_logging.py, tests/harness/test_fmi2_logging.py)."""
    with pytest.raises(FMICallException):
        fmu2.start(0.0, **dict(FIG9, wall=1), contact=contact, solver=1)
    fmu2.started = True
    law = "Hertz" if contact == 1 else "Hunt-Crossley"
    assert (f"solver = 1 (closed form) needs the linear contact law, not contact = {contact} "
            f"({law})") in capsys.readouterr().out


def test_fmi3_closed_form_equals_fmi2():
    f2, f3 = Fmu(2), Fmu(3)
    try:
        p = CASES["underdamped_rigid"]
        a, _ = orbit(f2, p, 5)
        b, _ = orbit(f3, p, 5)
        assert np.array_equal(a, b)
    finally:
        f2.close()
        f3.close()


# Constant ports in closed-form mode against the oracle: tests/fmu/test_ports.py
# (test_constant_ports_match_the_closed_form, solver = 1).


@pytest.mark.parametrize("wall", ["compliant", "rigid"])
def test_ramped_ports_closed_form_equals_cvode(wall):
    """F_ext and u_wall as ramps (values and first derivatives per step, FMI 2.0): a moving
    wall, with contacts; the closed form against CVODE mode step by step."""
    from tests.support.fmu import WALLS, LoggedSlave
    runs = {}
    for solver in (0, 1):
        f = LoggedSlave(name=f"ramp{solver}")
        try:
            f.start(wall=WALLS[wall], sigma=0.1, Gamma=100.0, r=0.8, u0=-0.5, v0=1.0,
                    nu=UNDERDAMPED["nu"], Omega=UNDERDAMPED["Omega"], solver=solver)
            out, h = [], 0.5
            for k in range(12):
                t = k * h
                F0, F1, w0, w1 = 2.0 + 0.4 * t, 0.4, -0.05 + 0.02 * t, 0.02
                f.set(F_ext=F0, u_wall=w0)
                f.slave.setRealInputDerivatives([f.vr["F_ext"], f.vr["u_wall"]], [1, 1], [F1, w1])
                f.step_to(t + h)
                out.append((*f.state(), f.impacts()))
            runs[solver] = np.array(out)
        finally:
            f.close()
    assert runs[1][-1, 2] > 2 and np.array_equal(runs[0][:, 2], runs[1][:, 2])
    assert np.max(np.abs(runs[0][:, :2] - runs[1][:, :2])) < 1e-8


@pytest.mark.parametrize("wall,sigma", [("compliant", 0.5), ("rigid", 0.3)])
def test_fmi3_early_return_at_every_event_in_closed_form(wall, sigma):
    """FMI 3.0 event mode with early return: the closed form stops at each wall event (the jump
    left to the importer's event mode) at the oracle's crossing times."""
    from fmpy import simulate_fmu

    from tests.support.fmu import WALLS
    lin = {k: FIG9[k] for k in ("nu", "Omega")}
    start = dict(wall=WALLS[wall], sigma=sigma, Gamma=10.0, **on_orbit(sigma, 0.5), **lin, solver=1)
    res = simulate_fmu(str(FMU3_PATH), fmi_type="CoSimulation", start_time=0.5, stop_time=10.5,
                       output_interval=1.0, start_values=start, output=["u", "v", "impacts"],
                       use_event_mode=True, early_return_allowed=True)
    t = res["time"]
    got = t[1:][np.diff(t) == 0.0]
    osc = oracle(dict(FIG9, sigma=sigma, wall=WALLS[wall]))
    events = osc.crossings(start["u0"], start["v0"], 0.5, 10.5)
    want = np.array([te for te, kind in events if kind in ("enter", "exit", "impact")])
    assert len(want) >= 1 and len(got) == len(want)
    assert np.abs(got - want).max() < 1e-11
    assert res["impacts"][-1] == sum(1 for _, kind in events if kind in ("enter", "impact"))


def test_bare_c_driver_runs_the_fmus_code(tmp_path, fmu2):
    """bench/cf_driver.c (the benchmark's bare C closed form) and the FMU in closed-form mode
    compute the same orbit bit for bit: the benchmark's ratio compares the same code."""
    import shutil
    import subprocess

    from tests.support.fmu import ROOT
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    src = ROOT / "fmu_src"
    exe = tmp_path / "cf_driver"
    subprocess.run([cc, "-O2", "-I", str(src), str(ROOT / "bench" / "cf_driver.c"),
                    *(str(src / f) for f in ("closed_form.c", "stepper.c", "sens.c", "model.c")), "-lm", "-o",
                    str(exe)], check=True)
    p = dict(UNDERDAMPED, wall=2, sigma=0.05)
    x0 = {"u0": -0.5, "v0": 1.0}
    out = tmp_path / "o.bin"
    args = [str(exe), "0", "30", "1", "1", str(out)] + [f"{k}={float(v)!r}" for k, v in
                                                         dict(p, **x0).items()]
    subprocess.run(args, check=True, capture_output=True)
    rec = np.fromfile(out).reshape(-1, 9)
    assert rec[-1, 2] > 0  # impacts happened
    fmu2.start(0.0, **p, **x0, solver=1, sensitivities=True)
    for k in range(30):
        fmu2.step(k + 1.0)
        J, S = fmu2.jac()
        assert np.array_equal(rec[k, :2], fmu2.state()) and rec[k, 2] == fmu2.impacts()
        assert np.array_equal(rec[k, 3:7], J.ravel()) and np.array_equal(rec[k, 7:], S)


def test_random_parameters_match_the_oracle(fmu2):
    """40 random cases (fixed seed) over damping regimes, walls, stiffnesses and restitutions:
    every wall event of the oracle is found (same counts), states within 1e-9 after 3 periods."""
    rng = np.random.default_rng(11)
    for _ in range(40):
        p = dict(nu=float(rng.uniform(0.05, 6.0)), Omega=float(rng.uniform(0.3, 9.0)),
                 sigma=float(rng.uniform(-0.05, 0.6)), r=float(rng.uniform(0.3, 1.0)),
                 Gamma=float(10 ** rng.uniform(0, 4)), wall=int(rng.integers(1, 3)))
        t0 = float(rng.uniform(0.0, 1.0))
        x0 = on_orbit(p["sigma"], t0)
        if p["wall"] == 2 and x0["u0"] >= 0.0:
            x0 = {"u0": -0.1, "v0": 0.0}
        fmu2.start(t0, **p, **x0, solver=1)
        fmu2.step(t0 + 3.0)
        u, v, c = oracle(p).state_at(x0["u0"], x0["v0"], t0, t0 + 3.0)
        assert fmu2.impacts() == c, p
        assert np.max(np.abs(fmu2.state() - (u, v))) <= 1e-9 * max(1.0, abs(v)), p
