"""The basin quantifiers against answers known from their definitions: the uncertainty exponent
of smooth boundaries (1) and of a Cantor boundary (1 - log 2 / log 3), the basin entropy of
independent random labels (an exact binomial / multinomial sum), the boundary basin entropy of a
straight boundary through boxes (the mean of H(k/n)), and the basin fraction of a disc."""
from __future__ import annotations

import math
from itertools import product

import numpy as np
import pytest

from harness.analysis.basins.measures import basin_entropy, basin_fractions, uncertainty_exponent


def _grid(n: int) -> tuple[np.ndarray, np.ndarray]:
    return np.meshgrid(np.linspace(-1.0, 1.0, n), np.linspace(-1.0, 1.0, n), indexing="ij")


@pytest.mark.parametrize("shape", ["line", "tilted", "disc", "ellipse"])
@pytest.mark.parametrize("n", [256, 400])
def test_a_smooth_boundary_has_exponent_one(shape: str, n: int) -> None:
    x, y = _grid(n)
    lab = {"line": x > 0.123, "tilted": x + 0.37 * y > 0.05, "disc": x ** 2 + y ** 2 < 0.5,
           "ellipse": (x / 0.8) ** 2 + (y / 0.5) ** 2 < 1.0}[shape].astype(int)
    fit = uncertainty_exponent(lab)
    assert fit.alpha == pytest.approx(1.0, abs=0.05)
    assert fit.alpha_err < 0.05 and fit.fit[0] == 1 and fit.fit[1] >= 16


