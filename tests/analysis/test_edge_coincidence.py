"""Coincident edges: a period-doubled window's birth and its parent's flip are one point when
their bisection brackets overlap, and flagged when they do not; the wall-free window's graze is
sigma = 0 (the wall-free orbit (1 + sigma) cos(2 pi t) - 1 reaches u = 0 there) when its
bracket holds 0.  The rows are in the format of windows.json's ``ode_windows_all``."""
from __future__ import annotations

import pytest

from harness.analysis.windows.edge_coincidence import reconcile, warnings


def _row(M, k, lo, hi, kinds, lo_iv, hi_iv):
    return {"M": M, "impacts": k, "lo": lo, "hi": hi, "kinds": list(kinds), "intervals": [lo_iv, hi_iv],
            "resolved": True}


@pytest.mark.parametrize("flip", [-0.2211, 0.37, 1.5])
def test_overlapping_brackets_give_one_point(flip) -> None:
    h = 1e-6
    parent = _row(2, 1, None, flip, ("range", "flip"), None, [flip - h, flip + h])
    child = _row(4, 2, flip + 0.5 * h, flip + 0.2, ("period-halving", "lost"), [flip + 1.5 * h, flip - 0.5 * h],
                 [flip + 0.2, flip + 0.2 + h])
    rec = reconcile([parent, child])
    assert child["lo"] == parent["hi"] == flip and rec[0]["agree"] and not warnings(rec)
    assert "flip of period 2" in child["located_by"]["lo"]


@pytest.mark.parametrize("gap", [1e-4, 3e-3])
def test_disjoint_brackets_are_flagged_not_merged(gap) -> None:
    h, flip = 1e-6, 0.3
    parent = _row(1, 1, flip, 0.9, ("flip", "range"), [flip + h, flip - h], None)
    child = _row(2, 2, 0.1, flip - gap, ("lost", "period-halving"), [0.1, 0.1 - h], [flip - gap - h, flip - gap + h])
    rec = reconcile([parent, child])
    assert child["hi"] == flip - gap and not rec[0]["agree"]
    (w,) = warnings(rec)
    assert "2/2" in w and f"{-gap:+.2g}" in w and "--xtol" in w


@pytest.mark.parametrize("hi,expect_zero", [(1.5e-7, True), (-2e-3, False)])
def test_the_wall_free_graze_is_sigma_zero_when_its_bracket_holds_it(hi, expect_zero) -> None:
    row = _row(1, 0, None, hi, ("range", "graze"), None, [hi - 3e-7, hi + 3e-7])
    rec = reconcile([row])
    assert (row["hi"] == 0.0) == expect_zero and rec[0]["agree"] == expect_zero
    assert bool(warnings(rec)) != expect_zero
