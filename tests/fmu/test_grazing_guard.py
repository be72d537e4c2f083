"""The rescue of a stepped-over wall crossing (solver_cvode.c, ``rescue``), forced and observed.

The CVODE driver has two defences against a lost crossing: the root values are floored
(``ROOT_FLOOR``: SUNDIALS decides "sign change" by the product glo*ghi, which underflows to 0 for a
mass restarted ON_WALL = 1e-300 off the wall that crosses by less than 1e-24), and every step end,
communication point and turning point is checked for the wall side, a state on the wrong side being
sent to ``rescue``, which locates the crossing and counts it in ``guard_hits`` (logged under
logEvents as "... N of them recovered by the rescue of a stepped-over crossing").

With the floor in place the rescue is a backstop that no resolvable contact reaches: a search
over 1e-12 .. 1e-4 deep grazing contacts at 25 phases, rtol 1e-12 .. 1e-4, both walls and both
damping cases, and 7,829 random runs with 71,978 wall events (walls, contact laws, r, sigma,
rtol, moving walls, step sizes) never ran it.  The reason: a contact that enters and leaves within one CVODE step changes the sign
of the velocity indicator g1, and CVODE's search for that turning point converges onto it, i.e.
into the contact, where its trial point shows g0's sign change, so CVODE locates the entry itself.

So the path is forced by the FMU built without the floor (CMake ``IMPACT_NO_ROOT_FLOOR``, the same
sources with ROOT_FLOOR = 0): then the crossings that follow a restart on the wall are invisible
to CVODE and the rescue alone finds them.  Those are the grazing contacts proper, entries at zero
relative velocity: on a compliant wall with r = 0 every entry is one (the mass enters with v = 0
at u = 1e-300 and leaves at once, 1e-24 or less beyond the wall); on a rigid wall the last
impacts of a chatter sequence, whose rebounds are too small to leave the wall by more than that.
Each case is checked period by period against the closed form (mapcheck.exact): the state, and
the impact count (exact on the compliant wall; on the rigid wall within the chatter allowance
of test_fmu_events_total, the closed form's own Zeno truncation); and the log must show the
rescue ran.  The release build runs the same cases (the floor finds them; the rescue does not
run): both must agree with the closed form.
"""
from __future__ import annotations

import math
import shutil
import subprocess

import numpy as np
import pytest

from mapcheck.exact import ExactOscillator
from tests.support.fmu import EVENTS_LOG, FMU_PATH, ROOT, LoggedSlave, on_orbit
from tests.fmu.test_events_total import BUDGET, allowance

FIG9 = dict(nu=4.605170185988091, Omega=0.3059238689620112)
UNDERDAMPED = dict(nu=0.196, Omega=7.368)
NOFLOOR = ROOT / "build" / "nofloor"

# compliant, r = 0: every entry is at zero relative velocity (linear part, Gamma, sigma, phase)
COMPLIANT = [(lin, Gamma, sigma, t0) for lin, Gamma in ((FIG9, 10.0), (UNDERDAMPED, 1000.0))
             for sigma in (0.05, 0.2, 0.5) for t0 in (0.3, 0.5, 0.7)]
# rigid chatter that ends in sticking (r, sigma, u0; start at rest at t = 0)
RIGID = [(r, sigma, u0) for r in (0.1, 0.2, 0.3) for sigma in (5.0, 10.0) for u0 in (-0.02, -0.03, -0.05)]


@pytest.fixture(scope="module")
def builds():
    """The release FMU and the one without the floor (built here: a few seconds)."""
    cache = NOFLOOR / "CMakeCache.txt"
    if NOFLOOR.is_symlink():  # a copy of the tree (scripts/mutants.py) builds its own
        NOFLOOR.unlink()
    elif cache.is_file() and f"CMAKE_HOME_DIRECTORY:INTERNAL={ROOT / 'fmu_src'}\n" not in cache.read_text():
        shutil.rmtree(NOFLOOR)  # configured for another tree's sources
    if not cache.is_file():
        subprocess.run(["cmake", "-S", str(ROOT / "fmu_src"), "-B", str(NOFLOOR),
                        "-DIMPACT_NO_ROOT_FLOOR=ON", "-DCMAKE_BUILD_TYPE=Release"],
                       check=True, capture_output=True)
    subprocess.run(["cmake", "--build", str(NOFLOOR), "-j", "2", "--target",
                    "ImpactOscillator_archive"], check=True, capture_output=True)
    return {"release": FMU_PATH, "no-floor": NOFLOOR / "ImpactOscillator.fmu"}


