"""Directional and adjoint derivatives through fmpy's calls (FMI 2 and 3, ME and CS).

Three truths, none of them the FMU's own partials: central differences of the FMU's getters
(derivatives, outputs, the event indicator) with the states or inputs moved; the closed form of
the linear flow (the generator matrix log P(t)/t of mapcheck.linear's propagator, the paper's
(7) with k2 = Omega^2 in flight, Omega^2 + kappa^2 inside the linear wall) and the contact laws as
docs/fmu.md writes them; and, for the adjoint, the transpose of the directional derivative.
The states of each grid cross every contact region: in flight, inside the wall, on it, the far
side of it with the mode unchanged (as an importer's trial state between events), sticking.
"""
from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from fmpy import read_model_description
from scipy.linalg import logm

from mapcheck.exact import forcing_amplitude_phase
from mapcheck.linear import propagator_k2
from tests.support.derivatives import INTERFACES, KNOWNS, Instance
from tests.support.fmu import FMU3_PATH, FMU_PATH

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112, Gamma=10.0)
UNDER = dict(nu=0.196, Omega=7.368, Gamma=1000.0)
#: (id, parameters): every contact law, both linear regimes, no wall, both solvers
CASES = [
    ("fig9-linear", dict(FIG9, wall=1, contact=0)),
    ("fig9-linear-closed-form-solver", dict(FIG9, wall=1, contact=0, solver=1)),
    ("under-linear", dict(UNDER, wall=1, contact=0)),
    ("under-hertz", dict(UNDER, wall=1, contact=1)),
    ("under-hunt-crossley", dict(UNDER, wall=1, contact=2, alpha_hc=0.15)),
    ("fig9-rigid", dict(FIG9, wall=2)),
    ("fig9-none", dict(FIG9, wall=0)),
]
RHS = ("der(u)", "der(v)", "F_contact")
U_GRID = (-1.5, -0.3, -1e-3, 0.0, 1e-3, 0.05, 0.4)
V_GRID = (-2.0, 0.0, 0.7)
INPUTS = ((0.0, 0.0, 0.0), (0.8, -0.05, 0.3))  # (F_ext, u_wall, v_wall)


def _start(params: dict, inside: bool) -> dict:
    """A start whose contact mode is inside the wall (inside) or in flight."""
    if params["wall"] == 2:
        return dict(params, u0=-0.4, v0=0.0)  # inside the rigid wall is no state
    return dict(params, u0=0.3 if inside else -0.4, v0=0.0)


def _stick_start(params: dict) -> tuple[float, dict]:
    """t0 and a start at rest on the rigid wall while the forcing pushes hardest: sticking."""
    _, phi = forcing_amplitude_phase(params["nu"], params["Omega"])
    return (-phi / (2 * math.pi)) % 1.0, dict(params, wall=2, u0=0.0, v0=0.0)


def _instances(interface: str, params: dict):
    """Instances in each contact mode the parameters allow (ME: the states then move freely)."""
    yield Instance(interface, **_start(params, inside=False))
    if params["wall"] == 1:
        yield Instance(interface, **_start(params, inside=True))
    if params["wall"] == 2:
        t0, start = _stick_start(params)
        x = Instance(interface, t0=t0, **start)
        assert x.integer("in_contact") == 1, "meant to stick"
        yield x


def _unknowns(x: Instance) -> tuple[str, ...]:
    return RHS + ("wall_indicator",) if x.fmi3 else RHS


def _read(x: Instance, unknowns) -> np.ndarray:
    """The unknowns from the FMU's own getters (der(u), der(v) through the derivative call)."""
    der = x.derivatives()
    rest = x.get(*unknowns[2:])
    return np.concatenate([der, rest])


def _central_differences(x: Instance, unknowns, state, inputs) -> np.ndarray:
    """d unknowns / d (u, v, F_ext, u_wall, v_wall) by central differences of the getters."""
    u, v = state
    f, w, vw = inputs
    cols = []
    for j in range(5):
        point = np.array([u, v, f, w, vw])
        h = 1e-6 * max(1.0, abs(point[j]))
        vals = []
        for s in (+1, -1):
            p = point.copy()
            p[j] += s * h
            x.set_states(p[0], p[1])
            x.set_inputs(F_ext=p[2], u_wall=p[3], v_wall=p[4])
            vals.append(_read(x, unknowns))
        cols.append((vals[0] - vals[1]) / (2 * h))
    x.set_states(u, v)
    x.set_inputs(F_ext=f, u_wall=w, v_wall=vw)
    return np.array(cols).T


