"""``reproduce rescaling --quick``: window positions on the FMU with a soft compliant wall
against a rigid wall, compared with the factor (1+r)^2/(1-r)^2 in rho (section 6.3)."""
from __future__ import annotations

import json

import pytest

from harness.reproduce import run_target


@pytest.fixture(scope="module")
def rescaling(tmp_path_factory):
    out = tmp_path_factory.mktemp("rescaling")
    run_target("rescaling", out, quick=True, progress=False)
    return out, json.loads((out / "rescaling.json").read_text())


def test_factor_in_rho(rescaling) -> None:
    """Edge by edge, the rigid/compliant ratio in rho~ is (1+r)^2/(1-r)^2 = 9 within 5%.

    At (nu, Omega) = (100, sqrt 2) P22 and gamma are negligible, so (39) and (48) are the same
    map up to the scale of rho; what remains is each map's own error against the ODE (0.2% of
    an edge at Figure 9), larger on the rigid wall whose edges lie at ~10x the sigma (the
    next order grows like sigma^(1/2): ~3x).  5% still separates 9 from the plain sigma ratio
    (up to +25%: the A~ nonlinearity, common to both walls, is what rho~ removes)."""
    out, res = rescaling
    assert (out / "rescaling.png").stat().st_size > 0 and (out / "report.md").stat().st_size > 0
    pred = res["summary"]["predicted"]
    assert pred == pytest.approx(9.0)
    assert len(res["factors"]) >= 4  # M = 1 lower, M = 2 both, M = 3 both
    for name, f in res["factors"].items():
        assert f["ratio_rho_tilde"] == pytest.approx(pred, rel=0.05), name
    # every window exists on both walls, rigid at larger sigma
    for M, w in res["windows"]["ode_compliant"].items():
        assert w is not None and res["windows"]["ode_rigid"][M] is not None
        assert res["windows"]["ode_rigid"][M][0] > 5 * w[0]
