"""Window edges of the maps and of the ODE (FMU) for a parameter set that is not in the paper.

Run from the repository root: ``.venv/bin/python examples/windows.py``; the same as
``impact-harness windows --alpha 0.5 --gamma 0.05 --r 0.8 --wall compliant --Gamma 10 --M-max 2
--quick --out results/windows-example``.  The worker processes re-import this file, hence the
``if __name__ == "__main__":`` guard.
"""
import sys

from harness import compare_windows

if __name__ == "__main__":
    out = sys.argv[1] if len(sys.argv) > 1 else "results/windows-example"
    res = compare_windows(alpha=0.5, gamma=0.05, r=0.8, wall="compliant", Gamma=10.0, M_max=2, quick=True,
                          out=out, workers=2)
    for M, w in res["windows"]["ode"].items():
        kinds = res["edge_kinds"]["ode"][M]
        print(f"M = {M}: ODE {w} ({kinds[0]}/{kinds[1]}), A~ map {res['windows']['map_A_tilde'][M]}")
    print(res["verdict"])