def _cantor_labels(levels: int, width: int) -> np.ndarray:
    """Labels on [0, 1) at resolution 3^-levels: the parity of the level of the middle third a
    point was removed at (1, 2), 0 on the Cantor set; the boundary is the middle-thirds Cantor
    set, of box-counting dimension log 2 / log 3."""
    n = 3 ** levels
    i = np.arange(n)
    lab = np.zeros(n, dtype=int)
    done = np.zeros(n, dtype=bool)
    for m in range(levels):
        hit = ((i // 3 ** (levels - 1 - m)) % 3 == 1) & ~done
        lab[hit] = m % 2 + 1
        done |= hit
    return np.repeat(lab[:, None], width, axis=1)


@pytest.mark.parametrize("levels,max_step", [(8, 64), (9, 64), (9, 128)])
def test_a_cantor_boundary_has_the_exponent_of_its_dimension(levels: int, max_step: int) -> None:
    # alpha = D - d: a Cantor set times a line in the plane, d = 1 + log 2 / log 3
    fit = uncertainty_exponent(_cantor_labels(levels, 2 * max_step + 20), max_step)
    assert fit.alpha == pytest.approx(1.0 - math.log(2) / math.log(3), abs=0.02)
    assert abs(fit.alpha - (1.0 - math.log(2) / math.log(3))) < 4 * fit.alpha_err + 0.01


def _entropy(p: list[float]) -> float:
    return -sum(x * math.log(x) for x in p if x > 0)


@pytest.mark.parametrize("classes", [2, 3])
@pytest.mark.parametrize("box", [3, 5])
def test_entropy_of_independent_random_labels_is_the_multinomial_mean(classes: int, box: int) -> None:
    cells = box * box
    exact = 0.0  # E[S] over the multinomial counts of a box of `cells` independent cells
    for counts in product(range(cells + 1), repeat=classes - 1):
        last = cells - sum(counts)
        if last < 0:
            continue
        ks = (*counts, last)
        prob = math.factorial(cells) / math.prod(math.factorial(k) for k in ks) / classes ** cells
        exact += prob * _entropy([k / cells for k in ks])
    lab = np.random.default_rng(classes * 10 + box).integers(0, classes, (600, 600))
    sb, sbb, n, nb = basin_entropy(lab, box)
    se = 0.5 / math.sqrt(n)  # S_i lies in [0, log 3]: its spread is below 0.5
    assert sb == pytest.approx(exact, abs=4 * se)
    if classes == 3 and box == 5:
        assert sbb > math.log(2)  # Daza et al.'s criterion holds for riddled random basins


@pytest.mark.parametrize("box", [4, 5, 8])
def test_boundary_entropy_of_a_straight_boundary_is_the_mean_of_h(box: int) -> None:
    # side by side, one block of 12 x 12 boxes per offset k: a straight boundary k cells into
    # the 7th column of boxes, so 12 boxes per block hold shares k/box and 1 - k/box
    n = box * 12
    blocks, expected = [], []
    for k in range(1, box):
        block = np.zeros((n, n), dtype=int)
        block[:, 6 * box + k:] = 1
        blocks.append(block)
        expected.append(_entropy([k / box, 1 - k / box]))
    lab = np.concatenate(blocks, axis=1)
    sb, sbb, boxes, nb = basin_entropy(lab, box)
    assert nb == (box - 1) * 12 and sbb == pytest.approx(np.mean(expected), rel=1e-12)
    assert sb == pytest.approx(sbb * nb / boxes, rel=1e-12)


@pytest.mark.parametrize("radius", [0.3, 0.5, 0.7])
def test_fraction_of_a_disc_with_its_error(radius: float) -> None:
    x, y = _grid(501)
    lab = (x ** 2 + y ** 2 < radius ** 2).astype(int)
    f, se = basin_fractions(lab)[1]
    assert abs(f - math.pi * radius ** 2 / 4.0) < 0.01 and se == pytest.approx(math.sqrt(f * (1 - f) / lab.size))
    assert sum(v[0] for v in basin_fractions(lab).values()) == pytest.approx(1.0)


def test_one_class_has_no_boundary() -> None:
    lab = np.zeros((50, 50), dtype=int)
    assert basin_entropy(lab, 5) == (0.0, 0.0, 100, 0)
    assert math.isnan(uncertainty_exponent(lab).alpha)


# -- from random pairs of starts (Grebogi et al.'s own procedure) ---------------------------------
@pytest.mark.parametrize("shape", ["line", "disc"])
def test_pairs_of_a_smooth_boundary_give_exponent_one(shape: str) -> None:
    from harness.analysis.basins.uncertainty import pairs_fit

    def classify(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        return (u + 0.37 * v > 0.05) if shape == "line" else (u ** 2 + v ** 2 < 0.5)

    fit = pairs_fit(classify, (-1.0, 1.0, -1.0, 1.0), pairs=20000, seed=3)
    assert fit.alpha == pytest.approx(1.0, abs=max(0.08, 3 * fit.alpha_err))
    assert fit.fit[0] < 0.01 and np.all(fit.fraction_err > 0)


def test_pairs_of_a_cantor_boundary_give_the_exponent_of_its_dimension() -> None:
    from harness.analysis.basins.uncertainty import pairs_fit

    # labels exact down to 3^-14 ~ 2e-7, far below the smallest eps (2^-10); each level's thirds a
    # class of its own (with two classes alternating, pairs that land in different thirds of the
    # same parity hide part of the boundary and the exponent creeps up more slowly: 0.33). Pairs at
    # exactly eps converge more slowly than the grid's eps-neighbourhood: 0.356 +- 0.006 here.
    levels = 14

    def classify(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        i = np.clip((np.mod(u, 1.0) * 3 ** levels).astype(np.int64), 0, 3 ** levels - 1)
        lab = np.zeros(i.shape, dtype=int)
        done = np.zeros(i.shape, dtype=bool)
        for m in range(levels):
            hit = ((i // 3 ** (levels - 1 - m)) % 3 == 1) & ~done
            lab[hit] = m + 1
            done |= hit
        return lab

    fit = pairs_fit(classify, (0.0, 1.0, 0.0, 1.0), pairs=20000, seed=5)
    assert fit.alpha == pytest.approx(1.0 - math.log(2) / math.log(3), abs=0.03)
