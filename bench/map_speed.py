"""Benchmark: map iterations per second on one core (the goal: >= 1e7/s).

Run:  python bench/map_speed.py [N_ORBITS] [N_ITER]

Iterates the compliant-wall map (37)/(38) with (48) at figure 9's parameters,
(alpha, gamma) = (0.99, 0.01), r = 0.9, over N_ORBITS values of sigma at once
(a fresh-start bifurcation diagram), and prints the rate.  Also times the plain
(allocating) vectorized call and the 1D map (54)/(55) for comparison.
"""
from __future__ import annotations

import os
import sys
import time

os.environ.setdefault("OMP_NUM_THREADS", "1")  # one core
sys.path.insert(0, os.path.join(os.path.dirname(__file__), ".."))

import numpy as np  # noqa: E402

from mapcheck import coefficients, damped_1d_map  # noqa: E402
from mapcheck.bifurcation import PiecewiseMap, orbit_diagram  # noqa: E402
from mapcheck.linear import invert_alpha_gamma  # noqa: E402
from mapcheck.windows import MapParams  # noqa: E402


def rate(fn, n_orbits: int, n_iter: int) -> float:
    t = time.perf_counter()
    fn()
    return n_orbits * n_iter / (time.perf_counter() - t)


def main() -> None:
    n_orbits = int(sys.argv[1]) if len(sys.argv) > 1 else 200_000
    n_iter = int(sys.argv[2]) if len(sys.argv) > 2 else 200
    inv = invert_alpha_gamma(0.99, 0.01)
    c = coefficients(inv.nu, inv.Omega, 0.9, "compliant")
    f = PiecewiseMap(MapParams.from_coefficients(c))
    rho = c.rho(np.linspace(0.0, 1.0, n_orbits))
    x = np.zeros(n_orbits)
    y = np.zeros(n_orbits)

    r_inplace = rate(lambda: f.iterate_inplace(x, y, rho, n_iter), n_orbits, n_iter)

    def plain():
        xx, yy = np.zeros(n_orbits), np.zeros(n_orbits)
        for _ in range(n_iter):
            xx, yy = f(xx, yy, rho)

    r_plain = rate(plain, n_orbits, n_iter)

    def one_d():
        xx = np.zeros(n_orbits)
        for _ in range(n_iter):
            xx = damped_1d_map(xx, rho)

    r_1d = rate(one_d, n_orbits, n_iter)
    n_grid = 2000
    r_diag = rate(lambda: orbit_diagram(f, c.rho(np.linspace(0, 1, n_grid)), np.zeros(50), 0.0,
                                        n_transient=n_iter, n_keep=32), n_grid * 50, n_iter + 32)
    print(f"orbits={n_orbits} iterations={n_iter}")
    print(f"2D map (37)/(38), in-place kernel      : {r_inplace:.3g} iterations/s")
    print(f"2D map (37)/(38), plain vectorized call: {r_plain:.3g} iterations/s")
    print(f"1D map (54)/(55), plain vectorized call: {r_1d:.3g} iterations/s")
    print(f"orbit_diagram fresh (2000 rho x 50 starts): {r_diag:.3g} iterations/s")


if __name__ == "__main__":
    main()