def _run(path, wall: str, lin: dict, sigma: float, r: float, Gamma: float, t0: float, u0: float,
         v0: float, periods: int) -> tuple[int, int, int, int]:
    """Steps one period per doStep, each against the closed form started from the FMU's state;
    returns (impacts, wall events and rescues the log reports, largest count difference)."""
    fmu = LoggedSlave(path=path, name="guard", logging=True)
    try:
        fmu.start(t0=t0, wall=wall, sigma=sigma, r=r, Gamma=Gamma, u0=u0, v0=v0, **lin)
        fmu.slave.setDebugLogging(True, ["logEvents"])
        osc = ExactOscillator(lin["nu"], lin["Omega"], sigma, r=r, Gamma=Gamma, wall=wall)
        x, k, worst = fmu.state(), fmu.impacts(), 0
        for n in range(periods):
            t = t0 + n
            fmu.step_to(t + 1.0)
            exact, count = osc.strobe(x[0], x[1], [t + 1.0], t0=t)
            got, k_new = fmu.state(), fmu.impacts()
            err = float(np.max(np.abs(got - exact[0])))
            if err > BUDGET:
                assert err <= allowance(osc, x, t), (n, err, got, exact[0])
            worst = max(worst, abs((k_new - k) - int(count[0])))
            x, k = got, k_new
        assert not fmu.errors()
        logged = [EVENTS_LOG.search(m) for _, c, m in fmu.messages if c == "logEvents"]
        events = sum(int(m.group(1)) for m in logged if m)
        rescued = sum(int(m.group(2)) for m in logged if m)
        return k, events, rescued, worst
    finally:
        fmu.close()


@pytest.mark.parametrize("build", ["release", "no-floor"])
def test_zero_velocity_entries_into_the_compliant_wall(builds, build):
    """r = 0 on the compliant wall, 18 cases (both damping cases, sigma 0.05 .. 0.5, 3 phases of
    the start on the wall-free orbit), 10 periods each: every entry is found at its time (the
    state after each period against the closed form) and the counts are exact (no chatter: one
    entry per contact).  Without the floor every one of them is the rescue's."""
    total = 0
    for lin, Gamma, sigma, t0 in COMPLIANT:
        start = on_orbit(sigma, t0)
        k, events, rescued, worst = _run(builds[build], "compliant", lin, sigma, 0.0, Gamma, t0,
                                         start["u0"], start["v0"], 10)
        assert worst == 0, (lin, sigma, t0)
        assert k > 0 and events >= k, (lin, sigma, t0, k, events)
        total += k
        if build == "no-floor":
            assert rescued > 0, (lin, sigma, t0)  # the rescue ran in every case
    assert total >= len(COMPLIANT)


@pytest.mark.parametrize("build", ["release", "no-floor"])
def test_the_last_impacts_of_rigid_chatter(builds, build):
    """Rigid wall, chatter into sticking (r 0.1 .. 0.3, sigma 5 and 10, three starts at rest),
    3 periods: the state after each period against the closed form; counts within the chatter
    allowance ln 10 / ln(1/r) (the closed form's and the FMU's Zeno truncations differ in the
    last impacts, test_fmu_events_total).  Without the floor the rescue finds the last impacts
    of some of these sequences."""
    rescued_total = 0
    for r, sigma, u0 in RIGID:
        k, events, rescued, worst = _run(builds[build], "rigid", UNDERDAMPED, sigma, r, 10.0, 0.0,
                                         u0, 0.0, 3)
        assert worst <= math.log(10) / math.log(1 / r), (r, sigma, u0, worst)
        assert k >= 5 and events >= k
        rescued_total += rescued
    if build == "no-floor":
        assert rescued_total > 0