def _law(params: dict, d: float, dv: float) -> tuple[float, float]:
    """dF/dd and dF/dd' of the contact laws as docs/fmu.md writes them (F = kappa^2 d,
    kappa^2 d^(3/2), kappa^2 d^(3/2) (1 + alpha_hc d'))."""
    k2 = params["Gamma"] * params["Omega"] ** 2
    law = params.get("contact", 0)
    if law == 0:
        return k2, 0.0
    if d <= 0:
        return 0.0, 0.0
    a = params.get("alpha_hc", 0.0) if law == 2 else 0.0
    return 1.5 * k2 * math.sqrt(d) * (1 + a * dv), k2 * d ** 1.5 * a


@functools.lru_cache(maxsize=None)  # one matrix logarithm per regime, not one per grid point
def _generator(nu: float, k2: float) -> np.ndarray:
    """The closed form's generator matrix: log P(t) / t of the exact propagator (the paper's (7))."""
    t = 0.5 / math.sqrt(k2 + nu * nu)  # a rotation angle below pi: the principal logarithm
    return np.real(logm(propagator_k2(t, nu, k2))) / t


def _exact(params: dict, mode: str, state, inputs, fmi3: bool) -> np.ndarray:
    """The partials from the closed form (linear regimes) and the laws (Hertz)."""
    nu, O2 = params["nu"], params["Omega"] ** 2
    rows = np.zeros((4, 5))
    if mode == "stick":
        rows[0, 4] = 1.0  # carried by the wall: der(u) = v_wall
        # the holding force forcing + F_ext - nu v_wall - O2 (w + 1)
        rows[2, 2:] = rows[3, 2:] = (1.0, -O2, -nu)
        return rows if fmi3 else rows[:3]
    rows[:2, :2] = _generator(nu, O2)
    rows[1, 2] = 1.0
    if params["wall"] != 0:
        rows[3] = (1.0, 0.0, 0.0, -1.0, 0.0)  # g0 = u - w
    if mode == "contact":
        Fd, Fdv = _law(params, state[0] - inputs[1], state[1] - inputs[2])
        if params.get("contact", 0) == 0:
            rows[:2, :2] = _generator(nu, O2 + Fd)
        else:
            rows[1, :2] -= (Fd, Fdv)
        rows[1, 3:] = (Fd, Fdv)
        rows[2] = (Fd, Fdv, 0.0, -Fd, -Fdv)
    return rows if fmi3 else rows[:3]


def _mode(x: Instance, params: dict) -> str:
    if x.integer("in_contact") == 0:
        return "free"
    return "stick" if params["wall"] == 2 else "contact"


def _scale(a: np.ndarray) -> float:
    return max(1.0, float(np.abs(a).max()))


def _grid(x):
    """Put ``x`` at every state of U_GRID x V_GRID with every input pair of INPUTS (crossing
    each contact region); yields (u, v, inputs) at each."""
    for u in U_GRID:
        for v in V_GRID:
            for inputs in INPUTS:
                x.set_states(u, v)
                x.set_inputs(F_ext=inputs[0], u_wall=inputs[1], v_wall=inputs[2])
                yield u, v, inputs


@pytest.mark.parametrize("interface", ["fmi2-me", "fmi3-me"])
@pytest.mark.parametrize("case,params", CASES, ids=[c[0] for c in CASES])
def test_model_exchange_partials_equal_differences_and_the_closed_form(interface, case, params):
    for x in _instances(interface, params):
        mode, unknowns = _mode(x, params), _unknowns(x)
        try:
            for u, v, inputs in _grid(x):
                J = x.jacobian(unknowns)
                exact = _exact(params, mode, (u, v), inputs, x.fmi3)
                assert np.abs(J - exact).max() <= 1e-11 * _scale(exact), (mode, u, v)
                d = u - inputs[1]
                if params.get("contact", 0) and mode == "contact" and abs(d) < 1e-2:
                    continue  # d^(3/2): a difference across d = 0 is not a derivative
                fd = _central_differences(x, unknowns, (u, v), inputs)
                assert np.abs(J - fd).max() <= 1e-6 * _scale(J), (mode, u, v, J, fd)
        finally:
            x.close()


