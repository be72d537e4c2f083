"""Physics and CVODE driver of the impact oscillator, in Python (the pythonfmu twin).

This module is the counterpart of the C FMU's ``fmu_src/model.c`` (the physics) and
``fmu_src/solver_cvode.c`` (the CVODE driver): the same specification and the same rules
(thresholds, directions, re-origin), a separate implementation on a separate SUNDIALS build, so
that the two check each other.  The differences, on purpose: how a stepped-over crossing is
located (:class:`CvodeDriver`) and the tail of rigid-wall chatter
(:meth:`OscillatorModel._rigid_impact`).  It is also the place to change the contact law
without touching C: everything that defines what happens at the wall is in
:class:`OscillatorModel` (``make_rhs``, ``make_jacobian``, ``make_indicators``,
``event_update``, ``missed_crossing``, ``release_now``).

The model is the non-dimensional driven oscillator of Molenaar, de Weger & van de Water (2001),
eqs (3), (5), (40), (53) (see ``docs/theory.md``, section 1)::

    u'' + nu u' + Omega^2 (u + 1) [+ kappa^2 u in contact] = (1 + sigma) F_g cos(2 pi t + phi)

Time inside the model is *local*: ``tau = t - origin`` with an integer ``origin``, so the
forcing phase ``cos(2 pi tau + phi)`` keeps full precision after many periods.

The integrator is SUNDIALS CVODE (Adams, dense linear solver, analytic Jacobian) through
scikit-sundae.  Wall crossings are located by CVODE's root finding on two indicators, the wall
(g0) and the velocity (g1, the grazing guard); see :class:`CvodeDriver`.
"""
from __future__ import annotations

# The parts, by concern (each importable alone): the fixed rules and checks, the physics, the
# CVODE driver.  This module gathers their public names for the twin's FMU class
# (ImpactOscillatorPy.py) and the tests.
from twin_cvode import CvodeDriver, SolverError
from twin_physics import OscillatorModel
from twin_rules import (CHATTER_RESOLVED_ATOL, MODE_CONTACT, MODE_FREE, MODE_STICK, ON_WALL,
                        STICK_VELOCITY, WALL_COMPLIANT, WALL_NONE, WALL_RIGID, ModelError,
                        check_real, check_wall)

__all__ = [
    "WALL_NONE",
    "WALL_COMPLIANT",
    "WALL_RIGID",
    "MODE_FREE",
    "MODE_CONTACT",
    "MODE_STICK",
    "STICK_VELOCITY",
    "ON_WALL",
    "CHATTER_RESOLVED_ATOL",
    "ModelError",
    "OscillatorModel",
    "SolverError",
    "CvodeDriver",
    "check_real",
    "check_wall",
]
