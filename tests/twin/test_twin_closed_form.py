"""The pythonfmu twin alone against ``mapcheck.exact.ExactOscillator`` (closed form, sharing no
code with either FMU): one-period maps, 1e-9-deep grazing contacts at several phases, rigid
chatter ending in sticking, the local time origin at t = 1e6; and the grazing guard's locating
step, white box.
"""
from __future__ import annotations

import importlib.util
import math
import sys

import numpy as np
import pytest

from mapcheck.exact import ExactOscillator
from tests.support.twin import FIG9, THETA, TWIN_SRC, UNDERDAMPED, on_orbit


# ---------------------------------------------------------------------------------------------
# the twin alone against the closed form
# ---------------------------------------------------------------------------------------------
OCASES = [
    ("compliant", 0.2, FIG9, 10.0),
    ("compliant", 0.95, FIG9, 10.0),
    ("rigid", 0.02, FIG9, 10.0),
    ("none", 0.3, FIG9, 10.0),
    ("compliant", 0.05, UNDERDAMPED, 1000.0),
    ("rigid", 0.05, UNDERDAMPED, 1000.0),
]


@pytest.mark.parametrize("wall,sigma,lin,Gamma", OCASES)
def test_one_period_map_matches_closed_form(twin, wall, sigma, lin, Gamma) -> None:
    """Each one-period step of the twin, from its own state, against the exact map (so that
    any instability of the orbit cannot amplify the error)."""
    u0, v0 = on_orbit(THETA, sigma)
    twin.start(t0=THETA, wall=wall, sigma=sigma, Gamma=Gamma, u0=u0, v0=v0, **lin)
    osc = ExactOscillator(lin["nu"], lin["Omega"], sigma, r=0.9, Gamma=Gamma, wall=wall)
    worst, n_twin, n_exact = 0.0, 0, 0
    x, k = twin.state(), twin.impacts()
    for n in range(20):
        t = THETA + n
        exact, count = osc.strobe(x[0], x[1], [t + 1.0], t0=t)
        twin.step_to(t + 1.0)
        x, k_new = twin.state(), twin.impacts()
        worst = max(worst, float(np.max(np.abs(x - exact[0]))))
        n_twin += k_new - k
        n_exact += int(count[0])
        k = k_new
    assert worst <= 1e-8, f"worst one-period error {worst:.2e}"
    assert n_twin == n_exact
    if wall != "none":
        assert n_twin > 0, "the case was meant to hit the wall"


def test_whole_orbit_matches_closed_form(twin) -> None:
    """20 periods in one run, strobed, against the closed form from the same start."""
    sigma = 0.5
    u0, v0 = on_orbit(THETA, sigma)
    twin.start(t0=THETA, sigma=sigma, u0=u0, v0=v0, **FIG9)
    times = np.arange(1, 21) + THETA
    exact, counts = ExactOscillator(FIG9["nu"], FIG9["Omega"], sigma).strobe(u0, v0, times, THETA)
    got = []
    for t in times:
        twin.step_to(float(t))
        got.append(twin.state())
    assert np.max(np.abs(np.array(got) - exact)) < 1e-8
    assert twin.impacts() == counts[-1] > 0


@pytest.mark.parametrize("lin", [FIG9, UNDERDAMPED], ids=["overdamped", "underdamped"])
@pytest.mark.parametrize("wall", ["compliant", "rigid"])
@pytest.mark.parametrize("t0", [0.05, 0.3, 0.5, 0.77, 0.999])
def test_grazing_contact_1e9_deep_is_found(twin, wall, lin, t0) -> None:
    """On the wall-free orbit with sigma = 1e-9 the maximum pokes 1e-9 into the wall at t = 1,
    reached from several phases (the contact falls at different places in the solver's steps);
    with sigma = -1e-9 it misses by 1e-9 and no contact may be invented."""
    for depth, expected in [(1e-9, 1), (-1e-9, 0)]:
        u0, v0 = on_orbit(t0, depth)
        twin.start(t0=t0, wall=wall, sigma=depth, u0=u0, v0=v0, Gamma=1000.0, **lin)
        twin.step_to(1.5)
        assert twin.impacts() == expected, f"depth {depth}: {twin.impacts()} contacts"