@pytest.mark.parametrize("interface", ["fmi2-cs", "fmi3-cs"])
@pytest.mark.parametrize("case,params", CASES, ids=[c[0] for c in CASES])
def test_co_simulation_partials_at_starts_in_every_region_equal_the_closed_form(interface, case,
                                                                                 params):
    """Co-Simulation has no state setter: the starts (u0, v0) put the instance in each region;
    the inputs' columns are also checked against differences of the F_contact output."""
    starts = [(u0, v0) for u0 in (-0.6, -1e-3, 0.02, 0.4) for v0 in (-1.0, 0.5)]
    for u0, v0 in starts:
        if params["wall"] == 2 and u0 > 0:
            continue
        x = Instance(interface, **dict(params, u0=u0, v0=v0))
        try:
            J = x.jacobian(_unknowns(x))
            exact = _exact(params, _mode(x, params), (u0, v0), (0.0, 0.0, 0.0), x.fmi3)
            assert np.abs(J - exact).max() <= 1e-11 * _scale(exact), (u0, v0)
            if params.get("contact", 0) and abs(u0) < 1e-2:
                continue
            for j, name in ((2, "F_ext"), (3, "u_wall"), (4, "v_wall")):
                h = 1e-6
                vals = []
                for s in (+1, -1):
                    x.set_inputs(**{name: s * h})
                    vals.append(x.get("F_contact")[0])
                x.set_inputs(**{name: 0.0})
                fd = (vals[0] - vals[1]) / (2 * h)
                assert abs(J[2, j] - fd) <= 1e-6 * _scale(J), (u0, v0, name)
            assert np.array_equal(x.jacobian(("u", "v")), np.eye(len(KNOWNS))[:2])
        finally:
            x.close()


@pytest.mark.parametrize("interface", ["fmi3-me", "fmi3-cs"])
@pytest.mark.parametrize("case,params", CASES, ids=[c[0] for c in CASES])
def test_the_adjoint_is_the_transpose_of_the_directional_derivative(interface, case, params):
    rng = np.random.default_rng(7)
    for x in _instances(interface, params):
        try:
            unknowns = _unknowns(x)
            for _ in range(6):
                if x.me:
                    x.set_states(*rng.uniform(-1.5, 0.5, 2))
                J = x.jacobian(unknowns)
                w = rng.normal(size=len(unknowns))
                adj = x.adjoint(unknowns, KNOWNS, w)
                assert np.abs(adj - J.T @ w).max() <= 1e-14 * _scale(J) * np.abs(w).sum()
                # a subset of the knowns in another order: the same columns
                sub = ("u_wall", "v")
                assert np.allclose(x.adjoint(unknowns, sub, w), (J.T @ w)[[3, 1]], rtol=0,
                                   atol=1e-14 * _scale(J) * np.abs(w).sum())
        finally:
            x.close()


def _declared(path) -> dict[str, set[str]]:
    """The ModelStructure's dependencies of each Real unknown, by names (the Integer and Boolean
    outputs declare none; FMI's directional derivatives are of Real variables)."""
    md = read_model_description(str(path))
    groups = [md.outputs, md.derivatives] + ([md.eventIndicators] if path == FMU3_PATH else [])
    out = {}
    for unknown in (u for g in groups for u in g):
        if unknown.variable.type not in ("Real", "Float64"):
            assert unknown.dependencies == [], unknown.variable.name
            continue
        deps = unknown.dependencies
        assert deps is not None, f"{unknown.variable.name}: dependencies not declared"
        out[unknown.variable.name] = {d.name for d in deps}
    return out


