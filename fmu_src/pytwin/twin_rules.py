"""The twin's fixed rules: the wall models and contact modes, the thresholds of the wall law, the
valid ranges of the parameters and their checks (the C FMU's ``fmu_vars.c`` table and
``model.c``'s constants, written again for the Python twin; see ``impact_twin_model``).
"""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

WALL_NONE, WALL_COMPLIANT, WALL_RIGID = 0, 1, 2
#: Discrete state. CONTACT: inside the compliant wall. STICK: resting on the rigid wall after
#: chatter, held there while the net force pushes into it.
MODE_FREE, MODE_CONTACT, MODE_STICK = 0, 1, 2

#: Chatter on the rigid wall: once an impact leaves at most this velocity (relative to the
#: incoming one, floored at 1) and the wall force pushes inwards, the impacts would accumulate in
#: finite time; the mass is taken to stick instead (Zeno truncation).  Same value as model.c.
STICK_VELOCITY = 1e-9

#: Where an event leaves the mass on the wall, u is put a hair on the side of its new mode
#: rather than at 0 (as model.c): CVODE deactivates a root function that is exactly zero at a
#: restart and takes its reference sign only after the first step, so a contact or flight
#: shorter than that first step (chatter, grazing) would be stepped over.
ON_WALL = 1e-300

#: Rigid-wall chatter: a flight that rises less than this many ``atol`` above the wall is not
#: left to CVODE, which cannot resolve it (see ``OscillatorModel._rigid_impact``).
CHATTER_RESOLVED_ATOL = 100.0

_TWO_PI = 2.0 * math.pi
_FOUR_PI2 = 4.0 * math.pi * math.pi


def _fmt(x: object) -> str:
    """A value as C's ``%g`` prints it (messages use the C FMU's wording)."""
    try:
        return f"{float(x):g}"
    except (TypeError, ValueError):
        return repr(x)


class ModelError(ValueError):
    """A parameter value or combination the model rejects (message names the variable)."""


#: Valid ranges (lo, hi, lo excluded) of the Real parameters: the C FMU's (fmu_vars.c, VARS).
RANGES = {
    "nu": (0.0, 1e6, False),
    "Omega": (1e-6, 1e4, False),
    "sigma": (-1.0, 1e6, True),
    "r": (0.0, 1.0, False),
    "Gamma": (0.0, 1e16, False),
    "u0": (-1e6, 1e6, False),
    "v0": (-1e6, 1e6, False),
    "rtol": (1e-15, 0.1, False),
    "atol": (1e-30, 0.01, False),
}


def check_real(name: str, x: float) -> Optional[str]:
    """Check one Real parameter value before it is stored (mirrors ``model_check_real``).

    Parameters
    ----------
    name : str
        Variable name (``nu``, ``Omega``, ``sigma``, ``r``, ``Gamma``, ``u0``, ``v0``, ``rtol``,
        ``atol``).
    x : float
        Proposed value.

    Returns
    -------
    str or None
        ``None`` if the value is acceptable, otherwise why not (without the variable name).
    """
    try:
        x = float(x)
    except (TypeError, ValueError):
        return "must be a real number"
    if not math.isfinite(x):
        return "must be a finite number"
    rng = RANGES.get(name)
    if rng is None:
        return "is not a settable Real variable"
    lo, hi, lo_open = rng
    if (x <= lo if lo_open else x < lo) or not x <= hi:
        return f"must lie in {'(' if lo_open else '['}{lo:g}, {hi:g}]"
    return None


def check_wall(x: int) -> Optional[str]:
    """Check the Integer parameter ``wall`` (mirrors ``model_check_integer``).

    Parameters
    ----------
    x : int
        Proposed wall model.

    Returns
    -------
    str or None
        ``None`` if acceptable, otherwise why not.
    """
    if isinstance(x, bool) or not isinstance(x, (int, np.integer)) or not (
        WALL_NONE <= int(x) <= WALL_RIGID
    ):
        return "must lie in [0, 2]"
    return None
