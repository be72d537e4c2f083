"""The saddle-node (fold) curve of the single-impact period-M orbits of the rigid-wall oscillator
near grazing, in closed form, written as a chart.json for `impact-harness atlas --curves`.

An orbit with one impact per M periods, at time t_i with velocity v, satisfies
(I - P(M)) w(t_i) = -v q with w(t) = (1 - A cos 2 pi t, 2 pi A sin 2 pi t), A = 1 + sigma,
q = (r P12(M), 1 + r P22(M)) (P the free flight's propagator, docs/theory.md section 2). Eliminating
v: K0 + A (-K0 cos 2 pi t + K2 sin 2 pi t) = 0 with K0 = q2 B11 - q1 B21, K2 = 2 pi (q2 B12 - q1 B22)
= -2 pi (1 + r) P12(M), B = I - P(M). Its two roots t_i merge (a saddle-node) at
A = |K0| / sqrt(K0^2 + K2^2) <= 1: sigma_SN <= 0, with equality exactly where P12(M) = 0, i.e.
omega_d M = n pi (omega_d = sqrt(Omega^2 - nu^2/4)); near there sigma_SN ~ -K2^2 / (2 K0^2), quadratic
in Omega - Omega*. The branch is kept where the impact velocity v > 0 (an admissible orbit).

    python docs/examples/resonant-grazing/fold_curve.py --nu 0.2 --r 0.8 --range 2.9:3.4 --out fold.json
"""
from __future__ import annotations

import argparse
import json
import math

import numpy as np

from mapcheck.resonant_grazing import fold


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--nu", type=float, default=0.2)
    ap.add_argument("--r", type=float, default=0.8)
    ap.add_argument("--M", type=int, default=1)
    ap.add_argument("--range", default="2.9:3.4")
    ap.add_argument("--out", default="fold.json")
    a = ap.parse_args()
    lo, hi = (float(x) for x in a.range.split(":"))
    om, sg = [], []
    for x in np.linspace(lo, hi, 801):
        s, _, v = fold(a.nu, a.r, float(x), a.M)
        if v > 0:  # admissible: the mass moves into the wall at the impact
            om.append(float(x))
            sg.append(s)
    star = math.sqrt((math.pi / a.M) ** 2 + a.nu ** 2 / 4)
    data = {"problem": {"param2": "Omega"}, "resonance_Omega": star,
            "windows": [{"M": a.M, "closing": {"closes": None},
                         "curves": {"lower": {"kind": "fold", "p2": om, "sigma": sg}}}]}
    with open(a.out, "w") as fh:
        json.dump(data, fh)
    print(f"fold of the single-impact period-{a.M} orbit: {len(om)} points, from grazing at Omega* = {star:.6f}")


if __name__ == "__main__":
    main()
