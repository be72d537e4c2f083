"""Simulators: what the sampling code drives.

A simulator integrates the oscillator from a state at a start time, lets the caller
change a parameter between communication points, and reports (u, v) and the cumulative
number of wall entries.  Two implementations:

* :class:`FmuSimulator` drives a Co-Simulation FMU (one instance, reused with ``reset``).
* :class:`MappingSimulator` wraps a user-given one-period map, so that the same sweeps,
  classification and plots apply to an analytic map (e.g. from :mod:`mapcheck`).

Derivatives (optional, feature-detected): a simulator with ``derivatives_available`` true
can integrate the variational equations (:meth:`FmuSimulator.track_derivatives`) and
report d(u, v)/d(u, v)_mark and d(u, v)/d sigma accumulated since the last
:meth:`~FmuSimulator.reset_derivatives` (or ``start``): the per-``doStep`` matrices the FMU
outputs are chained, so a period taken in several steps gets the product.
"""
from __future__ import annotations

import contextlib
import math
import threading
from typing import Any, Callable, Iterator, Mapping, Protocol, runtime_checkable

import numpy as np

from ..errors import FmuError, FmuRejectedInput, HarnessInputError
from .fmi import (
    IMPACT_COUNTER,
    INITIAL_STATE,
    SENSITIVITY_OUTPUTS,
    SENSITIVITY_SWITCH,
    STATE_OUTPUTS,
    FmuModel,
    FmuSource,
    VariableInfo,
    open_source,
)
from .slaves import make_slave

Params = Mapping[str, Any]


@runtime_checkable
class Simulator(Protocol):
    """The interface the sampling, sweep and Jacobian code relies on."""

    time: float

    def start(self, params: Params, t0: float, state: tuple[float, float]) -> None:
        """(Re)start at absolute time ``t0`` from ``state`` = (u, v) with ``params``."""

    def advance(self, t: float) -> None:
        """Integrate to absolute time ``t`` (> current time)."""

    def set_parameter(self, name: str, value: Any) -> None:
        """Change one parameter now; the state is carried on."""

    def read(self) -> tuple[float, float, int]:
        """Return (u, v, wall entries since the first ``start`` of this run)."""


class _DerivativeChain:
    """The derivatives of the map accumulated over steps, shared by both simulators.

    Over steps x_{k+1} = F_k(x_k, sigma) the chain rule gives J = J_k ... J_1 and
    S <- J_k S + S_k; a subclass calls :meth:`_chain` with each step's (J_k, S_k).
    """

    derivatives_available: bool = False
    _track: bool = False

    def _refuse_derivatives(self) -> str:
        """Why this simulator cannot track derivatives (the message of the refusal)."""
        return "no derivatives available"

    def track_derivatives(self, on: bool = True) -> None:
        """Integrate the variational equations from the next ``start`` on (``on``), or not.

        Raises
        ------
        HarnessInputError
            If ``on`` and the simulator cannot report derivatives.
        """
        if on and not self.derivatives_available:
            raise HarnessInputError("derivatives", self._refuse_derivatives())
        self._track = bool(on)

    @property
    def tracking(self) -> bool:
        """True while the variational equations are integrated."""
        return self._track

    def reset_derivatives(self) -> None:
        """Start accumulating the derivatives afresh at the current time."""
        self._J = np.eye(2)
        self._S = np.zeros(2)
        self._fresh = True

    def derivatives(self) -> tuple[np.ndarray, np.ndarray]:
        """(J, S): d(u, v)/d(u, v) and d(u, v)/d sigma from the last mark to now (copies)."""
        return self._J.copy(), self._S.copy()

    def _chain(self, Jk: np.ndarray, Sk: np.ndarray) -> None:
        """Append one step's Jacobian ``Jk`` and sigma-derivative ``Sk`` to the chain (arrays of
        the caller's own, kept).  The first step after a reset is the chain (Jk I = Jk and
        Jk 0 + Sk = Sk to the bit): a period in one ``doStep`` takes no product."""
        if self._fresh:
            self._J, self._S, self._fresh = Jk, Sk, False
            return
        self._S = Jk @ self._S + Sk
        self._J = Jk @ self._J


