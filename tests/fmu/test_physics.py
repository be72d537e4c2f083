"""The C FMU against the closed-form solution of the piecewise-linear ODE (mapcheck.exact).

The oracle is exact between crossings and finds crossings by bracketing on the closed form,
split at turning points: an independent implementation sharing no code with the FMU.
"""
from __future__ import annotations

import numpy as np
import pytest

from mapcheck.exact import ExactOscillator
from tests.support.fmu import LoggedSlave

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112)
UNDERDAMPED = dict(nu=0.196, Omega=7.368)
THETA = 0.5  # sample half a period away from the grazing phase t = n


@pytest.fixture(scope="module")
def fmu(module_fmu: LoggedSlave) -> LoggedSlave:
    return module_fmu


def one_period_errors(fmu: LoggedSlave, periods: int, wall: str, sigma: float, r: float = 0.9,
                      Gamma: float = 10.0, **lin: float) -> tuple[np.ndarray, int, int]:
    """Run the FMU from rest and compare each one-period step with the exact map from the
    FMU's own state (so that the error does not grow with any instability of the orbit).

    Returns the per-period errors max(|du|, |dv|), and the FMU's and the oracle's impact totals.
    """
    fmu.start(t0=THETA, wall=wall, sigma=sigma, r=r, Gamma=Gamma, u0=-1.0, v0=0.0, **lin)
    osc = ExactOscillator(lin["nu"], lin["Omega"], sigma, r=r, Gamma=Gamma, wall=wall)
    errors, n_fmu, n_exact = [], 0, 0
    x, k = fmu.state(), fmu.impacts()
    for n in range(periods):
        t = THETA + n
        exact, count = osc.strobe(x[0], x[1], [t + 1.0], t0=t)
        fmu.step_to(t + 1.0)
        x_new, k_new = fmu.state(), fmu.impacts()
        errors.append(np.max(np.abs(x_new - exact[0])))
        n_fmu += k_new - k
        n_exact += int(count[0])
        x, k = x_new, k_new
    return np.array(errors), n_fmu, n_exact


CASES = [
    ("compliant", 0.2, FIG9, 10.0),      # period-3 window
    ("compliant", 0.5, FIG9, 10.0),      # period-2 window
    ("compliant", 0.95, FIG9, 10.0),     # period 1
    ("rigid", 0.02, FIG9, 10.0),
    ("none", 0.3, FIG9, 10.0),
    ("compliant", 0.05, UNDERDAMPED, 1000.0),
    ("compliant", -0.05, UNDERDAMPED, 1000.0),
    ("rigid", 0.05, UNDERDAMPED, 1000.0),
    ("none", 0.1, UNDERDAMPED, 1000.0),
]


@pytest.mark.parametrize("wall,sigma,lin,Gamma", CASES)
def test_one_period_map_matches_closed_form(fmu, wall, sigma, lin, Gamma):
    errors, n_fmu, n_exact = one_period_errors(fmu, 30, wall, sigma, Gamma=Gamma, **lin)
    assert errors.max() <= 1e-8, f"worst one-period error {errors.max():.2e}"
    assert n_fmu == n_exact
    if wall != "none" and sigma > 0:
        assert n_fmu > 0, "the case was meant to hit the wall"


def test_whole_orbit_matches_closed_form(fmu):
    """Not only one-period steps: 20 periods in one run, strongly damped (errors cannot grow)."""
    lin, sigma = FIG9, 0.5
    fmu.start(t0=0.0, sigma=sigma, u0=-1.0, v0=0.0, **lin)
    times = np.arange(1, 21) + THETA
    exact, counts = ExactOscillator(lin["nu"], lin["Omega"], sigma).strobe(-1.0, 0.0, times)
    got = []
    for t in times:
        fmu.step_to(float(t))
        got.append(fmu.state())
    assert np.max(np.abs(np.array(got) - exact)) < 1e-8
    assert fmu.impacts() == counts[-1]


