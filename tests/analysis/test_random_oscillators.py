"""`windows` on oscillators nobody has looked at, against brute force on the exact flow.

For each seed (:mod:`tests.support.random_oscillators`: light damping, r near 1, rigid and
compliant walls, sigma below 0), brute force (many starts iterated to their attractors, each
confirmed by Newton on the exact flow) finds the periodic attractors at a few sigma values of a
narrow range; `windows` over that range must list each of them in a row whose window holds that
sigma, with both of its edges confirmed by the exact flow (the orbit marched there from the
attractor is stable 1e-6 inside and gone 1e-6 beyond), no orbit listed twice, and no sentence of
its summary contradicting its numbers.  A few seeds in the fast tier, 30 or more in the slow one
(``IMPACT_RANDOM_SEEDS=N`` for seeds 0..N-1, TESTING.md).
"""
from __future__ import annotations

import re

import numpy as np
import pytest

from tests.support.random_oscillators import (FAST_SEEDS, brute_force, duplicate_rows, edge_confirmed,
                                              random_oscillator, row_containing, slow_seeds, windows_report)

M_MAX = 3
WIDTH = 0.3


def _range(seed: int) -> tuple[float, float]:
    """A narrow sigma range of the seed, below and above grazing alike."""
    lo = float(np.random.default_rng(50_000 + seed).uniform(-0.3, 0.8))
    return round(lo, 3), round(lo + WIDTH, 3)


def check_seed(seed: int, tmp_path) -> tuple[list[str], int]:
    """What `windows` gets wrong on the seed's oscillator, and how many attractors were checked."""
    osc = random_oscillator(seed)
    lo, hi = _range(seed)
    res = windows_report(osc, (lo, hi), tmp_path / f"w{seed}", M_max=M_MAX)
    problems = [f"{osc}: {d}" for d in duplicate_rows(res)]
    for line in res["summary"]:
        # "does not agree" with a difference of 0 contradicts itself; 0.011 does not (seed 28)
        said = re.search(r"does not agree: its largest edge difference to the ODE is (\d[\d.eE+-]*)", line)
        if said and float(said.group(1).rstrip(".")) == 0.0:
            problems.append(f"{osc}: contradicted sentence: {line}")
    flow = osc.flow()
    checked: set[tuple] = set()
    n = 0
    for s in np.linspace(lo, hi, 5)[1:-1]:
        for a in brute_force(osc, float(s), n_starts=150, M_max=M_MAX):
            n += 1
            row = row_containing(res, a.M, a.k, float(s))
            if row is None:
                problems.append(f"{osc}: the attractor {a.M}/{a.k} at sigma = {s:.4g} (share {a.share:.2f} of the "
                                f"starts) is in no row of windows over [{lo}, {hi}]")
                continue
            key = (row["M"], row["impacts"], row["lo"], row["hi"])
            if key in checked:
                continue
            checked.add(key)
            for edge, inward in ((row["lo"], 1.0), (row["hi"], -1.0)):
                if edge is not None and lo < edge < hi and row["kinds"][0 if inward > 0 else 1] != "range":
                    bad = edge_confirmed(flow, a.M, a.k, a.points[0], float(s), float(edge), inward)
                    if bad:
                        problems.append(f"{osc}: {bad}")
    return problems, n


@pytest.mark.parametrize("seed", FAST_SEEDS)
def test_windows_lists_every_attractor_brute_force_finds(seed: int, tmp_path) -> None:
    problems, n = check_seed(seed, tmp_path)
    assert problems == []
    assert n >= 3  # the fast seeds have attractors to check (a chaotic range would check nothing)


@pytest.mark.slow
@pytest.mark.parametrize("seed", slow_seeds())
def test_windows_lists_every_attractor_brute_force_finds_on_more_oscillators(seed: int, tmp_path) -> None:
    assert check_seed(seed, tmp_path)[0] == []