class FmuSimulator(_DerivativeChain):
    """Drive one FMU instance; :meth:`start` resets and re-initializes it.

    Parameters
    ----------
    source : FmuSource
        Which FMU (checked by sha256 on this process).
    instance_name : str
        FMI instance name (appears in the FMU's log messages).
    max_step : float
        Longest communication step; a period is done in one ``doStep`` by default because
        the FMU handles its events inside a step (``canHandleVariableCommunicationStepSize``).
    record_events : bool
        FMI 3.0 FMUs only: run with event mode and early return, and record the time of every
        wall event in :attr:`event_times` (since the last :meth:`start`).
    """

    def __init__(self, source: FmuSource, instance_name: str = "harness", max_step: float = 1.0,
                 record_events: bool = False) -> None:
        unzipdir, model = open_source(source)
        self.model: FmuModel = model
        self.source = source
        self._slave = make_slave(model, unzipdir, instance_name, record_events)
        self._max_step = float(max_step)
        v = model.variables
        self._get_state = self._slave.getter([v[n] for n in STATE_OUTPUTS])
        self._get_impacts = self._slave.getter([v[IMPACT_COUNTER]])
        self._init_vars: tuple[VariableInfo, VariableInfo] = (v[INITIAL_STATE[0]], v[INITIAL_STATE[1]])
        self._params: dict[str, Any] = {}
        self._settable: dict[str, VariableInfo] = {}
        self._impact_offset = 0
        self.time = math.nan
        self.restarts = 0  # re-initializations to carry the state across a non-tunable change
        #: the FMU reports the derivatives of its map (its ``J_uu`` ... ``S_v`` outputs, SENSITIVITY_OUTPUTS)
        self.derivatives_available: bool = model.has_sensitivities
        self._track = False
        self._get_sens = (self._slave.getter([v[n] for n in SENSITIVITY_OUTPUTS])
                          if self.derivatives_available else None)
        self.reset_derivatives()

    def _refuse_derivatives(self) -> str:
        return (f"{self.model.path.name} does not report the derivatives of its map "
                f"(no variables {SENSITIVITY_SWITCH!r}, {', '.join(SENSITIVITY_OUTPUTS)})")

    # -- life cycle ----------------------------------------------------------------------
    def start(self, params: Params, t0: float, state: tuple[float, float]) -> None:
        self._params = dict(params)
        self._impact_offset = 0
        self.reset_derivatives()
        self._initialize(t0, state)

    def _initialize(self, t0: float, state: tuple[float, float]) -> None:
        values: dict[VariableInfo, Any] = {}
        for name, value in self._params.items():
            if name in INITIAL_STATE:
                continue  # the state argument wins
            var = self._settable.get(name)
            if var is None:  # checked once per name (a restart sets the same names again)
                var = self._settable[name] = self.model.check_settable(name)
            values[var] = value
        if self.derivatives_available:  # the harness decides (variational equations cost time)
            values[self.model.variables[SENSITIVITY_SWITCH]] = self._track
        values[self._init_vars[0]] = float(state[0])
        values[self._init_vars[1]] = float(state[1])
        try:
            self._slave.reset()
            self._slave.initialize(float(t0), values)
        except Exception as exc:
            said = self._slave.last_error()
            raise FmuRejectedInput(
                f"the FMU rejected the settings at initialization (t0 = {t0}, u0 = {state[0]}, v0 = {state[1]}): "
                + (said or str(exc))
            ) from exc
        self.time = float(t0)

    def advance(self, t: float) -> None:
        # Steps are computed from absolute times (not accumulated) so that sample times are
        # exactly n + theta however many periods a run has.
        while self.time < t:
            t_next = min(t, self.time + self._max_step)
            try:
                self._slave.do_step(self.time, t_next - self.time)
            except Exception as exc:
                said = self._slave.last_error()
                raise FmuError(f"doStep from t = {self.time} to {t_next} failed: {said or exc}") from exc
            self.time = t_next
            if self._track:
                # chain rule over the steps: x_{k+1} = F_k(x_k, sigma)
                juu, juv, jvu, jvv, su, sv = self._get_sens()
                self._chain(np.array([[juu, juv], [jvu, jvv]]), np.array([su, sv]))

    def set_parameter(self, name: str, value: Any) -> None:
        var = self.model.check_settable(name)
        self._params[name] = value
        if var.tunable:
            self._slave.set({var: value})
        else:
            # Not tunable: restart at the current time from the current state, which is
            # equivalent for a state-space model (the impact counter is carried over).
            u, v, n = self.read()
            self._impact_offset = n
            self._initialize(self.time, (u, v))
            self.restarts += 1

    def read(self) -> tuple[float, float, int]:
        u, v = self._get_state()
        (n,) = self._get_impacts()
        return float(u), float(v), int(n) + self._impact_offset

    @property
    def event_times(self) -> list[float]:
        """Times of the wall events since :meth:`start` (with ``record_events``; else empty)."""
        return list(getattr(self._slave, "event_times", []))

    @property
    def messages(self) -> list[tuple[int, str, str]]:
        """The FMU's recent log messages (status, category, text), newest last."""
        return list(self._slave.messages)

    def close(self) -> None:
        """Terminate and free the FMU instance."""
        self._slave.close()

    def __enter__(self) -> "FmuSimulator":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


