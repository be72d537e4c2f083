"""Random FMI call sequences as lists of plain JSON actions.

A sequence is drawn from ``random.Random(seed)`` alone and never looks at the FMU, so the same
seed always gives the same actions: a failure is reproduced by its seed, minimised by deleting
actions, and stored as JSON (tests/fuzz_corpus/). What an action means at run time (``"t": "now"``
is the FMU's current time) is resolved by the executor.

Most sequences start with a valid life cycle (set-up, parameters, initialisation) so that the
random part reaches the running states; the random part then mixes valid calls with calls in the
wrong state, values at the edges of the doubles (0, denormals, 1e300, inf, NaN, negative), steps
from 5e-324 to 1e300, FMU states taken, restored, serialised and corrupted (bit flips, NaN written
into the body, words zeroed, truncated or extended, a Co-Simulation state set into a Model
Exchange instance and back).
"""
from __future__ import annotations

import math
import random
from typing import Any

from tests.fuzz.model import Description

INTERFACES = ("fmi2cs", "fmi2me", "fmi3cs", "fmi3cs_event", "fmi3cs_intermediate", "fmi3me")

EXTREMES = (0.0, -0.0, 1.0, -1.0, 5e-324, 2.2250738585072014e-308, 1e-300, 1e-12, 0.5, 2.0,
            1e6, 1e10, 1e14, 1e295, -1e296, 1e300, 1.7976931348623157e308, -1.7976931348623157e308,
            math.inf, -math.inf, math.nan)
TINY_STEPS = (5e-324, 1e-320, 2.2250738585072014e-308, 1e-300, 1e-200, 1e-16, 1e-12)
HUGE_STEPS = (1e14, 1e300, math.inf, math.nan, -1.0, -1e-300, 1e3)
CORRUPTIONS = ("bitflip", "nan", "inf", "zero_word", "truncate", "extend", "zeros", "random_body",
               "swap_halves")
ACTIONS_ALWAYS = ("set", "get_all", "step", "terminate", "reset", "get_state", "set_state",
                  "free_state", "roundtrip", "deser", "enter_init", "exit_init", "setup",
                  "last_time", "update", "enter_event", "enter_step_mode", "enter_cont",
                  "set_der")
ACTIONS_ME = ("integrate", "set_time", "set_x", "me_get", "completed")


def interface_is_me(interface: str) -> bool:
    return interface.endswith("me")


def version_of(interface: str) -> int:
    return 2 if interface.startswith("fmi2") else 3


