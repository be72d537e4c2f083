"""``reproduce direct --quick``: the map's one-step prediction against the real FMU near grazing.

The expansion behind (31)/(37)-(39), (48) neglects terms of relative order eps^(1/2), so the
one-step error in natural coordinates is O(eps^(3/2)) (docs/theory.md section 4).  The fitted
order must be >= 1.4 on every ray, for the compliant (48) and the rigid (39) wall.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from harness.reproduce import run_target


@pytest.fixture(scope="module")
def direct(tmp_path_factory):
    out = tmp_path_factory.mktemp("direct")
    run_target("direct", out, quick=True, progress=False)
    return out, json.loads((out / "direct.json").read_text())


def test_order_of_the_one_step_error(direct) -> None:
    out, res = direct
    assert (out / "direct_error.png").stat().st_size > 0
    assert set(res["orders"]) == {"compliant", "rigid"}
    for wall, rows in res["rows"].items():
        for key, row in rows.items():
            # every point is a single impact near t = n (the maps' setting)
            assert row["contacts"] == [1] * len(row["eps"]), (wall, key)
            # at least three points over a decade above the FMU's own error
            fitted = np.asarray(row["eps"])[np.asarray(row["fitted"], dtype=bool)]
            assert fitted.size >= 3 and fitted.max() / fitted.min() >= 10, (wall, key)
            assert row["order"] >= 1.4, (wall, key, row["order"])
    assert res["min_order"] >= 1.4