@pytest.mark.parametrize("lin", [FIG9, UNDERDAMPED], ids=["overdamped", "underdamped"])
@pytest.mark.parametrize("wall", ["compliant", "rigid"])
@pytest.mark.parametrize("t0", [0.05, 0.3, 0.5, 0.77, 0.999])
def test_grazing_contact_1e9_deep_is_found(wall, lin, t0):
    """Start on the wall-free periodic orbit p(t) = (1+sigma) cos(2 pi t) - 1 with sigma = 1e-9:
    its maximum pokes 1e-9 into the wall at t = 1, reached from several starting phases (so the
    contact falls at different places in the solver's steps). With sigma = -1e-9 it misses the wall
    by 1e-9, and no contact may be invented."""
    fmu = LoggedSlave(name="graze", logging=True)
    try:
        for depth, expected in [(1e-9, 1), (-1e-9, 0)]:
            u0 = (1 + depth) * np.cos(2 * np.pi * t0) - 1
            v0 = -(1 + depth) * 2 * np.pi * np.sin(2 * np.pi * t0)
            fmu.messages.clear()
            fmu.start(t0=t0, wall=wall, sigma=depth, u0=u0, v0=v0, Gamma=1000.0, **lin)
            fmu.step_to(1.5)
            assert fmu.impacts() == expected, f"depth {depth}: {fmu.impacts()} contacts"
        assert not fmu.errors()
    finally:
        fmu.close()


def test_accuracy_does_not_decay_over_1e4_periods(fmu):
    """The one-period map error after 10^4 periods is as small as after 10 (the forcing phase is
    kept in a local time origin)."""
    lin, sigma = FIG9, 0.5
    fmu.start(t0=THETA, sigma=sigma, u0=-1.0, v0=0.0, **lin)
    osc = ExactOscillator(lin["nu"], lin["Omega"], sigma)

    def error_of_next_period() -> float:
        x, t = fmu.state(), fmu.t
        t_loc = t - np.floor(t)  # the ODE is 1-periodic in t; keep the oracle's clock small
        exact, _ = osc.strobe(x[0], x[1], [t_loc + 1.0], t0=t_loc)
        fmu.step_to(t + 1.0)
        return float(np.max(np.abs(fmu.state() - exact[0])))

    fmu.step_to(THETA + 10)
    early = max(error_of_next_period() for _ in range(3))
    fmu.step_to(THETA + 10_000)
    late = max(error_of_next_period() for _ in range(3))
    assert early < 1e-8 and late < 1e-8
    assert late < 10 * max(early, 1e-11)


def test_rigid_chatter_ends_in_sticking_not_a_hang(fmu):
    """Released just off a rigid wall while the drive pushes into it, the mass chatters: impacts
    accumulate in finite time. The FMU must stick (in_contact, u = v = 0), release when the force
    stops pushing, and agree with the oracle on the impact count and the release time."""
    import math
    from mapcheck.exact import forcing_amplitude_phase
    lin, sigma = FIG9, 0.3
    _, phi = forcing_amplitude_phase(lin["nu"], lin["Omega"])
    t0 = (-phi / (2 * math.pi)) % 1 - 0.15  # just before the phase of maximal push
    for r in (0.5, 0.8):
        fmu.start(t0=t0, wall="rigid", sigma=sigma, r=r, u0=-0.01, v0=0.0, **lin)
        osc = ExactOscillator(lin["nu"], lin["Omega"], sigma, r=r, wall="rigid")
        events = osc.crossings(-0.01, 0.0, t0, t0 + 1.0)
        kinds = [k for _, k in events]
        assert kinds.count("stick") == 1 and kinds.count("release") == 1, "meant to chatter"
        t_stick = next(t for t, k in events if k == "stick")
        t_release = next(t for t, k in events if k == "release")
        # chatter accumulates at t_stick (a Zeno point): the FMU must get there too
        fmu.step_to(t_stick - 1e-6)
        assert not fmu.in_contact()
        fmu.step_to(t_stick + 1e-6)
        assert fmu.in_contact() and np.all(fmu.state() == 0.0)
        fmu.step_to(t_release - 1e-6)
        assert fmu.in_contact()
        fmu.step_to(t_release + 1e-6)
        assert not fmu.in_contact() and fmu.state()[0] < 0.0
        fmu.step_to(t0 + 1.0)
        _, counts = osc.strobe(-0.01, 0.0, [t0 + 1.0], t0=t0)
        # The count of a Zeno sequence depends on where it is truncated: its last impacts are
        # 1e-9-sized and their number is set by the stick threshold and round-off, not by the
        # physics. The two must agree to within one decade of impact velocity.
        decade = math.log(10) / math.log(1 / r)
        assert abs(fmu.impacts() - counts[0]) <= decade, (fmu.impacts(), counts[0])
