"""Directional and adjoint derivatives in Initialization Mode (FMI 2.0 2.1.9, FMI 3.0 2.2.11):
the unknowns are the Real InitialUnknowns, the knowns the Real parameters and inputs their
dependencies name; the partials are those of the values read there, at the start values set so
far (never at the defaults' state the instance holds until it leaves Initialization Mode).

The truth: central differences of the initial unknowns themselves, read in Initialization Mode
with one known moved by +-h, at starts in flight, inside the compliant wall (linear, Hertz,
Hunt-Crossley) and sticking on the rigid wall; the contact starts are where partials taken at
the instance's stale state (free flight, u = -1) would be wrong.  And the errors: a known or an
unknown outside the declared dependencies, a NaN seed, each named, and the instance retried from
a state saved before the call, as the standards allow after Error.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Model, FMU2Slave
from fmpy.fmi3 import FMU3Model, FMU3Slave

from mapcheck.exact import forcing_amplitude_phase
from tests.support.fmu import FMU3_PATH, FMU_PATH, LoggedSlave

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112, Gamma=10.0)
UNDER = dict(nu=0.196, Omega=7.368, Gamma=1000.0)
INTEGERS = ("wall", "contact")
INTERFACES = ("fmi2-cs", "fmi2-me", "fmi3-cs", "fmi3-me")
#: the Real knowns of Initialization Mode: the Real parameters and inputs the InitialUnknowns
#: depend on (their union, read from the modelDescription in the test below)
KNOWNS = ("nu", "Omega", "sigma", "Gamma", "u0", "v0", "alpha_hc", "F_ext", "u_wall", "v_wall")
UNKNOWNS = ("F_g", "phi", "kappa", "u", "v", "der(u)", "der(v)", "F_contact", "v_impact",
            "t_impact", "J_uu", "S_v")


def _stick_t0(params: dict) -> float:
    """The start time at which the forcing pushes hardest into the wall: a start at rest on the
    rigid wall sticks."""
    _, phi = forcing_amplitude_phase(params["nu"], params["Omega"])
    return (-phi / (2 * math.pi)) % 1.0


#: (id, start time, start values, the knowns whose central difference keeps the contact mode)
POINTS = [
    ("flight", 0.3, dict(FIG9, wall=1, sigma=0.2, u0=-0.4, v0=0.3, F_ext=0.1, u_wall=0.05,
                         v_wall=0.02), KNOWNS),
    ("linear-contact", 0.0, dict(UNDER, wall=1, sigma=0.2, u0=0.3, v0=0.5, u_wall=0.05,
                                 v_wall=-0.1), KNOWNS),
    ("hertz-contact", 0.1, dict(UNDER, wall=1, contact=1, sigma=0.2, u0=0.3, v0=0.5,
                                u_wall=0.05, v_wall=0.2), KNOWNS),
    ("hunt-crossley-contact", 0.7, dict(UNDER, wall=1, contact=2, alpha_hc=0.15, sigma=0.2,
                                        u0=0.3, v0=0.5, u_wall=-0.05, v_wall=0.2, F_ext=0.4),
     KNOWNS),
    # at rest on the wall: moving u0, v0, u_wall or v_wall leaves the wall (another mode)
    ("stick", _stick_t0(FIG9), dict(FIG9, wall=2, sigma=0.2, u0=0.0, v0=0.0),
     ("nu", "Omega", "sigma", "Gamma", "alpha_hc", "F_ext")),
]


class InitInstance:
    """A fresh instance of one interface left in Initialization Mode at start time t0."""

    def __init__(self, interface: str, t0: float, params: dict) -> None:
        self.fmi3 = interface.startswith("fmi3")
        me = interface.endswith("me")
        path = FMU3_PATH if self.fmi3 else FMU_PATH
        md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        cls = {(False, True): FMU2Model, (False, False): FMU2Slave, (True, True): FMU3Model,
               (True, False): FMU3Slave}[(self.fmi3, me)]
        ident = (md.modelExchange if me else md.coSimulation).modelIdentifier
        self.fmu = cls(guid=md.guid, unzipDirectory=extract(str(path)), modelIdentifier=ident,
                       instanceName=interface)
        self.fmu.instantiate()
        if not self.fmi3:
            self.fmu.setupExperiment(startTime=t0)
        self.set(**params)
        if self.fmi3:
            self.fmu.enterInitializationMode(startTime=t0)
        else:
            self.fmu.enterInitializationMode()

    def set(self, **values: float) -> None:
        for k, x in values.items():
            if k in INTEGERS:
                (self.fmu.setInt32 if self.fmi3 else self.fmu.setInteger)([self.vr[k]], [int(x)])
            else:
                (self.fmu.setFloat64 if self.fmi3 else self.fmu.setReal)([self.vr[k]], [float(x)])

    def get(self, names) -> np.ndarray:
        vr = [self.vr[n] for n in names]
        return np.array(self.fmu.getFloat64(vr) if self.fmi3 else self.fmu.getReal(vr))

    def jacobian(self, unknowns, knowns) -> np.ndarray:
        u = [self.vr[n] for n in unknowns]
        k = [self.vr[n] for n in knowns]
        cols = [self.fmu.getDirectionalDerivative(u, k, list(np.eye(len(k))[j]))
                for j in range(len(k))]
        return np.array(cols).T

    def central_differences(self, params: dict, unknowns, knowns) -> np.ndarray:
        cols = []
        for k in knowns:
            x = float(params.get(k, 0.0 if k in ("F_ext", "u_wall", "v_wall") else
                                 {"alpha_hc": 0.15}.get(k, np.nan)))
            h = 1e-6 * max(1.0, abs(x))
            vals = []
            for s in (+1, -1):
                self.set(**{k: x + s * h})
                vals.append(self.get(unknowns))
            self.set(**{k: x})
            cols.append((vals[0] - vals[1]) / (2 * h))
        return np.array(cols).T

    def free(self) -> None:
        self.fmu.freeInstance()


def test_the_knowns_are_the_real_dependencies_of_the_initial_unknowns():
    """KNOWNS and UNKNOWNS above are what the modelDescription declares (both files)."""
    for path in (FMU_PATH, FMU3_PATH):
        md = read_model_description(str(path))
        init = [u for u in md.initialUnknowns if u.variable.type in ("Real", "Float64")]
        deps = {d.name for u in md.initialUnknowns for d in u.dependencies
                if d.type in ("Real", "Float64")}
        assert deps == set(KNOWNS), path
        assert set(UNKNOWNS) <= {u.variable.name for u in init}, path


@pytest.mark.parametrize("interface", INTERFACES)
@pytest.mark.parametrize("point", POINTS, ids=[p[0] for p in POINTS])
def test_initial_partials_equal_central_differences(interface, point):
    """Every Real initial unknown's partial w.r.t. every Real known, against central differences
    of the initial unknowns with the known moved (the knowns that keep the start's contact mode);
    the others are the mode's own partials (sticking: the holding force's)."""
    name, t0, params, smooth = point
    x = InitInstance(interface, t0, params)
    try:
        in_contact = (x.fmu.getBoolean([x.vr["in_contact"]])[0])
        assert bool(in_contact) == (name != "flight"), name
        J = x.jacobian(UNKNOWNS, KNOWNS)
        cols = [KNOWNS.index(k) for k in smooth]
        fd = x.central_differences(params, UNKNOWNS, smooth)
        scale = max(1.0, float(np.abs(J).max()))
        err = np.abs(J[:, cols] - fd).max()
        assert err <= 1e-6 * scale, (name, err, J[:, cols], fd)
        if name == "stick":  # the holding force forcing + F_ext - nu v_wall - Omega^2 (u_wall + 1)
            row = J[UNKNOWNS.index("F_contact")]
            assert row[KNOWNS.index("u_wall")] == pytest.approx(-params["Omega"] ** 2, rel=1e-15)
            assert row[KNOWNS.index("v_wall")] == pytest.approx(-params["nu"], rel=1e-15)
            assert not J[UNKNOWNS.index("der(v)")].any()
        if "contact" in name:  # F_contact depends on the start's depth: nonzero
            assert J[UNKNOWNS.index("F_contact"), KNOWNS.index("u0")] > 0.1
        # the adjoint (FMI 3.0) is the transpose
        if x.fmi3:
            w = np.linspace(-1.0, 1.0, len(UNKNOWNS))
            adj = x.fmu.getAdjointDerivative([x.vr[n] for n in UNKNOWNS],
                                             [x.vr[n] for n in KNOWNS], list(w),
                                             nSensitivity=len(KNOWNS))
            assert np.abs(np.array(adj) - J.T @ w).max() <= 1e-14 * scale * np.abs(w).sum()
    finally:
        x.free()


def test_initial_partials_follow_the_start_values_set_after_a_first_call():
    """A start value changed after a derivative was taken: the next derivative is taken at the new
    start (moved from flight into the compliant wall, F_contact's partial w.r.t. u0 goes from 0
    to kappa^2)."""
    x = InitInstance("fmi2-cs", 0.0, dict(UNDER, wall=1, u0=-0.4, v0=0.0))
    try:
        d = x.jacobian(["F_contact"], ["u0"])[0, 0]
        assert d == 0.0
        x.set(u0=0.3)
        d = x.jacobian(["F_contact"], ["u0"])[0, 0]
        assert d == pytest.approx(UNDER["Gamma"] * UNDER["Omega"] ** 2, rel=1e-14)
        x.fmu.exitInitializationMode()
    finally:
        x.free()


BAD_CALLS = [  # (unknowns, knowns, what the message names)
    (["der(v)"], ["r"], "r"),  # a parameter no initial unknown depends on
    (["der(v)"], ["wall"], "wall"),  # an Integer: no derivative
    (["in_contact"], ["u0"], "in_contact"),  # a Boolean initial unknown
    (["sigma"], ["u0"], "sigma"),  # a parameter is no unknown
]


@pytest.mark.parametrize("interface", INTERFACES)
@pytest.mark.parametrize("bad", BAD_CALLS, ids=[b[2] for b in BAD_CALLS])
def test_a_call_outside_the_dependencies_fails_and_the_instance_is_retried(interface, bad):
    """Error, and the instance restored from an FMU state saved before the call (FMI 2.0 from
    Error, FMI 3.0 from Terminated) is in Initialization Mode again: the right call works and
    initialisation completes."""
    unknowns, knowns, _ = bad
    params = dict(UNDER, wall=1, u0=0.3, v0=0.5)
    x = InitInstance(interface, 0.0, params)
    try:
        saved = x.fmu.getFMUState() if x.fmi3 else x.fmu.getFMUstate()
        with pytest.raises(Exception):
            x.jacobian(unknowns, knowns)
        (x.fmu.setFMUState if x.fmi3 else x.fmu.setFMUstate)(saved)
        J = x.jacobian(["F_contact"], ["u0"])
        assert J[0, 0] == pytest.approx(UNDER["Gamma"] * UNDER["Omega"] ** 2, rel=1e-14)
        x.fmu.exitInitializationMode()
    finally:
        x.free()


@pytest.mark.parametrize("init", [True, False], ids=["initialization-mode", "step-mode"])
def test_a_nan_seed_is_named(init):
    fmu = LoggedSlave()
    fmu.set(**dict(UNDER, wall=1, u0=0.3, v0=0.5))
    fmu.slave.setupExperiment(startTime=0.0)
    fmu.slave.enterInitializationMode()
    if not init:
        fmu.slave.exitInitializationMode()
    knowns = ["u0", "v0"] if init else ["u", "v"]
    with pytest.raises(Exception):
        fmu.slave.getDirectionalDerivative([fmu.vr["der(v)"]], [fmu.vr[k] for k in knowns],
                                           [1.0, float("nan")])
    text = " ".join(m[2] for m in fmu.messages)
    assert f"seed[1] = nan for the known {knowns[1]} is not finite" in text, text
    fmu.slave.freeInstance()
