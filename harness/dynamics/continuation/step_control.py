"""Step control shared by the continuations of orbits, event curves and graze curves.

Each continuation (:func:`~harness.dynamics.continuation.continue_orbit.continue_orbit`,
:func:`~harness.dynamics.curves.event_curves.continue_event`,
:func:`~harness.dynamics.curves.graze_curves.continue_graze`) walks a curve by steps whose size adapts:
halved when a step fails, grown (up to a largest step) when it succeeds, and the walk ends when
the step falls below the smallest one, when the point budget is spent, or for a reason of the
curve itself (a range left, a graze).  :class:`StepControl` holds that state in one place, so
that the three continuations take the same sequence of steps for the same failures.
"""
from __future__ import annotations

import math

__all__ = ["StepControl"]


class StepControl:
    """The arclength step of a continuation, its point budget and why the walk ended.

    Parameters
    ----------
    size : float
        The first step.  Its sign is kept through every change (a continuation may walk with a
        signed step; the size is compared by its absolute value).
    smallest, largest : float
        Halving below ``smallest`` ends the walk; growth stops at ``largest``.
    max_points : int
        Accepted steps at most.

    Attributes
    ----------
    steps : int
        Accepted steps so far.
    reason, note : str
        Why the walk ended (``"steps"`` and "<max_points> steps done" until told otherwise).
    """

    def __init__(self, size: float, smallest: float, largest: float, max_points: int) -> None:
        self.size = size
        self.smallest = smallest
        self.largest = largest
        self.max_points = max_points
        self.steps = 0
        self.reason = "steps"
        self.note = f"{max_points} steps done"

    @property
    def budget_left(self) -> bool:
        """True while fewer than ``max_points`` steps were accepted."""
        return self.steps < self.max_points

    def shrink(self) -> bool:
        """Halve the step after a failure; False when it fell below the smallest step."""
        self.size *= 0.5
        return abs(self.size) >= self.smallest

    def can_shrink(self, factor: float = 4.0) -> bool:
        """The step is still above ``factor`` times the smallest step (room for a retry shorter
        that is not a failure, e.g. after a tangent that turned too much)."""
        return abs(self.size) > factor * self.smallest

    def accept(self, growth: float = 1.5) -> None:
        """Count an accepted step and scale the next one by ``growth`` (at most the largest)."""
        self.count()
        self.grow(growth)

    def count(self) -> None:
        """Count an accepted step, the step size unchanged (a switch to another orbit)."""
        self.steps += 1

    def grow(self, growth: float) -> None:
        """Scale the step by ``growth``, capped at the largest step, keeping its sign."""
        self.size = math.copysign(min(abs(self.size) * growth, self.largest), self.size)

    def stop(self, reason: str, note: str) -> None:
        """Record why the walk ends."""
        self.reason, self.note = reason, note