def test_rigid_chatter_ends_in_sticking(twin) -> None:
    """Rigid wall, r = 0.5, leaving the wall slowly while the net force pushes in: impacts
    accumulate in finite time; the twin must stick (in_contact, u = v = 0), release when the
    force stops pushing, and count the oracle's impacts (to one: the oracle sticks below the
    same velocity, but a chatter impact that close to the threshold is a coin toss)."""
    sigma, r, t0, (u0, v0) = 0.3, 0.5, THETA, (0.0, -0.1)
    twin.start(t0=t0, wall="rigid", sigma=sigma, r=r, u0=u0, v0=v0, **FIG9)
    osc = ExactOscillator(FIG9["nu"], FIG9["Omega"], sigma, r=r, wall="rigid")
    kinds = [k for _, k in osc.crossings(u0, v0, t0, t0 + 3)]
    assert "stick" in kinds and "release" in kinds, "the case was meant to chatter"
    stuck_seen = False
    for t in np.arange(t0 + 0.02, t0 + 3, 0.02):
        twin.step_to(float(t))
        if twin.in_contact():
            stuck_seen = True
            assert np.all(twin.state() == 0.0)
    assert stuck_seen
    assert not twin.in_contact(), "released by the end"
    _, counts = osc.strobe(u0, v0, [twin.t], t0)
    assert abs(twin.impacts() - counts[0]) <= 1, (twin.impacts(), counts[0])


def test_local_time_origin_keeps_accuracy_at_t_1e6(twin) -> None:
    """Started at t = 10^6 + 1/2 the one-period map is as accurate as near t = 0 (the forcing
    phase is kept in an integer time origin plus a local time)."""
    sigma = 0.5
    osc = ExactOscillator(FIG9["nu"], FIG9["Omega"], sigma)
    errors = []
    for t0 in (THETA, 1e6 + THETA):
        u0, v0 = on_orbit(t0, sigma)
        twin.start(t0=t0, sigma=sigma, u0=u0, v0=v0, **FIG9)
        exact, counts = osc.strobe(u0, v0, [t0 + 1, t0 + 2, t0 + 3], t0=t0)
        got = []
        for k in (1, 2, 3):
            twin.step_to(t0 + k)
            got.append(twin.state())
        errors.append(float(np.max(np.abs(np.array(got) - exact))))
        assert twin.impacts() == counts[-1] > 0
    assert max(errors) < 1e-8, errors


# ---------------------------------------------------------------------------------------------
# the grazing guard's locating step (white box: at the default tolerances CVODE's own root
# finding on v already samples inside a shallow contact, so the guard is a backstop that the
# FMU-level tests above rarely reach)
# ---------------------------------------------------------------------------------------------
def test_guard_locates_a_stepped_over_crossing() -> None:
    """Hand the driver's locating step a free flight whose last good point lies before a 1e-6
    deep contact and a turning point past it: it must return the exact entry time."""
    # Loaded under another name: the twin FMU, running in this process, imports its own copy
    # as ``impact_twin_model`` and must not find this one in sys.modules. The parts it gathers
    # (twin_rules, twin_physics, twin_cvode) are imported by their names from the source folder.
    if str(TWIN_SRC) not in sys.path:
        sys.path.append(str(TWIN_SRC))
    spec = importlib.util.spec_from_file_location("twin_model_under_test",
                                                  TWIN_SRC / "impact_twin_model.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    CvodeDriver, OscillatorModel = mod.CvodeDriver, mod.OscillatorModel
    depth, t_good = 1e-6, 0.97
    m = OscillatorModel()
    m.wall, m.Gamma = 1, 1000.0
    m.set_real("sigma", depth)
    m.u0, m.v0 = on_orbit(t_good, depth)
    drv = CvodeDriver(m)
    drv.start(t_good)
    m.initialize_state(drv.tau)
    drv._reinit()
    found = drv._locate_missed_crossing(1.0)  # the maximum of u is at t = 1 (local time)
    assert found is not None
    tc, yc = found
    # exact entry: (1 + depth) cos(2 pi t) - 1 = 0 just before t = 1
    t_exact = 1.0 - math.acos(1.0 / (1.0 + depth)) / (2.0 * math.pi)
    assert abs(drv.origin + tc - t_exact) < 1e-9
    assert yc[0] >= 0.0 and yc[1] > 0.0