OneStepMap = Callable[[float, float, float, Mapping[str, Any]], tuple[float, float, int]]


class MappingSimulator(_DerivativeChain):
    """A user-given one-period map seen as a simulator.

    Parameters
    ----------
    step : callable
        ``step(u, v, t, params) -> (u_next, v_next, impacts)``: the state one period after
        time ``t`` and the number of wall entries during that period.
    defaults : mapping
        Default parameters, merged under those passed to :meth:`start`.
    derivative : callable, optional
        ``derivative(u, v, t, params) -> (J, S)``: the map's Jacobian (2x2) at (u, v) and its
        derivative in sigma (2,; may be None); makes the mapping report derivatives as an
        FMU with sensitivity outputs does.
    """

    def __init__(self, step: OneStepMap, defaults: Params | None = None,
                 derivative: Callable[..., tuple[Any, Any]] | None = None) -> None:
        self._step = step
        self._derivative = derivative
        self.derivatives_available = derivative is not None
        self._track = False
        self.reset_derivatives()
        self._defaults = dict(defaults or {})
        self._params: dict[str, Any] = {}
        self._u = self._v = math.nan
        self._n = 0
        self.time = math.nan

    def start(self, params: Params, t0: float, state: tuple[float, float]) -> None:
        self._params = {**self._defaults, **params}
        self._u, self._v = float(state[0]), float(state[1])
        self._n = 0
        self.time = float(t0)
        self.reset_derivatives()

    def _refuse_derivatives(self) -> str:
        return "this mapping was given no derivative"

    def advance(self, t: float) -> None:
        periods = t - self.time
        k = round(periods)
        if k < 0 or abs(periods - k) > 1e-9:
            raise HarnessInputError("t", f"a mapping advances in whole periods; cannot go from {self.time} to {t}")
        for _ in range(k):
            if self._track:
                Jk, Sk = self._derivative(self._u, self._v, self.time, self._params)
                self._chain(np.array(Jk, dtype=float),
                            np.zeros(2) if Sk is None else np.array(Sk, dtype=float))
            self._u, self._v, m = self._step(self._u, self._v, self.time, self._params)
            self._n += int(m)
            self.time += 1.0

    def set_parameter(self, name: str, value: Any) -> None:
        self._params[name] = value

    def read(self) -> tuple[float, float, int]:
        return self._u, self._v, self._n


def has_derivatives(sim: Any) -> bool:
    """True when ``sim`` can report exact derivatives of its map."""
    return bool(getattr(sim, "derivatives_available", False))


@contextlib.contextmanager
def tracking_derivatives(sim: Any, on: bool = True) -> Iterator[Any]:
    """Within the block ``sim`` integrates the variational equations (``on``) or not; the
    previous setting is restored afterwards.  Takes effect at the next ``start``."""
    before = bool(getattr(sim, "tracking", False))
    if has_derivatives(sim):
        sim.track_derivatives(on)
    elif on:
        raise HarnessInputError("derivatives", "the simulator does not report derivatives")
    try:
        yield sim
    finally:
        if has_derivatives(sim):
            sim.track_derivatives(before)


# ----------------------------------------------------------------------------------------
# One simulator per (FMU, thread): workers reuse their instance across tasks.
# ----------------------------------------------------------------------------------------
_LOCAL = threading.local()


def simulator_for(source: FmuSource) -> FmuSimulator:
    """Return this thread's simulator for ``source``, creating it on first use.

    A process-pool worker or a Dask worker thread instantiates the FMU once and then only
    resets it between sweep points.  Thread-local because an FMI instance must not be used
    from two threads at once (a Dask worker may run several threads).
    """
    cache: dict[str, FmuSimulator] | None = getattr(_LOCAL, "sims", None)
    if cache is None:
        cache = _LOCAL.sims = {}
    sim = cache.get(source.sha256)
    if sim is None:
        name = f"harness-{threading.get_ident()}"
        sim = cache[source.sha256] = FmuSimulator(source, instance_name=name)
    return sim