class Generator:
    """Draws sequences for the variables of one FMU description (the same VRs in FMI 2 and 3)."""

    def __init__(self, desc: Description) -> None:
        self.desc = desc
        self.reals = desc.of_kind("real")
        self.ints = desc.of_kind("int")
        self.bools = desc.of_kind("bool")
        self.params = [v for v in desc.variables if v.causality in ("parameter", "input")]
        self.inputs = [v for v in self.reals if v.causality == "input"]

    # -- values ---------------------------------------------------------------------------
    def real_value(self, rng: random.Random, start: float | None) -> float:
        x = rng.random()
        s = 0.0 if start is None else start
        if x < 0.35:
            return s
        if x < 0.6:
            return s * rng.uniform(0.3, 3.0) if s else rng.uniform(-1.0, 1.0)
        if x < 0.85:
            return rng.choice(EXTREMES)
        return rng.choice((-1.0, 1.0)) * 10.0 ** rng.uniform(-12, 12)

    def int_value(self, rng: random.Random, start: float | None) -> int:
        x = rng.random()
        if x < 0.5 and start is not None:
            return int(start)
        if x < 0.8:
            return rng.randint(-1, 3)
        return rng.choice((-2**31, 2**31 - 1, -1, 0, 1, 2, 3, 100))

    def step_size(self, rng: random.Random) -> float:
        x = rng.random()
        if x < 0.55:
            return rng.uniform(0.0, 0.5)
        if x < 0.7:
            return rng.uniform(0.0, 2.5)
        if x < 0.8:
            return rng.choice(TINY_STEPS)
        if x < 0.85:
            return 0.0
        if x < 0.93:
            return rng.uniform(1e-6, 0.05)
        return rng.choice(HUGE_STEPS)

    # -- actions --------------------------------------------------------------------------
    def set_action(self, rng: random.Random, realistic: bool) -> dict[str, Any]:
        pool = self.params if realistic and self.params else list(self.desc.variables)
        kinds = sorted({v.kind for v in pool})
        kind = rng.choice(kinds)
        cand = [v for v in pool if v.kind == kind]
        chosen = rng.sample(cand, k=min(len(cand), 1 if rng.random() < 0.8 else rng.randint(1, 3)))
        vrs = [v.vr for v in chosen]
        if rng.random() < 0.03:
            vrs[0] = rng.choice((999, 2**32 - 1, len(self.desc.variables) + 40))
        if kind == "real":
            vals: list[Any] = [self.real_value(rng, v.start) if not realistic or rng.random() < 0.3
                               else (v.start or 0.0) * rng.uniform(0.7, 1.4) for v in chosen]
        elif kind == "int":
            vals = [self.int_value(rng, v.start) for v in chosen]
        else:
            vals = [rng.random() < 0.5 for _ in chosen]
        return {"op": "set", "kind": kind, "vrs": vrs, "values": vals}

    def regime(self, rng: random.Random) -> list[dict[str, Any]]:
        """Sets of a physically meaningful operating point (damping regime, wall model, solver,
        sensitivities), so that valid runs reach every event and solver path, not only the
        default one. Names missing from the description are skipped."""
        by_name = {v.name: v for v in self.desc.variables}
        nu, omega = rng.choice(((0.196, 7.368), (100.0, 2 ** 0.5), (4.605170185988091, 0.3059),
                                (1.0, 3.0), (0.0, 5.0), (2.0, 1.0)))
        values = {"nu": nu, "Omega": omega, "sigma": rng.choice((-0.5, 0.0, 0.2, 1.0, 10.0)),
                  "r": rng.choice((0.0, 0.5, 0.9, 1.0)), "Gamma": rng.choice((10.0, 1e3, 1e6)),
                  "wall": rng.randrange(3), "solver": rng.randrange(2),
                  "sensitivities": rng.random() < 0.5, "u0": rng.uniform(-2.0, 0.0),
                  "v0": rng.uniform(-3.0, 3.0)}
        acts = []
        for name, x in values.items():
            v = by_name.get(name)
            if v is not None and rng.random() < 0.8:
                val: Any = float(x) if v.kind == "real" else (bool(x) if v.kind == "bool" else int(x))
                acts.append({"op": "set", "kind": v.kind, "vrs": [v.vr], "values": [val]})
        return acts

    def prefix(self, rng: random.Random, interface: str) -> list[dict[str, Any]]:
        start = rng.choice((0.0, 0.0, 0.0, rng.uniform(-10, 10), 1e6, rng.choice(EXTREMES)))
        tol = rng.choice((None, None, 1e-8, 1e-4, 1e-12, rng.choice(EXTREMES)))
        acts: list[dict[str, Any]] = [{"op": "setup", "start": start, "tol": tol},
                                      {"op": "enter_init", "start": start, "tol": tol}]
        if rng.random() < 0.5:
            acts += self.regime(rng)
        for _ in range(rng.randint(0, 4)):
            acts.append(self.set_action(rng, realistic=rng.random() < 0.7))
        acts.append({"op": "exit_init"})
        if interface_is_me(interface):
            acts += [{"op": "update"}, {"op": "enter_cont"}]
        elif interface == "fmi3cs_event":
            acts += [{"op": "update"}, {"op": "enter_step_mode"}]
        return acts

    def action(self, rng: random.Random, interface: str) -> dict[str, Any]:
        me = interface_is_me(interface)
        ops = list(ACTIONS_ALWAYS) + (list(ACTIONS_ME) * 2 if me else [])
        weights = {"step": 10, "get_all": 3, "set": 6, "integrate": 8, "get_state": 3,
                   "set_state": 3, "roundtrip": 2, "deser": 4, "set_der": 2}
        op = rng.choices(ops, weights=[weights.get(o, 1) for o in ops])[0]
        slot = rng.randrange(3)
        if op == "set":
            return self.set_action(rng, realistic=rng.random() < 0.5)
        if op == "step":
            t: Any = "now"
            x = rng.random()
            if x < 0.05:
                t = rng.choice(EXTREMES)
            elif x < 0.1:
                t = "now+eps"
            return {"op": "step", "t": t, "h": self.step_size(rng)}
        if op in ("get_state", "set_state", "free_state", "roundtrip"):
            return {"op": op, "slot": slot}
        if op == "deser":
            src = "foreign" if rng.random() < 0.25 else f"slot{rng.randrange(3)}"
            corrupt = rng.choice(CORRUPTIONS) if rng.random() < 0.75 else "none"
            return {"op": "deser", "slot": slot, "src": src, "corrupt": corrupt,
                    "pos": rng.random(), "bit": rng.randrange(8), "set": rng.random() < 0.8}
        if op in ("setup", "enter_init"):
            start = rng.choice((0.0, rng.uniform(-5, 5), rng.choice(EXTREMES)))
            return {"op": op, "start": start, "tol": rng.choice((None, 1e-6, rng.choice(EXTREMES)))}
        if op == "set_der":
            v = rng.choice(self.inputs if self.inputs and rng.random() < 0.8 else self.reals)
            return {"op": "set_der", "vrs": [v.vr], "order": rng.choice((1, 1, 2, 0, -1, 99)),
                    "values": [self.real_value(rng, 0.0)]}
        if op == "integrate":
            return {"op": "integrate", "h": rng.choice((1e-3, 5e-3, 1e-2, 2e-2)),
                    "n": rng.randint(1, 200)}
        if op == "set_time":
            t = ("now+dt", rng.uniform(0, 0.1)) if rng.random() < 0.8 else rng.choice(EXTREMES)
            return {"op": "set_time", "t": t}
        if op == "set_x":
            if rng.random() < 0.6:
                x0 = [rng.uniform(-2.5, 0.2), rng.uniform(-10, 10)]
            else:
                x0 = [self.real_value(rng, -1.0), self.real_value(rng, 0.0)]
            n = self.desc.n_states if rng.random() < 0.95 else rng.choice((0, 1, 3))
            return {"op": "set_x", "x": (x0 + [0.0] * 4)[:n]}
        if op == "me_get":
            return {"op": "me_get", "what": rng.choice(("der", "ind", "x", "nominal")),
                    "n_delta": 0 if rng.random() < 0.95 else rng.choice((-1, 1, 5))}
        return {"op": op}

    def sequence(self, seed: int) -> dict[str, Any]:
        """The sequence of `seed`.

        Parameters
        ----------
        seed : int
            Seed of ``random.Random``; the same seed always gives the same sequence.

        Returns
        -------
        dict
            {"seed", "interface", "actions"}, plain JSON.
        """
        rng = random.Random(seed)
        version = self.desc.version
        interface = rng.choice([i for i in INTERFACES if version_of(i) == version])
        actions: list[dict[str, Any]] = []
        if rng.random() < 0.02:
            actions.append({"op": "instantiate_bad_token"})
        if rng.random() < 0.25:
            actions.append({"op": "foreign", "h": rng.choice((0.0, 0.3, 1.7))})
        if rng.random() < 0.85:
            actions += self.prefix(rng, interface)
        for _ in range(rng.randint(3, 60)):
            actions.append(self.action(rng, interface))
        return {"seed": seed, "interface": interface, "actions": actions}