@pytest.mark.parametrize("interface", ["fmi2-me", "fmi3-me"])
def test_declared_dependency_pattern_equals_the_measured_one(interface):
    """A declared dependency is non-zero somewhere on the grids of every case; one that is not
    declared is zero everywhere (the discrete outputs: no dependency at all)."""
    declared = _declared(FMU3_PATH if interface == "fmi3-me" else FMU_PATH)
    measured: dict[str, set[str]] = {name: set() for name in declared}
    for _, params in CASES:
        for x in _instances(interface, params):
            try:
                for _ in _grid(x):
                    names = tuple(declared)
                    J = x.jacobian(names)
                    for i, name in enumerate(names):
                        measured[name] |= {KNOWNS[j] for j in np.flatnonzero(J[i])}
            finally:
                x.close()
    assert measured == declared


@pytest.mark.parametrize("interface", INTERFACES)
def test_a_parameter_is_no_known_and_the_error_names_it(interface):
    x = Instance(interface, **dict(FIG9, wall=1))
    try:
        with pytest.raises(Exception):
            x.fmu.getDirectionalDerivative([20], [2], [1.0])  # d der(v) / d sigma: not offered
    finally:
        x.fmu.freeInstance()


def _initial_values(md, unzipped: str, t0: float, params: dict, names) -> np.ndarray:
    """The Real initial unknowns `names` read in Initialization Mode of a fresh FMI 2.0 instance
    with the start values `params`."""
    from fmpy.fmi2 import FMU2Slave
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s = FMU2Slave(guid=md.guid, unzipDirectory=unzipped,
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="init")
    s.instantiate()
    try:
        s.setupExperiment(startTime=t0)
        for k, x in params.items():
            if k in ("wall", "contact"):
                s.setInteger([vr[k]], [int(x)])
            else:
                s.setReal([vr[k]], [float(x)])
        s.enterInitializationMode()
        return np.array(s.getReal([vr[n] for n in names]))
    finally:
        s.freeInstance()


def _init_points() -> list[tuple[float, dict]]:
    """Starts in flight, inside the linear and the Hunt-Crossley wall, sticking, and sticking
    exactly where the holding force vanishes (where the knowns of the mode decision act)."""
    nu, Omega, sigma = FIG9["nu"], FIG9["Omega"], 0.2
    F_g, phi = forcing_amplitude_phase(nu, Omega)
    t_edge = (math.acos(Omega ** 2 / ((1 + sigma) * F_g)) - phi) / (2 * math.pi) % 1.0
    t_push, stick = _stick_start(dict(FIG9, wall=2))
    return [(0.0, dict(FIG9, wall=1, u0=-0.4, v0=0.3, F_ext=0.1, u_wall=0.05)),
            (0.0, dict(UNDER, wall=1, u0=0.3, v0=0.5, u_wall=0.05)),
            (0.0, dict(UNDER, wall=1, contact=2, alpha_hc=0.15, u0=0.3, v0=0.5)),
            (t_push, dict(stick, sigma=sigma)),
            (t_edge, dict(FIG9, wall=2, sigma=sigma, u0=0.0, v0=0.0))]


def test_declared_initial_unknowns_are_the_measured_dependencies():
    """Initialization Mode, FMI 2.0: an initial unknown changes under a change of a Real known
    (a parameter or input, +-1e-6 relative, 1e-6 from 0) at some start of the list iff it is declared to
    depend on it; the Integer knowns (wall, contact) are left out (no value between)."""
    from fmpy import extract
    md = read_model_description(str(FMU_PATH))
    unzipped = extract(str(FMU_PATH))
    init = {u.variable.name: {d.name for d in u.dependencies} for u in md.initialUnknowns
            if u.variable.type == "Real"}
    knowns = [v.name for v in md.modelVariables if v.type == "Real"
              and v.causality in ("parameter", "input")]
    names = list(init)
    measured: dict[str, set[str]] = {n: set() for n in names}
    for t0, params in _init_points():
        base = dict({k: v.start for v in md.modelVariables for k in [v.name]
                     if v.name in knowns and v.start is not None}, **params)
        for k in knowns:
            x = float(base[k])
            h = 1e-6 * abs(x) if x else 1e-6  # relative: rtol and atol are 1e-12, 1e-14
            vals = [_initial_values(md, unzipped, t0, dict(base, **{k: x + s * h}), names)
                    for s in (+1, -1)]
            for i, n in enumerate(names):
                if vals[0][i] != vals[1][i]:
                    measured[n].add(k)
    assert measured == {n: {d for d in init[n] if d in knowns} for n in names}
